//! Undo and redo (Ctrl+Z / Ctrl+Y) of the player's edits. Each undoable edit is one batch: the edit path hands
//! over what the edit's box held before (`EditApplied::before`), undo writes it back with an `Edit::Restore`,
//! redo applies the edit again. Both go through the same edit path as everything else.

use crate::world::events::{ApplyEdits, EditApplied, EditRequest};
use crate::world::{Edit, Voxel, VoxelWorld};
use bevy::prelude::*;
use std::collections::VecDeque;
use std::sync::Arc;

/// Oldest batches are dropped beyond this many voxels of history (2 bytes each: 128 MiB).
const MAX_HISTORY_VOXELS: usize = 64 << 20;

/// Asks to undo or redo one batch.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub enum HistoryAction {
    Undo,
    Redo,
}

#[derive(Clone, Debug)]
struct Batch {
    edit: Edit,
    min: IVec3,
    max: IVec3,
    before: Arc<[Voxel]>,
}

/// The undo and redo stacks.
#[derive(Resource, Default)]
pub struct UndoHistory {
    undo: VecDeque<Batch>,
    redo: Vec<Batch>,
    voxels: usize,
    world: Option<u64>,
}

impl UndoHistory {
    pub fn undo_len(&self) -> usize {
        self.undo.len()
    }

    pub fn redo_len(&self) -> usize {
        self.redo.len()
    }
}

pub struct UndoPlugin;

impl Plugin for UndoPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<UndoHistory>()
            .add_message::<HistoryAction>()
            .add_systems(Update, (undo_or_redo.before(ApplyEdits), record_batches.after(ApplyEdits)));
    }
}

/// Ctrl+Z undoes, Ctrl+Y (or Ctrl+Shift+Z) redoes. Needs a window.
pub fn history_keys(keys: Res<ButtonInput<KeyCode>>, mut actions: MessageWriter<HistoryAction>) {
    let ctrl = keys.any_pressed([KeyCode::ControlLeft, KeyCode::ControlRight]);
    let shift = keys.any_pressed([KeyCode::ShiftLeft, KeyCode::ShiftRight]);
    if ctrl && keys.just_pressed(KeyCode::KeyZ) {
        actions.write(if shift { HistoryAction::Redo } else { HistoryAction::Undo });
    }
    if ctrl && keys.just_pressed(KeyCode::KeyY) {
        actions.write(HistoryAction::Redo);
    }
}

fn undo_or_redo(
    mut actions: MessageReader<HistoryAction>,
    mut history: ResMut<UndoHistory>,
    mut edits: MessageWriter<EditRequest>,
) {
    for action in actions.read() {
        match action {
            HistoryAction::Undo => {
                if let Some(batch) = history.undo.pop_back() {
                    history.voxels -= batch.before.len();
                    let restore = Edit::Restore { min: batch.min, max: batch.max, voxels: batch.before.clone() };
                    edits.write(EditRequest::unrecorded(restore));
                    history.redo.push(batch);
                }
            }
            HistoryAction::Redo => {
                if let Some(batch) = history.redo.pop() {
                    edits.write(EditRequest::unrecorded(batch.edit.clone()));
                    history.voxels += batch.before.len();
                    history.undo.push_back(batch);
                }
            }
        }
    }
}

fn record_batches(
    mut applied: MessageReader<EditApplied>,
    world: Option<Res<VoxelWorld>>,
    mut history: ResMut<UndoHistory>,
) {
    // A new world (loaded or generated) starts a new history.
    let instance = world.map(|w| w.instance);
    if history.world != instance {
        *history = UndoHistory { world: instance, ..default() };
    }
    for event in applied.read() {
        let Some(before) = event.before.clone() else { continue };
        history.voxels += before.len();
        history.undo.push_back(Batch { edit: event.edit.clone(), min: event.min, max: event.max, before });
        history.redo.clear();
        while history.voxels > MAX_HISTORY_VOXELS
            && let Some(old) = history.undo.pop_front()
        {
            history.voxels -= old.before.len();
        }
    }
}
