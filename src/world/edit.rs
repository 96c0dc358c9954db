//! Edits: the one way gameplay changes voxels. Each edit records the bricks it touches in the grid's dirty set.

use super::VoxelWorld;
use super::grid::{AIR, OutOfWorld, Voxel};
use bevy::math::IVec3;

/// A change to the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Edit {
    /// Sets one voxel to a material.
    Place { at: IVec3, material: Voxel },
    /// Sets one voxel to air.
    Break { at: IVec3 },
    /// Sets every voxel of the box from `min` to `max` (both inclusive) to a material (air clears).
    FillBox { min: IVec3, max: IVec3, material: Voxel },
}

/// Why an edit was refused. The world is unchanged when an edit fails.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum EditError {
    OutOfWorld(OutOfWorld),
    UnknownMaterial { id: Voxel, palette_ids: usize },
}

impl std::fmt::Display for EditError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EditError::OutOfWorld(e) => write!(f, "edit refused: {e}"),
            EditError::UnknownMaterial { id, palette_ids } => {
                write!(f, "edit refused: material id {id} is not in the palette (ids 0..{})", palette_ids - 1)
            }
        }
    }
}

impl std::error::Error for EditError {}

impl VoxelWorld {
    /// Applies an edit; returns how many voxels changed. Validates fully before changing anything.
    pub fn apply(&mut self, edit: Edit) -> Result<u64, EditError> {
        let material = match edit {
            Edit::Place { material, .. } | Edit::FillBox { material, .. } => material,
            Edit::Break { .. } => AIR,
        };
        if material as usize >= self.palette.id_count() {
            return Err(EditError::UnknownMaterial { id: material, palette_ids: self.palette.id_count() });
        }
        match edit {
            Edit::Place { at, .. } | Edit::Break { at } => {
                Ok(self.grid.set(at, material).map_err(EditError::OutOfWorld)? as u64)
            }
            Edit::FillBox { min, max, .. } => {
                let (lo, hi) = (min.min(max), min.max(max));
                self.grid.fill_box(lo, hi + IVec3::ONE, material).map_err(EditError::OutOfWorld)
            }
        }
    }
}
