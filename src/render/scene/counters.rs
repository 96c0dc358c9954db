//! The counters buffer every pass may add to (`GpuCounter` names them; `shaders/lib/counters.wgsl`), bound in
//! group 0. An asset of the main world, so tests, the bench and the stress run can read it back.

use crate::render::gpu_types::{COUNTERS, PER_FRAME_COUNTERS};
use crate::render::interface::GpuBinding;
use bevy::prelude::*;
use bevy::render::extract_resource::{ExtractResource, ExtractResourcePlugin};
use bevy::render::render_asset::RenderAssets;
use bevy::render::renderer::RenderQueue;
use bevy::render::storage::{GpuShaderBuffer, ShaderBuffer};
use bevy::render::{Render, RenderApp, RenderSystems};

/// Group 0's counters part (`shaders/lib/counters.wgsl`).
pub const COUNTER_BINDINGS: [GpuBinding; 1] = [GpuBinding::read_write("counters")];

/// The counters buffer's handle, in both worlds.
#[derive(Resource, ExtractResource, Clone)]
pub struct GpuCountersBuffer(pub Handle<ShaderBuffer>);

/// The counters buffer and its per-frame restart.
pub struct CountersPlugin;

impl Plugin for CountersPlugin {
    fn build(&self, app: &mut App) {
        add(app);
    }
}

fn add(app: &mut App) {
    let buffer = ShaderBuffer::new(&[0u8; COUNTERS * 4], bevy::asset::RenderAssetUsages::default());
    let handle = app.world_mut().resource_mut::<Assets<ShaderBuffer>>().add(buffer);
    app.insert_resource(GpuCountersBuffer(handle)).add_plugins(ExtractResourcePlugin::<GpuCountersBuffer>::default());
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
    render_app.add_systems(Render, restart_per_frame_counters.in_set(RenderSystems::PrepareResources));
}

/// Zeroes the counters that count per frame (the others count since the start).
fn restart_per_frame_counters(
    counters: Option<Res<GpuCountersBuffer>>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    queue: Res<RenderQueue>,
) {
    if let Some(buffer) = counters.and_then(|c| buffers.get(&c.0)) {
        queue.write_buffer(&buffer.buffer, 0, &[0u8; PER_FRAME_COUNTERS * 4]);
    }
}
