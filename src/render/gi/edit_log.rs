//! The GI cache's edit log: the boxes of the bricks edited lately, each under the epoch of its edit. An entry
//! whose cached hits were traced before an edit that reached its rays retraces them (`shaders/gi/refresh.wgsl`).

use crate::render::gpu_types::GiEdit;
use crate::world::grid::BRICK_SIZE;
use bevy::math::IVec3;
use std::collections::VecDeque;

/// Edited boxes remembered; older edits force a retrace of everything traced before them.
pub const EDIT_LOG: usize = 64;
/// Bricks one frame may log one by one; more become their bounding box.
const BRICKS_LOGGED_APART: usize = 16;

/// The edit log, oldest first.
pub struct EditLog {
    records: VecDeque<GiEdit>,
    /// The epoch of the latest edit (1 before any).
    epoch: u32,
    /// The newest epoch dropped from the log: entries traced at or before it cannot tell whether it reached
    /// them.
    lost_epoch: u32,
}

impl Default for EditLog {
    fn default() -> Self {
        EditLog { records: VecDeque::new(), epoch: 1, lost_epoch: 0 }
    }
}

impl EditLog {
    /// Records this frame's edited bricks under a new epoch; whether anything was recorded.
    pub fn record(&mut self, bricks: &[IVec3]) -> bool {
        if bricks.is_empty() {
            return false;
        }
        self.epoch += 1;
        let edge = BRICK_SIZE;
        let boxes: Vec<(IVec3, IVec3)> = if bricks.len() <= BRICKS_LOGGED_APART {
            bricks.iter().map(|b| (*b * edge, (*b + 1) * edge)).collect()
        } else {
            let lo = bricks.iter().fold(IVec3::MAX, |a, b| a.min(*b));
            let hi = bricks.iter().fold(IVec3::MIN, |a, b| a.max(*b));
            vec![(lo * edge, (hi + 1) * edge)]
        };
        for (lo, hi) in boxes {
            if self.records.len() == EDIT_LOG
                && let Some(oldest) = self.records.pop_front()
            {
                self.lost_epoch = self.lost_epoch.max(oldest.epoch as u32);
            }
            self.records.push_back(GiEdit {
                min: lo.to_array(),
                epoch: self.epoch as i32,
                max: hi.to_array(),
                _pad: 0,
            });
        }
        true
    }

    pub fn epoch(&self) -> u32 {
        self.epoch
    }

    pub fn lost_epoch(&self) -> u32 {
        self.lost_epoch
    }

    /// Records in the log (the shaders read this many).
    pub fn count(&self) -> u32 {
        self.records.len() as u32
    }

    /// The records as the GPU reads them, oldest first.
    pub fn records(&self) -> Vec<GiEdit> {
        self.records.iter().copied().collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_few_bricks_are_logged_one_by_one_under_one_new_epoch() {
        let mut log = EditLog::default();
        assert!(!log.record(&[]), "no edit, no epoch");
        assert_eq!(log.epoch(), 1);
        assert!(log.record(&[IVec3::new(1, 0, 2), IVec3::new(3, 1, 0)]));
        assert_eq!((log.epoch(), log.count() as usize), (2, 2));
        let first = log.records()[0];
        assert_eq!((first.min, first.max, first.epoch), ([8, 0, 16], [16, 8, 24], 2));
    }

    #[test]
    fn many_bricks_in_one_frame_become_their_bounding_box() {
        let mut log = EditLog::default();
        let bricks: Vec<IVec3> = (0..=BRICKS_LOGGED_APART as i32).map(|i| IVec3::new(i, 1, 2)).collect();
        log.record(&bricks);
        assert_eq!(log.count() as usize, 1);
        let edit = log.records()[0];
        assert_eq!((edit.min, edit.max), ([0, 8, 16], [8 * (BRICKS_LOGGED_APART as i32 + 1), 16, 24]));
    }

    #[test]
    fn edits_that_fall_off_the_log_are_remembered_as_lost() {
        let mut log = EditLog::default();
        for i in 0..EDIT_LOG as u32 {
            log.record(&[IVec3::new(i as i32, 0, 0)]);
        }
        assert_eq!((log.count() as usize, log.lost_epoch()), (EDIT_LOG, 0));
        log.record(&[IVec3::ZERO]);
        log.record(&[IVec3::ONE]);
        // Epochs 2 and 3 (the first two edits) fell off.
        assert_eq!((log.count() as usize, log.lost_epoch(), log.epoch()), (EDIT_LOG, 3, EDIT_LOG as u32 + 3));
        assert_eq!(log.records()[0].epoch, 4);
    }
}
