//! Undo and redo (Ctrl+Z / Ctrl+Y) of the player's edits. Each undoable edit is one batch: the edit path hands
//! over what the edit's box held before (`EditApplied::before`), undo writes it back with an `Edit::Restore`,
//! redo applies the edit again. Both go through the same edit path as everything else. On a server the server
//! keeps the stacks (per player name, so they outlast a reconnect): Ctrl+Z asks it.

use crate::world::VoxelWorld;
use crate::world::events::{ApplyEdits, EditApplied, EditRequest, EditsFromServer};
use crate::world::history::EditHistory;
use bevy::prelude::*;

/// Oldest batches are dropped beyond this many voxels of history (2 bytes each: 128 MiB).
const MAX_HISTORY_VOXELS: usize = 64 << 20;

/// Asks to undo or redo one batch.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub enum HistoryAction {
    Undo,
    Redo,
}

/// The player's undo and redo stacks, for the world they were recorded in.
#[derive(Resource)]
pub struct UndoHistory {
    stacks: EditHistory,
    world: Option<u64>,
}

impl Default for UndoHistory {
    fn default() -> Self {
        UndoHistory { stacks: EditHistory::new(MAX_HISTORY_VOXELS), world: None }
    }
}

impl UndoHistory {
    pub fn undo_len(&self) -> usize {
        self.stacks.undo_len()
    }

    pub fn redo_len(&self) -> usize {
        self.stacks.redo_len()
    }
}

pub struct UndoPlugin;

impl Plugin for UndoPlugin {
    fn build(&self, app: &mut App) {
        let local = not(resource_exists::<EditsFromServer>);
        app.init_resource::<UndoHistory>().add_message::<HistoryAction>().add_systems(
            Update,
            (
                undo_or_redo.before(ApplyEdits).run_if(local.clone()),
                record_batches.after(ApplyEdits).run_if(local),
                ask_the_server.run_if(resource_exists::<EditsFromServer>),
            ),
        );
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
        let edit = match action {
            HistoryAction::Undo => history.stacks.undo(),
            HistoryAction::Redo => history.stacks.redo(),
        };
        if let Some(edit) = edit {
            edits.write(EditRequest::unrecorded(edit));
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
        history.stacks.record(event.edit.clone(), event.min, event.max, before);
    }
}

/// On a server, undo and redo are the server's: it holds this player's stacks.
fn ask_the_server(
    mut actions: MessageReader<HistoryAction>,
    mut asks: MessageWriter<crate::net::protocol::HistoryAsk>,
) {
    for action in actions.read() {
        asks.write(crate::net::protocol::HistoryAsk { redo: *action == HistoryAction::Redo });
    }
}
