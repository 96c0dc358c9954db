//! The one edit path of the game: `EditRequest` messages are applied to the world in order by
//! `apply_edit_requests`, which reports each change as an `EditApplied` message (the light pool listens) and
//! each refusal as an `EditRefused` message. The grid records the dirty bricks the renderer uploads.

use super::{Edit, EditError, Voxel, VoxelWorld};
use bevy::prelude::*;
use std::sync::Arc;

/// Asks for an edit. `undoable` edits (the player's) record what they replace so undo can put it back.
#[derive(Message, Clone, Debug, PartialEq, Eq)]
pub struct EditRequest {
    pub edit: Edit,
    pub undoable: bool,
}

impl EditRequest {
    /// A player's edit, recorded for undo.
    pub fn player(edit: Edit) -> Self {
        EditRequest { edit, undoable: true }
    }

    /// An edit that undo does not record (undo and redo themselves, scripted changes).
    pub fn unrecorded(edit: Edit) -> Self {
        EditRequest { edit, undoable: false }
    }
}

/// An edit that changed the world: its inclusive voxel bounds, how many voxels changed, and for undoable edits
/// the voxels the box held before.
#[derive(Message, Clone, Debug, PartialEq, Eq)]
pub struct EditApplied {
    pub edit: Edit,
    pub min: IVec3,
    pub max: IVec3,
    pub changed: u64,
    pub before: Option<Arc<[Voxel]>>,
}

/// An edit the world refused (out of the world, unknown material); the world is unchanged.
#[derive(Message, Clone, Debug, PartialEq, Eq)]
pub struct EditRefused {
    pub edit: Edit,
    pub error: EditError,
}

/// Present on a networked client: the server applies edits, so local requests are sent to it (`net::client`)
/// instead of being applied here.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct EditsFromServer;

/// Systems that apply edits, in `Update`.
#[derive(SystemSet, Clone, Debug, PartialEq, Eq, Hash)]
pub struct ApplyEdits;

pub struct WorldEditPlugin;

impl Plugin for WorldEditPlugin {
    fn build(&self, app: &mut App) {
        app.add_message::<EditRequest>().add_message::<EditApplied>().add_message::<EditRefused>().add_systems(
            Update,
            apply_edit_requests
                .in_set(ApplyEdits)
                .run_if(resource_exists::<VoxelWorld>.and_then(not(resource_exists::<EditsFromServer>))),
        );
    }
}

pub fn apply_edit_requests(
    mut requests: MessageReader<EditRequest>,
    mut world: ResMut<VoxelWorld>,
    mut applied: MessageWriter<EditApplied>,
    mut refused: MessageWriter<EditRefused>,
) {
    for request in requests.read() {
        let edit = request.edit.clone();
        let (min, max) = edit.bounds();
        let before = request.undoable.then(|| Arc::from(world.grid.read_box(min, max + IVec3::ONE)));
        match world.apply(edit.clone()) {
            Ok(0) => {}
            Ok(changed) => {
                applied.write(EditApplied { edit, min, max, changed, before });
            }
            Err(error) => {
                refused.write(EditRefused { edit, error });
            }
        }
    }
}
