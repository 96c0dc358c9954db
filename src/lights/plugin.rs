//! Keeps the `LightPool` resource in step with the world: a full scan when a world is loaded or replaced,
//! `update_region` after every applied edit, then the GPU upload.

use super::LightPool;
use super::upload::{
    LightUpload, LightUploadState, LightsLayout, PendingLightUploads, extract_light_upload, prepare_gpu_lights,
    stage_light_upload,
};
use crate::world::VoxelWorld;
use crate::world::events::{ApplyEdits, EditApplied};
use bevy::prelude::*;
use bevy::render::{ExtractSchedule, Render, RenderApp, RenderSystems};

/// Which world the pool was built from.
#[derive(Resource, Default)]
struct PoolWorld(Option<u64>);

pub struct LightsPlugin;

impl Plugin for LightsPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<LightPool>()
            .init_resource::<PoolWorld>()
            .init_resource::<LightUpload>()
            .init_resource::<LightUploadState>()
            .add_systems(
                Update,
                (rebuild_on_new_world, update_after_edits)
                    .chain()
                    .after(ApplyEdits)
                    .run_if(resource_exists::<VoxelWorld>),
            )
            .add_systems(PostUpdate, stage_light_upload);
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app
                .init_resource::<PendingLightUploads>()
                .init_resource::<LightsLayout>()
                .add_systems(ExtractSchedule, extract_light_upload)
                .add_systems(Render, prepare_gpu_lights.in_set(RenderSystems::PrepareResources));
        }
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
