//! Seeded, deterministic terrain: an fBm height field (the `noise` crate) in rock, soil and surface layers.

use super::VoxelWorld;
use super::grid::Voxel;
use bevy::math::IVec3;
use noise::{Fbm, MultiFractal, NoiseFn, Perlin};

/// Parameters of a height-field terrain.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct TerrainParams {
    /// Mean surface height in voxels.
    pub base_height: f32,
    /// Height variation in voxels (peak to mean).
    pub amplitude: f32,
    /// Noise frequency in cycles per voxel (0.01 gives hills about 100 voxels apart).
    pub frequency: f64,
    #[serde(default = "default_octaves")]
    pub octaves: usize,
    /// Voxels of soil between the surface and the rock.
    #[serde(default = "default_soil_depth")]
    pub soil_depth: i32,
}

fn default_octaves() -> usize {
    4
}

fn default_soil_depth() -> i32 {
    3
}

/// Height of the terrain column at (x, z) for a seed; deterministic across runs and platforms.
pub fn column_height(noise: &Fbm<Perlin>, params: &TerrainParams, x: i32, z: i32) -> i32 {
    let n = noise.get([x as f64 * params.frequency, z as f64 * params.frequency]) as f32;
    (params.base_height + n * params.amplitude).round() as i32
}

/// The fBm noise of a terrain.
pub fn terrain_noise(seed: u32, params: &TerrainParams) -> Fbm<Perlin> {
    Fbm::<Perlin>::new(seed).set_octaves(params.octaves.clamp(1, 8))
}

/// Fills columns with rock below, soil, and one surface voxel on top, clipped to the world.
pub fn fill_terrain(
    world: &mut VoxelWorld,
    seed: u32,
    params: &TerrainParams,
    rock: Voxel,
    soil: Voxel,
    surface: Voxel,
) {
    let noise = terrain_noise(seed, params);
    let size = world.grid.size().as_ivec3();
    for z in 0..size.z {
        for x in 0..size.x {
            let h = column_height(&noise, params, x, z).clamp(0, size.y - 1);
            let rock_top = (h - params.soil_depth).max(0);
            // Each column fill stays inside the world, so these cannot fail.
            let _ = world.grid.fill_box(IVec3::new(x, 0, z), IVec3::new(x + 1, rock_top, z + 1), rock);
            let _ = world.grid.fill_box(IVec3::new(x, rock_top, z), IVec3::new(x + 1, h, z + 1), soil);
            let _ = world.grid.set(IVec3::new(x, h, z), surface);
        }
    }
}

/// A small deterministic hash (pcg-style) for seeded placement.
pub fn hash_u32(mut v: u32) -> u32 {
    v = v.wrapping_mul(747_796_405).wrapping_add(2_891_336_453);
    let word = ((v >> ((v >> 28) + 4)) ^ v).wrapping_mul(277_803_737);
    (word >> 22) ^ word
}

/// The top solid voxel's height in column (x, z), or -1 when the column is empty.
pub fn surface_height(world: &VoxelWorld, x: i32, z: i32) -> i32 {
    let size = world.grid.size().as_ivec3();
    (0..size.y).rev().find(|&y| world.grid.get(IVec3::new(x, y, z)) != 0).unwrap_or(-1)
}
