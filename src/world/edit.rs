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

    /// The same edit `by` voxels away (from one frame of coordinates to another: a window's, the world's).
    pub fn moved(&self, by: IVec3) -> Edit {
        match self {
            Edit::Place { at, material } => Edit::Place { at: *at + by, material: *material },
            Edit::Break { at } => Edit::Break { at: *at + by },
            Edit::FillBox { min, max, material } => {
                Edit::FillBox { min: *min + by, max: *max + by, material: *material }
            }
            Edit::Restore { min, max, voxels } => {
                Edit::Restore { min: *min + by, max: *max + by, voxels: voxels.clone() }
            }
        }
    }

    /// The part of the edit inside the box `lo..=hi`, or `None` where it touches none of it. A restore keeps the
    /// voxels of its part (a restore of the wrong voxel count is kept whole, for `apply` to refuse).
    pub fn clipped(&self, lo: IVec3, hi: IVec3) -> Option<Edit> {
        let (min, max) = self.bounds();
        let (a, b) = (min.max(lo), max.min(hi));
        if a.cmpgt(b).any() {
            return None;
        }
        if (a, b) == (min, max) {
            return Some(self.clone());
        }
        Some(match self {
            Edit::Place { .. } | Edit::Break { .. } => self.clone(),
            Edit::FillBox { material, .. } => Edit::FillBox { min: a, max: b, material: *material },
            Edit::Restore { voxels, .. } => {
                let extent = max - min + IVec3::ONE;
                let count = extent.x as usize * extent.y as usize * extent.z as usize;
                if voxels.len() != count {
                    return Some(self.clone());
                }
                let mut part = Vec::with_capacity(((b - a + IVec3::ONE).as_uvec3().element_product()) as usize);
                for z in a.z..=b.z {
                    for y in a.y..=b.y {
                        let row = ((z - min.z) * extent.y + (y - min.y)) * extent.x;
                        let from = (row + a.x - min.x) as usize;
                        part.extend_from_slice(&voxels[from..=from + (b.x - a.x) as usize]);
                    }
                }
                Edit::Restore { min: a, max: b, voxels: Arc::from(part) }
            }
        })
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::palette::{Material, Palette};
    use bevy::math::UVec3;

    fn world() -> VoxelWorld {
        let palette = Palette::new((1..4).map(|i| Material::solid(&format!("m{i}"), [0.5; 3])).collect());
        VoxelWorld::new(UVec3::new(16, 16, 16), palette)
    }

    #[test]
    fn an_edit_cut_in_parts_applies_as_the_whole() {
        let voxels: Vec<Voxel> = (0..5 * 3 * 4).map(|i| (i % 4) as Voxel).collect();
        let edits = [
            Edit::Restore { min: IVec3::new(2, 1, 3), max: IVec3::new(6, 3, 6), voxels: Arc::from(voxels) },
            Edit::FillBox { min: IVec3::new(1, 0, 1), max: IVec3::new(9, 4, 7), material: 2 },
            Edit::Place { at: IVec3::new(5, 5, 5), material: 3 },
        ];
        for edit in edits {
            let mut whole = world();
            whole.apply(edit.clone()).unwrap();
            let mut parts = world();
            // Cut at x = 4 and z = 5: four parts, each applied alone.
            for (lo, hi) in [(0, 4), (5, 15)] {
                for (zlo, zhi) in [(0, 5), (6, 15)] {
                    let (a, b) = (IVec3::new(lo, 0, zlo), IVec3::new(hi, 15, zhi));
                    if let Some(part) = edit.clipped(a, b) {
                        let (min, max) = part.bounds();
                        assert!(min.cmpge(a).all() && max.cmple(b).all(), "{part:?} inside its part");
                        parts.apply(part).unwrap();
                    }
                }
            }
            let mut differ = 0;
            whole.grid.for_each_solid(|p, v| differ += (parts.grid.get(p) != v) as u32);
            parts.grid.for_each_solid(|p, v| differ += (whole.grid.get(p) != v) as u32);
            assert_eq!(differ, 0, "{edit:?}");
        }
        let place = Edit::Place { at: IVec3::ONE, material: 1 };
        assert_eq!(place.clipped(IVec3::splat(2), IVec3::splat(3)), None);
        assert_eq!(place.moved(IVec3::new(-1, 2, 3)), Edit::Place { at: IVec3::new(0, 3, 4), material: 1 });
    }
}
