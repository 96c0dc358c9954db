//! Materials: what a voxel id means (albedo, per-voxel variation, emission colour, emission strength).

use bevy::math::IVec3;
use serde::{Deserialize, Serialize};

/// One material of the world palette. Colours are linear RGB.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Material {
    pub name: String,
    /// Diffuse reflectance per channel, in `[0, 1]`.
    pub albedo: [f32; 3],
    /// Emission colour per channel, in `[0, 1]`; radiance is `emission * strength`.
    #[serde(default)]
    pub emission: [f32; 3],
    /// Radiance scale; the material is an emitter when it is above zero.
    #[serde(default)]
    pub strength: f32,
    /// Per-voxel detail: each world voxel's albedo is scaled by `1 + variation * (2u - 1)`, `u` a hash of its
    /// position in `[0, 1)` (`albedo_at`; `albedo_at` in `shaders/lib/world.wgsl` is the same), so a field of
    /// grass is not one flat colour. In `[0, 1]`; 0 (the default) is a flat colour. Moving objects stay flat.
    #[serde(default, skip_serializing_if = "is_zero")]
    pub variation: f32,
}

fn is_zero(v: &f32) -> bool {
    *v == 0.0
}

/// The hash of a voxel position behind per-voxel variation: the same bits on the CPU and in WGSL
/// (`voxel_hash` in `shaders/lib/world.wgsl`).
pub fn voxel_hash(voxel: IVec3) -> u32 {
    let pcg = super::terrain::hash_u32;
    pcg(voxel.x as u32 ^ pcg(voxel.y as u32 ^ pcg(voxel.z as u32)))
}

impl Material {
    pub fn solid(name: &str, albedo: [f32; 3]) -> Self {
        Material { name: name.to_string(), albedo, emission: [0.0; 3], strength: 0.0, variation: 0.0 }
    }

    pub fn emissive(name: &str, albedo: [f32; 3], emission: [f32; 3], strength: f32) -> Self {
        Material { name: name.to_string(), albedo, emission, strength, variation: 0.0 }
    }

    /// The same material with per-voxel variation `variation`.
    pub fn varied(self, variation: f32) -> Self {
        Material { variation, ..self }
    }

    /// The albedo of this material's world voxel at `voxel`, with its per-voxel variation.
    pub fn albedo_at(&self, voxel: IVec3) -> [f32; 3] {
        if self.variation == 0.0 {
            return self.albedo;
        }
        let u = (voxel_hash(voxel) >> 8) as f32 / 16_777_216.0;
        let scale = 1.0 + self.variation * (2.0 * u - 1.0);
        self.albedo.map(|c| (c * scale).min(1.0))
    }

    pub fn is_emissive(&self) -> bool {
        self.strength > 0.0 && self.emission.iter().any(|&c| c > 0.0)
    }

    /// Emitted radiance per channel.
    pub fn radiance(&self) -> [f32; 3] {
        self.emission.map(|c| c * self.strength)
    }

    /// Why this material is unusable, if it is (non-finite or out-of-range values).
    pub fn problem(&self) -> Option<String> {
        let in_unit = |c: &f32| c.is_finite() && (0.0..=1.0).contains(c);
        if !self.albedo.iter().all(in_unit) {
            return Some(format!("material '{}': albedo {:?} must be within [0, 1]", self.name, self.albedo));
        }
        if !self.emission.iter().all(in_unit) {
            return Some(format!("material '{}': emission {:?} must be within [0, 1]", self.name, self.emission));
        }
        if !self.variation.is_finite() || !(0.0..=1.0).contains(&self.variation) {
            return Some(format!("material '{}': variation {} must be within [0, 1]", self.name, self.variation));
        }
        if !self.strength.is_finite() || !(0.0..=1.0e6).contains(&self.strength) {
            return Some(format!("material '{}': strength {} must be within [0, 1e6]", self.name, self.strength));
        }
        None
    }
}

/// The materials of a world. Voxel id `k > 0` is `materials[k - 1]`; id 0 is air and has no entry.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct Palette {
    pub materials: Vec<Material>,
}

/// The most materials a palette can hold (ids are `u16`, 0 is air).
pub const MAX_MATERIALS: usize = u16::MAX as usize;

impl Palette {
    pub fn new(materials: Vec<Material>) -> Self {
        Palette { materials }
    }

    /// The material of voxel id `id`, or `None` for air and unknown ids.
    pub fn get(&self, id: u16) -> Option<&Material> {
        if id == 0 { None } else { self.materials.get(id as usize - 1) }
    }

    /// The id of the material called `name`.
    pub fn id_of(&self, name: &str) -> Option<u16> {
        self.materials.iter().position(|m| m.name == name).map(|i| (i + 1) as u16)
    }

    /// Number of valid ids including air.
    pub fn id_count(&self) -> usize {
        self.materials.len() + 1
    }

    pub fn is_emissive(&self, id: u16) -> bool {
        self.get(id).is_some_and(Material::is_emissive)
    }

    /// Adds a material and returns its id.
    pub fn push(&mut self, material: Material) -> u16 {
        self.materials.push(material);
        self.materials.len() as u16
    }

    /// A small palette for generated worlds: terrain, building blocks and lights of several colours.
    pub fn default_blocks() -> Self {
        Palette::new(vec![
            Material::solid("stone", [0.45, 0.45, 0.47]).varied(0.18),
            Material::solid("dirt", [0.42, 0.30, 0.20]).varied(0.2),
            Material::solid("grass", [0.30, 0.55, 0.22]).varied(0.22),
            Material::solid("sand", [0.76, 0.70, 0.50]).varied(0.1),
            Material::solid("wood", [0.55, 0.38, 0.22]).varied(0.15),
            Material::solid("leaves", [0.20, 0.45, 0.16]).varied(0.3),
            Material::solid("white", [0.80, 0.80, 0.80]),
            Material::solid("red", [0.75, 0.10, 0.10]),
            Material::solid("green", [0.12, 0.60, 0.15]),
            Material::emissive("lamp-warm", [0.9, 0.8, 0.6], [1.0, 0.75, 0.45], 8.0),
            Material::emissive("lamp-white", [0.9, 0.9, 0.9], [1.0, 1.0, 1.0], 12.0),
            Material::emissive("lamp-blue", [0.5, 0.6, 0.9], [0.35, 0.55, 1.0], 6.0),
            Material::emissive("lamp-red", [0.9, 0.4, 0.4], [1.0, 0.25, 0.2], 6.0),
            // The generator's own (appended, so the ids above keep their meaning in older saves).
            Material::solid("snow", [0.86, 0.88, 0.92]).varied(0.05),
            Material::solid("planks", [0.62, 0.46, 0.30]).varied(0.15),
            Material::solid("plaster", [0.80, 0.76, 0.68]).varied(0.06),
            Material::solid("roof", [0.48, 0.17, 0.12]).varied(0.15),
            Material::solid("cobble", [0.40, 0.39, 0.38]).varied(0.3),
            Material::emissive("crystal-cyan", [0.5, 0.9, 0.95], [0.3, 0.9, 1.0], 5.0),
            Material::emissive("crystal-violet", [0.75, 0.5, 0.95], [0.7, 0.3, 1.0], 5.0),
        ])
    }
}
