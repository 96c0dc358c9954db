//! The one edit path of the game: `EditRequest` messages are applied to the world in order by
//! `apply_edit_requests`, which reports each change as an `EditApplied` message (the light pool listens) and
//! each refusal as an `EditRefused` message. The grid records the dirty bricks the renderer uploads.

use super::{Edit, EditError, VoxelWorld};
use bevy::prelude::*;

/// Asks for an edit.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub struct EditRequest(pub Edit);

/// An edit that changed the world: its inclusive voxel bounds and how many voxels changed.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub struct EditApplied {
    pub edit: Edit,
    pub min: IVec3,
    pub max: IVec3,
    pub changed: u64,
}

/// An edit the world refused (out of the world, unknown material); the world is unchanged.
#[derive(Message, Clone, Debug, PartialEq, Eq)]
pub struct EditRefused {
    pub edit: Edit,
    pub error: EditError,
}

impl Edit {
    /// Inclusive voxel bounds of what the edit may touch.
    pub fn bounds(&self) -> (IVec3, IVec3) {
        match *self {
            Edit::Place { at, .. } | Edit::Break { at } => (at, at),
            Edit::FillBox { min, max, .. } => (min.min(max), min.max(max)),
        }
    }
}

/// Systems that apply edits, in `Update`.
#[derive(SystemSet, Clone, Debug, PartialEq, Eq, Hash)]
pub struct ApplyEdits;

pub struct WorldEditPlugin;

impl Plugin for WorldEditPlugin {
    fn build(&self, app: &mut App) {
        app.add_message::<EditRequest>()
            .add_message::<EditApplied>()
            .add_message::<EditRefused>()
            .add_systems(Update, apply_edit_requests.in_set(ApplyEdits).run_if(resource_exists::<VoxelWorld>));
    }
}

pub fn apply_edit_requests(
    mut requests: MessageReader<EditRequest>,
    mut world: ResMut<VoxelWorld>,
    mut applied: MessageWriter<EditApplied>,
    mut refused: MessageWriter<EditRefused>,
) {
    for &EditRequest(edit) in requests.read() {
        match world.apply(edit) {
            Ok(0) => {}
            Ok(changed) => {
                let (min, max) = edit.bounds();
                applied.write(EditApplied { edit, min, max, changed });
            }
            Err(error) => {
                refused.write(EditRefused { edit, error });
            }
        }
    }
}
