//! Importers for worlds made elsewhere: the Voxel ReSTIR thesis' `.vx` scenes and MagicaVoxel `.vox` models.
//! Both validate as they read, bound their memory, and report the first problem as one `LoadError` line.

pub mod vox;
pub mod vx;

use super::VoxelWorld;
use super::cell_map::CellMap;
use super::grid::{BRICK_VOXELS, Voxel, local_index};
use bevy::math::IVec3;

/// Collects voxel writes brick by brick (last write wins) and builds the world at the end, so importing
/// millions of entries costs a hash lookup each instead of a brick-collapse check each, and not even that while
/// consecutive writes stay in one brick (the files list voxels in runs).
pub struct BrickBuilder {
    /// Brick coordinate -> its place in `bricks`.
    index: CellMap<usize>,
    bricks: Vec<(IVec3, Box<[Voxel; BRICK_VOXELS]>)>,
    /// The brick of the last write and its place.
    last: Option<(IVec3, usize)>,
}

impl BrickBuilder {
    pub fn new() -> Self {
        BrickBuilder { index: CellMap::default(), bricks: Vec::new(), last: None }
    }

    /// Writes one voxel (callers check that `p` is inside the world).
    pub fn set(&mut self, p: IVec3, v: Voxel) {
        let b = p >> 3_i32;
        let place = match self.last {
            Some((last, place)) if last == b => place,
            _ => {
                let bricks = &mut self.bricks;
                let place = *self.index.entry(b).or_insert_with(|| {
                    bricks.push((b, Box::new([0; BRICK_VOXELS])));
                    bricks.len() - 1
                });
                self.last = Some((b, place));
                place
            }
        };
        self.bricks[place].1[local_index(p & 7_i32)] = v;
    }

    /// Moves the collected bricks into `world` (uniform bricks collapse), in the order they were first written,
    /// leaving nothing dirty.
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
