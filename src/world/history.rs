//! Undo and redo stacks of one player's edits, as batches: each undoable edit with what its box held before.
//! Undo writes the box back (`Edit::Restore`), redo applies the edit again. The game keeps one for its player
//! (`game::undo`); a server keeps one per player name (`net::server`), so undo works the same in both and
//! survives a player's reconnect.

use super::{Edit, Voxel};
use bevy::math::IVec3;
use std::collections::VecDeque;
use std::sync::Arc;

#[derive(Clone, Debug)]
struct Batch {
    edit: Edit,
    min: IVec3,
    max: IVec3,
    before: Arc<[Voxel]>,
}

/// The undo and redo stacks, holding at most `max_voxels` voxels of `before` boxes (the oldest batches go first).
#[derive(Clone, Debug)]
pub struct EditHistory {
    undo: VecDeque<Batch>,
    redo: Vec<Batch>,
    voxels: usize,
    max_voxels: usize,
}

impl EditHistory {
    pub fn new(max_voxels: usize) -> Self {
        EditHistory { undo: VecDeque::new(), redo: Vec::new(), voxels: 0, max_voxels }
    }

    pub fn undo_len(&self) -> usize {
        self.undo.len()
    }

    pub fn redo_len(&self) -> usize {
        self.redo.len()
    }

    /// Voxels of `before` boxes held (2 bytes each).
    pub fn voxels(&self) -> usize {
        self.voxels
    }

    /// Records an applied edit of the box `min..=max`, which held `before`. A new edit ends the redo stack.
    pub fn record(&mut self, edit: Edit, min: IVec3, max: IVec3, before: Arc<[Voxel]>) {
        self.voxels += before.len();
        self.undo.push_back(Batch { edit, min, max, before });
        self.redo.clear();
        while self.voxels > self.max_voxels
            && let Some(old) = self.undo.pop_front()
        {
            self.voxels -= old.before.len();
        }
    }

    /// The edit that takes back the latest batch (it moves to the redo stack).
    pub fn undo(&mut self) -> Option<Edit> {
        let batch = self.undo.pop_back()?;
        self.voxels -= batch.before.len();
        let restore = Edit::Restore { min: batch.min, max: batch.max, voxels: batch.before.clone() };
        self.redo.push(batch);
        Some(restore)
    }

    /// The edit that applies the last undone batch again (it moves back to the undo stack).
    pub fn redo(&mut self) -> Option<Edit> {
        let batch = self.redo.pop()?;
        let edit = batch.edit.clone();
        self.voxels += batch.before.len();
        self.undo.push_back(batch);
        Some(edit)
    }

    /// Drops the oldest undo batch; whether there was one (a server making room across players).
    pub fn forget_oldest(&mut self) -> bool {
        match self.undo.pop_front() {
            Some(old) => {
                self.voxels -= old.before.len();
                true
            }
            None => false,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn place(x: i32) -> (Edit, IVec3) {
        (Edit::Place { at: IVec3::new(x, 0, 0), material: 1 }, IVec3::new(x, 0, 0))
    }

    #[test]
    fn undo_redo_and_the_voxel_budget() {
        let mut history = EditHistory::new(3);
        for x in 0..4 {
            let (edit, at) = place(x);
            history.record(edit, at, at, Arc::from([x as Voxel].as_slice()));
        }
        // Four one-voxel batches in a budget of three: the oldest went.
        assert_eq!((history.undo_len(), history.voxels()), (3, 3));
        let restore = history.undo().unwrap();
        assert_eq!(
            restore,
            Edit::Restore { min: IVec3::new(3, 0, 0), max: IVec3::new(3, 0, 0), voxels: Arc::from([3].as_slice()) }
        );
        assert_eq!(history.redo(), Some(place(3).0));
        assert_eq!(history.redo(), None);
        history.undo();
        // A new edit ends what could be redone.
        let (edit, at) = place(9);
        history.record(edit, at, at, Arc::from([0].as_slice()));
        assert_eq!((history.redo_len(), history.redo()), (0, None));
        assert!(history.forget_oldest());
        assert_eq!(history.undo_len(), 2);
    }
}
