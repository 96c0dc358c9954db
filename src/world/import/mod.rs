//! Importers for worlds made elsewhere: the Voxel ReSTIR thesis' `.vx` scenes and MagicaVoxel `.vox` models.
//! Both validate as they read, bound their memory, and report the first problem as one `LoadError` line.

pub mod vox;
pub mod vx;

use super::VoxelWorld;
use super::cell_map::CellMap;
use super::grid::{BRICK_VOXELS, Voxel, local_index};
use bevy::math::IVec3;

/// Collects voxel writes brick by brick (last write wins) and builds the world at the end, so importing
/// millions of entries costs a hash lookup each instead of a brick-collapse check each.
pub struct BrickBuilder {
    bricks: CellMap<Box<[Voxel; BRICK_VOXELS]>>,
}

impl BrickBuilder {
    pub fn new() -> Self {
        BrickBuilder { bricks: CellMap::default() }
    }

    /// Writes one voxel (callers check that `p` is inside the world).
    pub fn set(&mut self, p: IVec3, v: Voxel) {
        let brick = self.bricks.entry(p >> 3_i32).or_insert_with(|| Box::new([0; BRICK_VOXELS]));
        brick[local_index(p & 7_i32)] = v;
    }

    /// Moves the collected bricks into `world` (uniform bricks collapse), leaving nothing dirty.
    pub fn finish(self, world: &mut VoxelWorld) {
        for (b, voxels) in self.bricks {
            world.grid.set_brick(b, &voxels);
        }
        world.grid.take_dirty();
    }
}

impl Default for BrickBuilder {
    fn default() -> Self {
        Self::new()
    }
}
