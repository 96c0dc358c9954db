//! Keeps the `LightPool` resource in step with the world: a full scan when a world is loaded or replaced,
//! `update_region` after every applied edit. (Its GPU copy is `render::scene::lights`.)

use super::LightPool;
use crate::world::VoxelWorld;
use crate::world::events::{ApplyEdits, EditApplied};
use bevy::prelude::*;

/// Which world the pool was built from.
#[derive(Resource, Default)]
struct PoolWorld(Option<u64>);

pub struct LightsPlugin;

impl Plugin for LightsPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<LightPool>().init_resource::<PoolWorld>().add_systems(
            Update,
            (rebuild_on_new_world, update_after_edits).chain().after(ApplyEdits).run_if(resource_exists::<VoxelWorld>),
        );
    }
}

fn rebuild_on_new_world(world: Res<VoxelWorld>, mut pool: ResMut<LightPool>, mut built_from: ResMut<PoolWorld>) {
    if built_from.0 != Some(world.instance) {
        *pool = LightPool::from_world(&world);
        built_from.0 = Some(world.instance);
    }
}

fn update_after_edits(mut edits: MessageReader<EditApplied>, world: Res<VoxelWorld>, mut pool: ResMut<LightPool>) {
    for edit in edits.read() {
        pool.update_region(&world, edit.min, edit.max);
    }
}
