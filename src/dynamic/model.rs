//! Voxel models of moving objects: a small grid of palette materials, written in RON as layers of characters so
//! a modder can draw them by hand (`assets/models/*.ron`):
//!
//! ```ron
//! (
//!     name: "lantern",
//!     legend: {"#": "wood", "o": "lamp"},
//!     // Bottom layer first; each layer is rows along z, each row's characters along x. '.' is air.
//!     layers: [["###", "#o#", "###"], [".o.", "ooo", ".o."]],
//! )
//! ```

use crate::world::Palette;
use bevy::math::UVec3;
use serde::Deserialize;
use std::collections::BTreeMap;

/// Largest model edge in voxels: objects are traced by a per-object DDA, and are meant to be small.
pub const MAX_MODEL_EDGE: u32 = 16;

/// A model resolved against a palette: voxel ids, x fastest, then y, then z.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxelModel {
    pub name: String,
    pub size: UVec3,
    pub voxels: Vec<u16>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ModelFile {
    name: String,
    legend: BTreeMap<String, String>,
    layers: Vec<Vec<String>>,
}

impl VoxelModel {
    /// Parses a RON model, resolving its legend's material names in `palette`. One message per problem.
    pub fn from_ron(text: &str, origin: &str, palette: &Palette) -> Result<VoxelModel, String> {
        let file: ModelFile = ron::from_str(text)
            .map_err(|e| format!("{origin}:{}:{}: {}", e.span.start.line, e.span.start.col, e.code))?;
        let mut ids = BTreeMap::new();
        for (key, material) in &file.legend {
            let mut chars = key.chars();
            let (Some(c), None) = (chars.next(), chars.next()) else {
                return Err(format!("{origin}: legend key '{key}' must be one character"));
            };
            if c == '.' {
                return Err(format!("{origin}: legend key '.' is reserved for air"));
            }
            let id = palette
                .id_of(material)
                .ok_or_else(|| format!("{origin}: legend '{key}': no material '{material}' in the world's palette"))?;
            ids.insert(c, id);
        }
        let height = file.layers.len() as u32;
        let depth = file.layers.first().map_or(0, |l| l.len()) as u32;
        let width = file.layers.first().and_then(|l| l.first()).map_or(0, |r| r.chars().count()) as u32;
        let size = UVec3::new(width, height, depth);
        if size.min_element() == 0 || size.max_element() > MAX_MODEL_EDGE {
            return Err(format!(
                "{origin}: model size {width}x{height}x{depth} must be 1..={MAX_MODEL_EDGE} on each side"
            ));
        }
        let mut voxels = vec![0u16; (width * height * depth) as usize];
        for (y, layer) in file.layers.iter().enumerate() {
            if layer.len() as u32 != depth {
                return Err(format!("{origin}: layer {y} has {} rows, the first has {depth}", layer.len()));
            }
            for (z, row) in layer.iter().enumerate() {
                if row.chars().count() as u32 != width {
                    return Err(format!("{origin}: layer {y} row {z} is not {width} characters long"));
                }
                for (x, c) in row.chars().enumerate() {
                    let id = match c {
                        '.' => 0,
                        c => *ids
                            .get(&c)
                            .ok_or_else(|| format!("{origin}: layer {y} row {z}: '{c}' is not in the legend"))?,
                    };
                    voxels[x + width as usize * (y + height as usize * z)] = id;
                }
            }
        }
        if voxels.iter().all(|&v| v == 0) {
            return Err(format!("{origin}: the model has no solid voxel"));
        }
        Ok(VoxelModel { name: file.name, size, voxels })
    }

    /// Voxel id at a local coordinate (air outside).
    pub fn get(&self, x: u32, y: u32, z: u32) -> u16 {
        if x >= self.size.x || y >= self.size.y || z >= self.size.z {
            return 0;
        }
        self.voxels[(x + self.size.x * (y + self.size.y * z)) as usize]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::palette::Material;

    fn palette() -> Palette {
        Palette::new(vec![
            Material::solid("wood", [0.5, 0.3, 0.1]),
            Material::emissive("lamp", [0.9; 3], [1.0; 3], 5.0),
        ])
    }

    #[test]
    fn a_drawn_model_resolves_its_legend_against_the_palette() {
        let text =
            "(name: \"l\", legend: {\"w\": \"wood\", \"o\": \"lamp\"}, layers: [[\"ww\", \"w.\"], [\"o.\", \"..\"]])";
        let m = VoxelModel::from_ron(text, "l.ron", &palette()).unwrap();
        assert_eq!(m.size, UVec3::new(2, 2, 2));
        let (wood, lamp) = (palette().id_of("wood").unwrap(), palette().id_of("lamp").unwrap());
        assert_eq!([m.get(0, 0, 0), m.get(1, 0, 0), m.get(0, 0, 1), m.get(1, 0, 1)], [wood, wood, wood, 0]);
        assert_eq!([m.get(0, 1, 0), m.get(1, 1, 1), m.get(5, 0, 0)], [lamp, 0, 0]);
    }

    #[test]
    fn bad_models_get_one_clear_message() {
        let cases = [
            ("(name: \"x\", legend: {\"w\": \"gold\"}, layers: [[\"w\"]])", "no material 'gold'"),
            ("(name: \"x\", legend: {\"w\": \"wood\"}, layers: [[\"w\", \"ww\"]])", "row 1 is not 1 characters"),
            ("(name: \"x\", legend: {\"w\": \"wood\"}, layers: [[\"w\"], [\"w\", \"w\"]])", "layer 1 has 2 rows"),
            ("(name: \"x\", legend: {\"w\": \"wood\"}, layers: [[\"wx\"]])", "'x' is not in the legend"),
            ("(name: \"x\", legend: {\"w\": \"wood\"}, layers: [[\"..\"]])", "no solid voxel"),
            ("(name: \"x\", legend: {\"ab\": \"wood\"}, layers: [[\"a\"]])", "must be one character"),
            ("(name: \"x\", legend: {}, layers: [])", "must be 1..=16"),
            ("(name: \"x\", legend: {\"w\": \"wood\"}, layers: [[\"wwwwwwwwwwwwwwwww\"]])", "must be 1..=16"),
            ("(name: \"x\", legend: {\"w\": \"wood\"}, layers: [[\"w\"]], extra: 1)", "m.ron:1:"),
        ];
        for (text, expected) in cases {
            let err = VoxelModel::from_ron(text, "m.ron", &palette()).unwrap_err();
            assert!(err.starts_with("m.ron") && err.contains(expected), "{text}: {err}");
        }
    }
}
