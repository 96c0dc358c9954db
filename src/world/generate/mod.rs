//! The world generator behind `glowbrick play`: plains, hills and snowy mountains, caves that open to the surface
//! with glowing crystals deep inside, trees, and a lamp-lit village on a flattened plaza. Deterministic per seed
//! and size; the ground generates one brick column at a time in parallel (rayon).
//!
//! Views it leaves in the world: `village` (the start, on the plaza), `house` (inside a house), `cave` (facing a
//! crystal, when a cave with one has room for a camera), `overview` (above the village); `lantern` marks where the
//! default moving objects hang.

mod columns;
pub mod endless;
mod land;
mod trees;
mod village;

use super::format::LoadError;
use super::grid::{BRICK_SIZE, MAX_WORLD_EDGE, Voxel};
use super::palette::Palette;
use super::{CameraView, VoxelWorld};
use crate::progress::Progress;
use bevy::math::{IVec2, IVec3, UVec3, Vec3};
use columns::{GeneratedBrick, Ground};
use land::{Footprint, Land};
use rayon::prelude::*;

pub use land::VillageSite;
pub use village::SWING_PIVOT;

/// The block ids the generator places, looked up once from the palette.
pub struct Blocks {
    pub stone: Voxel,
    pub dirt: Voxel,
    pub grass: Voxel,
    pub sand: Voxel,
    pub snow: Voxel,
    pub wood: Voxel,
    pub leaves: Voxel,
    pub planks: Voxel,
    pub plaster: Voxel,
    pub roof: Voxel,
    pub cobble: Voxel,
    pub lamp_warm: Voxel,
    pub lamp_blue: Voxel,
    pub crystal_cyan: Voxel,
    pub crystal_violet: Voxel,
}

impl Blocks {
    fn of(palette: &Palette) -> Result<Self, String> {
        let id = |name: &str| palette.id_of(name).ok_or_else(|| format!("the palette has no '{name}'"));
        Ok(Blocks {
            stone: id("stone")?,
            dirt: id("dirt")?,
            grass: id("grass")?,
            sand: id("sand")?,
            snow: id("snow")?,
            wood: id("wood")?,
            leaves: id("leaves")?,
            planks: id("planks")?,
            plaster: id("plaster")?,
            roof: id("roof")?,
            cobble: id("cobble")?,
            lamp_warm: id("lamp-warm")?,
            lamp_blue: id("lamp-blue")?,
            crystal_cyan: id("crystal-cyan")?,
            crystal_violet: id("crystal-violet")?,
        })
    }
}

/// What the generator made besides voxels, for tests and the log line.
#[derive(Clone, Debug, Default)]
pub struct GenerationReport {
    pub trees: u32,
    pub houses: u32,
    pub crystals: u32,
}

/// Brick rows (along z) generated together before their bricks go into the grid: bounds the memory in flight.
const ROWS_PER_BATCH: i32 = 8;

/// Generates the world of `seed` at `size` (each edge clamped to `1..=MAX_WORLD_EDGE`).
pub fn generate_world(seed: u32, size: UVec3) -> Result<(VoxelWorld, GenerationReport), LoadError> {
    let size = size.clamp(UVec3::ONE, UVec3::splat(MAX_WORLD_EDGE));
    let fail = |message: String| LoadError { location: "generated world".into(), message };
    let palette = Palette::default_blocks();
    let blocks = Blocks::of(&palette).map_err(fail)?;
    let mut world = VoxelWorld::new(size, palette);
    let s = size.as_ivec3();
    let land = Land::new(seed, size.y);
    let site = land.village_site((s.x, s.y, s.z));
    let heights = land::height_field(&land, site.as_ref(), s.x, s.y, s.z);

    let footprint = Footprint { min: IVec2::ZERO, size: s };
    let ground = Ground::new(&land, &heights, footprint, site.as_ref(), seed, &blocks);
    let dims = world.grid.brick_dims().as_ivec3();
    let progress = Progress::new("generating world", dims.z as u64);
    let mut report = GenerationReport::default();
    for batch in (0..dims.z).step_by(ROWS_PER_BATCH as usize) {
        let rows: Vec<(i32, i32, Vec<GeneratedBrick>)> = (batch..(batch + ROWS_PER_BATCH).min(dims.z))
            .flat_map(|bz| (0..dims.x).map(move |bx| (bx, bz)))
            .collect::<Vec<_>>()
            .into_par_iter()
            .map(|(bx, bz)| (bx, bz, ground.brick_column(bx, bz)))
            .collect();
        for (bx, bz, column) in rows {
            report.crystals += place_column(&mut world, bx, bz, column, &blocks);
        }
        progress.advance((batch + ROWS_PER_BATCH).min(dims.z) as u64 - batch as u64);
    }
    progress.finish();

    report.trees = trees::plant_trees(&mut world, &land, &heights, site.as_ref(), seed, &blocks);
    let houses = match &site {
        Some(site) => village::build_village(&mut world, site, seed, &blocks),
        None => Vec::new(),
    };
    report.houses = houses.len() as u32;
    world.views = views(&world, &heights, site.as_ref(), &houses, &blocks);
    // Generating is not an edit: nothing is dirty until the world is uploaded as a whole.
    world.grid.take_dirty();
    Ok((world, report))
}

/// Puts a generated brick column into the world at its brick column (bx, bz); returns the crystals it holds.
fn place_column(world: &mut VoxelWorld, bx: i32, bz: i32, column: Vec<GeneratedBrick>, blocks: &Blocks) -> u32 {
    let size = world.grid.size().as_ivec3();
    let mut crystals = 0;
    for (by, brick) in column.into_iter().enumerate() {
        let b = IVec3::new(bx, by as i32, bz);
        match brick {
            GeneratedBrick::Uniform(0) => {}
            GeneratedBrick::Uniform(v) => {
                let lo = b * BRICK_SIZE;
                let _ = world.grid.fill_box(lo, (lo + BRICK_SIZE).min(size), v);
            }
            GeneratedBrick::Mixed(voxels) => {
                crystals +=
                    voxels.iter().filter(|&&v| v == blocks.crystal_cyan || v == blocks.crystal_violet).count() as u32;
                world.grid.set_brick(b, &voxels);
            }
        }
    }
    crystals
}

fn view(name: &str, origin: Vec3, target: Vec3) -> CameraView {
    CameraView {
        name: name.into(),
        origin: origin.into(),
        direction: (target - origin).normalize_or(Vec3::X).into(),
        fov_deg: 70.0,
    }
}

/// The named views: the start on the plaza, inside a house, a crystal cave, above the village, and where the
/// default moving objects hang.
fn views(
    world: &VoxelWorld,
    heights: &[i32],
    site: Option<&VillageSite>,
    houses: &[village::House],
    blocks: &Blocks,
) -> Vec<CameraView> {
    let s = world.grid.size().as_ivec3();
    let mut views = Vec::new();
    let half = Vec3::splat(0.5);
    match (site, houses.first()) {
        (Some(site), Some(house)) => {
            let plaza = IVec3::new(site.centre.0, site.ground, site.centre.1).as_vec3() + half;
            let door = house.door.as_vec3() + half;
            let away = (plaza - door).with_y(0.0).normalize_or(Vec3::X);
            // Between two houses at the plaza's edge, at a standing player's eye height, looking across the fountain
            // at the houses on the far side: of 64 spots on that circle, the one farthest from every house.
            let clearance = |p: Vec3| {
                houses
                    .iter()
                    .map(|h| {
                        let lo = h.min.as_vec3().with_y(0.0);
                        let hi = h.max.as_vec3().with_y(0.0);
                        (p.with_y(0.0) - p.with_y(0.0).clamp(lo, hi)).length()
                    })
                    .fold(f32::MAX, f32::min)
            };
            let spot = |k: i32| {
                let angle = std::f32::consts::TAU * k as f32 / 64.0;
                plaza + Vec3::new(angle.cos(), 0.0, angle.sin()) * site.radius * 0.55
            };
            let start = (0..64).map(spot).max_by(|a, b| clearance(*a).total_cmp(&clearance(*b))).unwrap_or(plaza);
            views.push(view("village", start + Vec3::Y * 2.6, plaza + Vec3::Y * 1.5));
            let inside = door + house.inward.as_vec3() * 1.2 + Vec3::Y * 1.1;
            views.push(view("house", inside, inside + house.inward.as_vec3() * 4.0 + Vec3::Y * 0.6));
            views.push(view("lantern", plaza + Vec3::Y * 5.0, plaza));
            let above = plaza - away * site.radius * 1.6 + Vec3::Y * site.radius * 1.1;
            views.push(view("overview", above.min(s.as_vec3() - 1.0), plaza));
        }
        _ => {
            let (x, z) = (s.x / 2, s.z / 2);
            let ground = heights[(z * s.x + x) as usize];
            let start = Vec3::new(x as f32, ground as f32 + 6.0, z as f32) + half;
            views.push(CameraView {
                name: "start".into(),
                origin: start.min(s.as_vec3() - 0.5).into(),
                direction: Vec3::new(0.6, -0.25, 0.75).normalize().into(),
                fov_deg: 60.0,
            });
        }
    }
    if let Some(cave) = cave_view(world, heights, blocks) {
        views.push(cave);
    }
    views
}

/// A camera a few voxels from a crystal, in the cave's air with a clear line to it; the crystal nearest the
/// middle of the world that has one.
fn cave_view(world: &VoxelWorld, heights: &[i32], blocks: &Blocks) -> Option<CameraView> {
    let s = world.grid.size().as_ivec3();
    let mut crystals = Vec::new();
    // Only columns on a coarse grid near the middle: finding one good crystal does not need every column.
    let (cx, cz) = (s.x / 2, s.z / 2);
    let reach = (s.x.max(s.z) / 2).min(256);
    for z in (cz - reach).max(0)..(cz + reach).min(s.z) {
        for x in (cx - reach).max(0)..(cx + reach).min(s.x) {
            let h = heights[(z * s.x + x) as usize];
            for y in 4..h {
                let v = world.grid.get(IVec3::new(x, y, z));
                if (v == blocks.crystal_cyan || v == blocks.crystal_violet)
                    && world.grid.get(IVec3::new(x, y - 1, z)) != v
                {
                    crystals.push(IVec3::new(x, y, z));
                }
            }
        }
    }
    crystals.sort_by_key(|p| (p.x - cx).pow(2) + (p.z - cz).pow(2));
    let air = |p: IVec3| world.grid.contains(p) && world.grid.get(p) == 0;
    for crystal in crystals.into_iter().take(4096) {
        for dir in [IVec3::X, -IVec3::X, IVec3::Z, -IVec3::Z] {
            for distance in (3..=7).rev() {
                let eye = crystal + dir * distance + IVec3::Y;
                let clear = (1..=distance).all(|k| air(crystal + dir * k + IVec3::Y) && air(crystal + dir * k))
                    && air(eye + IVec3::Y);
                if clear {
                    let target = crystal.as_vec3() + Vec3::splat(0.5);
                    return Some(view("cave", eye.as_vec3() + Vec3::new(0.5, 0.6, 0.5), target));
                }
            }
        }
    }
    None
}
