//! What the passes trace and light, on the GPU: the brick grid (`world`), the light pool and this frame's
//! lighting (`lights`), the moving objects (`objects`) and the counters every pass may add to (`counters`). The
//! only place that knows these buffers' layouts. Each module stages its upload in the main world (PostUpdate),
//! extracts it, and writes the GPU buffers in `RenderSystems::PrepareResources`, changed ranges only. The world's
//! and the lights' buffers go through one queue per buffer (`staging`), which merges the frames' uploads in order.
//!
//! Bind groups: group 0 (`world`: grid, materials, then the parts of `objects` and `counters`) and group 2
//! (`lights`) of every voxel pass.

pub mod counters;
pub mod lights;
pub mod objects;
pub mod staging;
pub mod world;

use bevy::prelude::*;
use bevy::render::render_resource::{Buffer, BufferInitDescriptor, BufferUsages};
use bevy::render::renderer::RenderDevice;
use bevy::render::{Render, RenderApp, RenderSystems};

/// A storage buffer initialised with `contents` that later frames can write (COPY_DST).
pub fn storage_buffer(device: &RenderDevice, label: &str, contents: &[u8]) -> Buffer {
    device.create_buffer_with_data(&BufferInitDescriptor {
        label: Some(label),
        contents,
        usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
    })
}

/// The scene's uploads, in the order the GPU copies depend on each other: lights (and this frame's lighting),
/// the world, then the objects (whose count lands in the world's uniform).
pub struct ScenePlugin;

/// Runs after every scene upload of the frame (the per-view and GI preparation order themselves after it).
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct SceneUploaded;

impl Plugin for ScenePlugin {
    fn build(&self, app: &mut App) {
        app.add_plugins((
            counters::CountersPlugin,
            lights::LightUploadPlugin,
            world::WorldUploadPlugin,
            objects::ObjectUploadPlugin,
        ));
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
        render_app.configure_sets(Render, SceneUploaded.in_set(RenderSystems::PrepareResources)).add_systems(
            Render,
            (
                lights::prepare_gpu_lights,
                world::prepare_gpu_world,
                objects::prepare_gpu_objects,
                world::write_object_count,
            )
                .chain()
                .before(SceneUploaded)
                .in_set(RenderSystems::PrepareResources),
        );
    }
}
