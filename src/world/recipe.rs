//! Scene recipes (`assets/scenes/*.ron`): a short description that expands into a world. Also the generated
//! default world of `glowbrick play`.
//!
//! ```ron
//! (
//!     size: (32, 16, 32),
//!     seed: 7,
//!     materials: [(name: "white", albedo: (0.8, 0.8, 0.8))],
//!     ops: [Box(min: (0, 0, 0), max: (32, 1, 32), material: "white")],
//!     views: [(name: "inside", origin: (16, 8, 2), direction: (0, 0, 1), fov_deg: 60)],
//! )
//! ```
//! Boxes are `[min, max)` in voxels. Material names refer to `materials`; `"air"` clears.

use super::font::glyph;
use super::format::{LoadError, check_world_header, parse_ron, read_limited};
use super::grid::{AIR, Voxel};
use super::palette::{Material, Palette};
use super::terrain::{TerrainParams, fill_terrain, hash_u32, surface_height};
use super::{CameraView, VoxelWorld};
use bevy::math::{IVec3, UVec3};
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// One step of a recipe, applied in order.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SceneOp {
    /// Fills `[min, max)` with a material.
    Box { min: (i32, i32, i32), max: (i32, i32, i32), material: String },
    /// A noise height field over the whole world.
    Terrain { params: TerrainParams, rock: String, soil: String, surface: String },
    /// `count` boxes of `size` at seeded random columns, standing on the surface (lamps, pillars, trees).
    Scatter { material: String, count: u32, size: (i32, i32, i32) },
    /// `count` boxes with seeded random sizes in `[size_min, size_max]`, placed inside `[min, max)` (floating
    /// blocks).
    RandomBoxes {
        material: String,
        count: u32,
        min: (i32, i32, i32),
        max: (i32, i32, i32),
        size_min: (i32, i32, i32),
        size_max: (i32, i32, i32),
    },
    /// Fills the voxels of `[min, max)` whose x + y + z is even with a material: a checkerboard of one-voxel
    /// lamps, each lit on all sides, the many-light stress case of issue 15 (`lamp-checkerboard`).
    Checker { min: (i32, i32, i32), max: (i32, i32, i32), material: String },
    /// Replaces a seeded `fraction` of the air-exposed voxels of material `on` with materials drawn from
    /// `materials` (lit windows on blocks).
    Speckle { on: String, materials: Vec<String>, fraction: f32 },
    /// Writes `text` in the 5 x 7 font: glyph pixels become `scale`^2 x `depth` voxels; `origin` is the bottom
    /// left of the first glyph, `right` and `up` the unit axes the text runs along, `depth_dir` the axis it
    /// extends into (into a wall or floor to set it flush).
    Text {
        text: String,
        material: String,
        origin: (i32, i32, i32),
        right: (i32, i32, i32),
        up: (i32, i32, i32),
        depth_dir: (i32, i32, i32),
        scale: i32,
        depth: i32,
    },
}

/// A scene recipe as written in `assets/scenes/NAME.ron`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneRecipe {
    pub size: (u32, u32, u32),
    #[serde(default)]
    pub seed: u32,
    pub materials: Vec<Material>,
    pub ops: Vec<SceneOp>,
    #[serde(default)]
    pub views: Vec<CameraView>,
}

/// Most ops a recipe may hold, and most scattered boxes per op (hostile recipes must stay cheap).
const MAX_OPS: usize = 100_000;
const MAX_SCATTER: u32 = 1_000_000;

impl SceneRecipe {
    /// Validates the recipe and expands it into a world. `location` names the source in messages.
    pub fn build(&self, location: &str) -> Result<VoxelWorld, LoadError> {
        let fail = |message: String| LoadError { location: location.to_string(), message };
        check_world_header(self.size, &self.materials, "materials", &self.views).map_err(&fail)?;
        if self.ops.len() > MAX_OPS {
            return Err(fail(format!("{} ops, at most {MAX_OPS} allowed", self.ops.len())));
        }
        let (sx, sy, sz) = self.size;
        let palette = Palette::new(self.materials.clone());
        let mut world = VoxelWorld::new(UVec3::new(sx, sy, sz), palette);
        world.views = self.views.clone();
        for (i, op) in self.ops.iter().enumerate() {
            apply_op(&mut world, self.seed, i as u32, op).map_err(|m| fail(format!("ops[{i}]: {m}")))?;
        }
        // Recipe building is not an edit: nothing is dirty until the world is uploaded as a whole.
        world.grid.take_dirty();
        Ok(world)
    }
}

fn material_id(palette: &Palette, name: &str) -> Result<Voxel, String> {
    if name == "air" {
        return Ok(AIR);
    }
    palette.id_of(name).ok_or_else(|| format!("unknown material '{name}'"))
}

fn apply_op(world: &mut VoxelWorld, seed: u32, op_index: u32, op: &SceneOp) -> Result<(), String> {
    match op {
        SceneOp::Box { min, max, material } => {
            let id = material_id(&world.palette, material)?;
            let (lo, hi) = (IVec3::from(*min), IVec3::from(*max));
            world.grid.fill_box(lo, hi, id).map(|_| ()).map_err(|e| format!("box {lo}..{hi}: {e}"))
        }
        SceneOp::Checker { min, max, material } => apply_checker(world, min, max, material),
        SceneOp::Terrain { params, rock, soil, surface } => apply_terrain(world, seed, params, rock, soil, surface),
        SceneOp::Scatter { material, count, size } => apply_scatter(world, seed, op_index, material, count, size),
        SceneOp::RandomBoxes { material, count, min, max, size_min, size_max } => {
            apply_random_boxes(world, seed, op_index, material, count, min, max, size_min, size_max)
        }
        SceneOp::Speckle { on, materials, fraction } => apply_speckle(world, seed, op_index, on, materials, fraction),
        SceneOp::Text { text, material, origin, right, up, depth_dir, scale, depth } => {
            apply_text(world, text, material, origin, right, up, depth_dir, scale, depth)
        }
    }
}

/// A checkerboard of one-voxel cells in a box.
fn apply_checker(
    world: &mut VoxelWorld,
    min: &(i32, i32, i32),
    max: &(i32, i32, i32),
    material: &str,
) -> Result<(), String> {
    let id = material_id(&world.palette, material)?;
    let (lo, hi) = (IVec3::from(*min), IVec3::from(*max));
    if lo.cmpge(hi).any() || !world.grid.contains(lo) || !world.grid.contains(hi - IVec3::ONE) {
        return Err(format!("checker {lo}..{hi} must be a non-empty box inside the world"));
    }
    for z in lo.z..hi.z {
        for y in lo.y..hi.y {
            // The first x of this row whose x + y + z is even.
            let first = lo.x + (lo.x + y + z).rem_euclid(2);
            for x in (first..hi.x).step_by(2) {
                world.grid.set(IVec3::new(x, y, z), id).map_err(|e| e.to_string())?;
            }
        }
    }
    Ok(())
}

/// Noise terrain over the whole world.
fn apply_terrain(
    world: &mut VoxelWorld,
    seed: u32,
    params: &TerrainParams,
    rock: &str,
    soil: &str,
    surface: &str,
) -> Result<(), String> {
    let ids =
        (material_id(&world.palette, rock)?, material_id(&world.palette, soil)?, material_id(&world.palette, surface)?);
    if !(params.frequency.is_finite() && params.amplitude.is_finite() && params.base_height.is_finite()) {
        return Err("terrain parameters must be finite".into());
    }
    // Found by the fuzzer (recipe input 520195 of seed 2): a frequency of 7e36 put the noise's lattice
    // coordinates beyond an isize and panicked inside the `noise` crate. Above one cycle per voxel the
    // terrain is noise anyway.
    if !(0.0..=1.0).contains(&params.frequency.abs()) {
        return Err(format!("terrain frequency {} must be within -1..=1 cycles per voxel", params.frequency));
    }
    fill_terrain(world, seed, params, ids.0, ids.1, ids.2);
    Ok(())
}

/// Boxes of one size dropped on the surface at hashed places.
fn apply_scatter(
    world: &mut VoxelWorld,
    seed: u32,
    op_index: u32,
    material: &str,
    count: &u32,
    size: &(i32, i32, i32),
) -> Result<(), String> {
    let id = material_id(&world.palette, material)?;
    if *count > MAX_SCATTER {
        return Err(format!("scatter count {count} exceeds {MAX_SCATTER}"));
    }
    let extent = IVec3::from(*size);
    let world_size = world.grid.size().as_ivec3();
    if extent.cmplt(IVec3::ONE).any() || extent.cmpgt(world_size).any() {
        return Err(format!("scatter size {extent} must be at least 1 and fit in the world"));
    }
    for n in 0..*count {
        let h = hash_u32(seed ^ hash_u32(op_index.wrapping_mul(0x9E37_79B9) ^ n));
        let x = (h % (world_size.x - extent.x + 1) as u32) as i32;
        let z = (hash_u32(h) % (world_size.z - extent.z + 1) as u32) as i32;
        let base = surface_height(world, x, z) + 1;
        if base + extent.y > world_size.y {
            continue;
        }
        let lo = IVec3::new(x, base, z);
        world.grid.fill_box(lo, lo + extent, id).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Boxes of hashed sizes at hashed places in a region.
#[allow(clippy::too_many_arguments)]
fn apply_random_boxes(
    world: &mut VoxelWorld,
    seed: u32,
    op_index: u32,
    material: &str,
    count: &u32,
    min: &(i32, i32, i32),
    max: &(i32, i32, i32),
    size_min: &(i32, i32, i32),
    size_max: &(i32, i32, i32),
) -> Result<(), String> {
    let id = material_id(&world.palette, material)?;
    if *count > MAX_SCATTER {
        return Err(format!("random box count {count} exceeds {MAX_SCATTER}"));
    }
    let (lo, hi) = (IVec3::from(*min), IVec3::from(*max));
    let (smin, smax) = (IVec3::from(*size_min), IVec3::from(*size_max));
    if smin.cmplt(IVec3::ONE).any() || smax.cmplt(smin).any() || (hi - lo).cmplt(smax).any() {
        return Err("random boxes need 1 <= size_min <= size_max <= max - min".into());
    }
    if !world.grid.contains(lo) || !world.grid.contains(hi - IVec3::ONE) {
        return Err(format!("random box region {lo}..{hi} leaves the world"));
    }
    for n in 0..*count {
        let mut h = hash_u32(seed ^ hash_u32(op_index.wrapping_mul(0x85EB_CA6B) ^ n));
        let mut draw = |lo: i32, hi_inclusive: i32| {
            h = hash_u32(h);
            lo + (h % (hi_inclusive - lo + 1) as u32) as i32
        };
        let size = IVec3::new(draw(smin.x, smax.x), draw(smin.y, smax.y), draw(smin.z, smax.z));
        let at = IVec3::new(draw(lo.x, hi.x - size.x), draw(lo.y, hi.y - size.y), draw(lo.z, hi.z - size.z));
        world.grid.fill_box(at, at + size, id).map_err(|e| e.to_string())?;
    }
    Ok(())
}

/// Exposed voxels of one material turned, by a hashed fraction, into others.
fn apply_speckle(
    world: &mut VoxelWorld,
    seed: u32,
    op_index: u32,
    on: &str,
    materials: &[String],
    fraction: &f32,
) -> Result<(), String> {
    let on = material_id(&world.palette, on)?;
    let ids = materials.iter().map(|m| material_id(&world.palette, m)).collect::<Result<Vec<_>, _>>()?;
    if ids.is_empty() || !(0.0..=1.0).contains(fraction) {
        return Err("speckle needs materials and a fraction within [0, 1]".into());
    }
    let mut exposed = Vec::new();
    world.grid.for_each_solid(|p, m| {
        if m == on && NEIGHBOURS.iter().any(|&d| world.grid.get(p + d) == AIR) {
            exposed.push(p);
        }
    });
    let threshold = (*fraction as f64 * u32::MAX as f64) as u32;
    for p in exposed {
        let h = hash_u32(
            seed ^ hash_u32(op_index ^ hash_u32((p.x as u32) ^ hash_u32((p.y as u32) ^ hash_u32(p.z as u32)))),
        );
        if h < threshold {
            let pick = ids[(hash_u32(h) % ids.len() as u32) as usize];
            world.grid.set(p, pick).map_err(|e| e.to_string())?;
        }
    }
    Ok(())
}

/// Text in the 5 x 7 font.
#[allow(clippy::too_many_arguments)]
fn apply_text(
    world: &mut VoxelWorld,
    text: &str,
    material: &str,
    origin: &(i32, i32, i32),
    right: &(i32, i32, i32),
    up: &(i32, i32, i32),
    depth_dir: &(i32, i32, i32),
    scale: &i32,
    depth: &i32,
) -> Result<(), String> {
    let id = material_id(&world.palette, material)?;
    let axes = [IVec3::from(*right), IVec3::from(*up), IVec3::from(*depth_dir)];
    if axes.iter().any(|a| a.abs().element_sum() != 1) {
        return Err("text right, up and depth_dir must be unit axes like (1, 0, 0)".into());
    }
    if !(1..=64).contains(scale) || !(1..=64).contains(depth) || text.chars().count() > 256 {
        return Err("text scale and depth must be within 1..=64, text at most 256 characters".into());
    }
    let [right, up, into] = axes;
    for (i, c) in text.chars().enumerate() {
        let rows = glyph(c).ok_or_else(|| format!("the font has no {c:?} (A-Z, 0-9 and space)"))?;
        for (row, bits) in rows.iter().enumerate() {
            for col in 0..5 {
                if bits & (0b10000 >> col) == 0 {
                    continue;
                }
                let cell =
                    IVec3::from(*origin) + right * ((i as i32 * 6 + col) * scale) + up * ((6 - row as i32) * scale);
                for (a, b, k) in
                    (0..*scale).flat_map(|a| (0..*scale).flat_map(move |b| (0..*depth).map(move |k| (a, b, k))))
                {
                    let p = cell + right * a + up * b + into * k;
                    world.grid.set(p, id).map_err(|e| format!("text '{text}': {e}"))?;
                }
            }
        }
    }
    Ok(())
}

const NEIGHBOURS: [IVec3; 6] = [IVec3::X, IVec3::NEG_X, IVec3::Y, IVec3::NEG_Y, IVec3::Z, IVec3::NEG_Z];

/// Parses recipe text into a world.
pub fn parse_recipe(text: &str, location: &str) -> Result<VoxelWorld, LoadError> {
    parse_ron::<SceneRecipe>(text, location)?.build(location)
}

/// Folder of the bundled scene recipes: `$GLOWBRICK_ASSETS/scenes`, else `assets/scenes` next to the crate
/// where it was built, else `assets/scenes` in the current folder (a checkout moved or renamed after its build).
pub fn scenes_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("GLOWBRICK_ASSETS") {
        return PathBuf::from(dir).join("scenes");
    }
    let built_beside = Path::new(env!("CARGO_MANIFEST_DIR")).join("assets").join("scenes");
    if built_beside.is_dir() { built_beside } else { PathBuf::from("assets").join("scenes") }
}

/// Loads `assets/scenes/NAME.ron`. Names are plain identifiers, so `--scene` cannot reach outside the folder.
pub fn load_scene(name: &str) -> Result<VoxelWorld, LoadError> {
    if name.is_empty() || !name.chars().all(|c| c.is_ascii_alphanumeric() || c == '-' || c == '_') {
        return Err(LoadError {
            location: name.to_string(),
            message: "scene names use letters, digits, '-' and '_'".into(),
        });
    }
    let dir = scenes_dir();
    if !dir.is_dir() {
        return Err(LoadError {
            location: dir.display().to_string(),
            message: "no scene folder here: run from the checkout, or set GLOWBRICK_ASSETS to its assets folder".into(),
        });
    }
    let path = dir.join(format!("{name}.ron"));
    if !path.exists() {
        let known = list_scenes().join(", ");
        return Err(LoadError {
            location: path.display().to_string(),
            message: format!("no such scene (known: {known})"),
        });
    }
    load_recipe(&path)
}

/// Loads a recipe file from a path.
pub fn load_recipe(path: &Path) -> Result<VoxelWorld, LoadError> {
    let text = read_limited(path, 16 * 1024 * 1024)?;
    parse_recipe(&text, &path.display().to_string())
}

/// Names of the bundled scene recipes, sorted.
pub fn list_scenes() -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(scenes_dir())
        .into_iter()
        .flatten()
        .flatten()
        .filter_map(|e| e.path().file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    names
}

/// The generated default world of `glowbrick play` (see `world::generate`).
pub fn generated_world(seed: u32, size: UVec3) -> Result<VoxelWorld, LoadError> {
    super::generate::generate_world(seed, size).map(|(world, _)| world)
}
