//! Edits: the one way gameplay changes voxels. Each edit records the bricks it touches in the grid's dirty set.

use super::VoxelWorld;
use super::grid::{AIR, OutOfWorld, Voxel};
use bevy::math::IVec3;
use std::sync::Arc;

/// A change to the world.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Edit {
    /// Sets one voxel to a material.
    Place { at: IVec3, material: Voxel },
    /// Sets one voxel to air.
    Break { at: IVec3 },
    /// Sets every voxel of the box from `min` to `max` (both inclusive) to a material (air clears).
    FillBox { min: IVec3, max: IVec3, material: Voxel },
    /// Writes `voxels` (x fastest, then y, then z) into the box from `min` to `max` (inclusive): how undo puts
    /// back what an edit replaced.
    Restore { min: IVec3, max: IVec3, voxels: Arc<[Voxel]> },
}

/// Why an edit was refused. The world is unchanged when an edit fails.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum EditError {
    OutOfWorld(OutOfWorld),
    UnknownMaterial { id: Voxel, palette_ids: usize },
    WrongVoxelCount { expected: usize, got: usize },
}

impl std::fmt::Display for EditError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            EditError::OutOfWorld(e) => write!(f, "edit refused: {e}"),
            EditError::UnknownMaterial { id, palette_ids } => {
                write!(f, "edit refused: material id {id} is not in the palette (ids 0..{})", palette_ids - 1)
            }
            EditError::WrongVoxelCount { expected, got } => {
                write!(f, "edit refused: restore carries {got} voxels for a box of {expected}")
            }
        }
    }
}

impl std::error::Error for EditError {}

impl Edit {
    /// Inclusive voxel bounds of what the edit may touch.
    pub fn bounds(&self) -> (IVec3, IVec3) {
        match self {
            Edit::Place { at, .. } | Edit::Break { at } => (*at, *at),
            Edit::FillBox { min, max, .. } | Edit::Restore { min, max, .. } => (min.min(*max), min.max(*max)),
        }
    }
}

impl VoxelWorld {
    /// Applies an edit; returns how many voxels changed. Validates fully before changing anything.
    pub fn apply(&mut self, edit: Edit) -> Result<u64, EditError> {
        let ids = self.palette.id_count();
        let unknown = |id: Voxel| EditError::UnknownMaterial { id, palette_ids: ids };
        match edit {
            Edit::Place { at, material } => {
                if material as usize >= ids {
                    return Err(unknown(material));
                }
                Ok(self.grid.set(at, material).map_err(EditError::OutOfWorld)? as u64)
            }
            Edit::Break { at } => Ok(self.grid.set(at, AIR).map_err(EditError::OutOfWorld)? as u64),
            Edit::FillBox { min, max, material } => {
                if material as usize >= ids {
                    return Err(unknown(material));
                }
                let (lo, hi) = (min.min(max), min.max(max));
                self.grid.fill_box(lo, hi + IVec3::ONE, material).map_err(EditError::OutOfWorld)
            }
            Edit::Restore { min, max, voxels } => {
                let extent = (max - min + IVec3::ONE).max(IVec3::ZERO);
                let expected = extent.x as usize * extent.y as usize * extent.z as usize;
                if voxels.len() != expected {
                    return Err(EditError::WrongVoxelCount { expected, got: voxels.len() });
                }
                if let Some(&bad) = voxels.iter().find(|&&v| v as usize >= ids) {
                    return Err(unknown(bad));
                }
                self.grid.write_box(min, max + IVec3::ONE, &voxels).map_err(EditError::OutOfWorld)
            }
        }
    }
}
