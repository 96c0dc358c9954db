//! The render plugin: GPU copy of the world, and the voxel passes as systems in Bevy's `Core3d` schedule.
//!
//! The frame, in order:
//! 1. main world, PostUpdate: `upload::stage_world_upload` turns the world's dirty bricks into an upload;
//! 2. extract: `upload::extract_world_upload` copies it to the render world;
//! 3. Render / PrepareResources: `gpu_world::prepare_gpu_world` writes it to GPU buffers,
//!    `primary::prepare_view_resources` writes each view's parameters and restarts accumulation on change;
//! 4. Core3d / MainPass, per camera with `VoxelCamera`: `primary::primary_pass` (G-buffer, and the image unless
//!    ReSTIR shades it; it also inserts the GI cache entries it sees), then `restir::restir_passes` (candidates +
//!    temporal, spatial, shade), then `gi::gi_passes` (cache update and filter, read by next frame's shading);
//!    then Bevy's tonemapping.

pub mod camera;
pub mod gi;
pub mod gpu_world;
pub mod primary;
pub mod restir;
pub mod upload;

pub use camera::{VoxelCamera, camera_ray};

use crate::settings::RenderSettings;
use crate::world::grid::{BRICK_SIZE, BRICK_VOXELS, POOLED_FLAG};
use bevy::core_pipeline::core_3d::main_transparent_pass_3d;
use bevy::core_pipeline::{Core3d, Core3dSystems};
use bevy::prelude::*;
use bevy::render::extract_component::ExtractComponentPlugin;
use bevy::render::extract_resource::{ExtractResource, ExtractResourcePlugin};
use bevy::render::{ExtractSchedule, Render, RenderApp, RenderStartup, RenderSystems};
use bevy::shader::{Shader, ShaderDefVal};
use std::sync::Arc;
use std::sync::atomic::AtomicU32;

/// Handles of the embedded WGSL (the files in the top-level `shaders/` folder, compiled into the binary).
#[derive(Resource, Clone)]
pub struct GlowbrickShaders {
    pub world: Handle<Shader>,
    pub traversal: Handle<Shader>,
    pub lights: Handle<Shader>,
    pub frame: Handle<Shader>,
    pub primary: Handle<Shader>,
    pub restir_common: Handle<Shader>,
    pub restir_initial: Handle<Shader>,
    pub restir_spatial: Handle<Shader>,
    pub restir_shade: Handle<Shader>,
    pub gi: Handle<Shader>,
    pub gi_refresh: Handle<Shader>,
    pub gi_update: Handle<Shader>,
    pub gi_filter: Handle<Shader>,
}

/// What the primary pass outlines: the player's target voxel and face, and a pending box selection
/// (inclusive corners). Written by the game, read by the renderer.
#[derive(Resource, ExtractResource, Clone, Copy, Debug, Default, PartialEq)]
pub struct Highlight {
    pub target: Option<(IVec3, u8)>,
    pub selection: Option<(IVec3, IVec3)>,
}

/// Frames the primary pass has dispatched, shared by both worlds (headless capture waits on it).
#[derive(Resource, Clone, Default)]
pub struct FramesRendered(pub Arc<AtomicU32>);

/// Constants the WGSL shares with Rust, passed as shader defs so there is one source of truth.
pub fn shader_defs() -> Vec<ShaderDefVal> {
    vec![
        ShaderDefVal::UInt("POOLED_FLAG".into(), POOLED_FLAG),
        ShaderDefVal::Int("BRICK_SIZE".into(), BRICK_SIZE),
        ShaderDefVal::UInt("BRICK_WORDS".into(), (BRICK_VOXELS / 2) as u32),
    ]
}

/// The first of `ids` (named by `names`) that failed to compile, as one message (a shader not loaded yet is not
/// a failure).
pub fn compile_error(
    render_world: &bevy::ecs::world::World,
    ids: &[bevy::render::render_resource::CachedComputePipelineId],
    names: &[&str],
) -> Option<String> {
    use bevy::render::render_resource::{CachedPipelineState, PipelineCache};
    let cache = render_world.resource::<PipelineCache>();
    ids.iter().zip(names).find_map(|(id, name)| match cache.get_compute_pipeline_state(*id) {
        CachedPipelineState::Err(e) if !matches!(e, bevy::shader::ShaderCacheError::ShaderNotLoaded(_)) => {
            Some(format!("the {name} shader failed to compile: {e}"))
        }
        _ => None,
    })
}

/// Adds the voxel renderer. Needs `VoxelWorld` and `RenderSettings` resources in the main world.
pub struct VoxelRenderPlugin;

impl Plugin for VoxelRenderPlugin {
    fn build(&self, app: &mut App) {
        let mut shaders = app.world_mut().resource_mut::<Assets<Shader>>();
        let mut add = |source: &'static str, path: &str| shaders.add(Shader::from_wgsl(source, path.to_string()));
        let handles = GlowbrickShaders {
            world: add(include_str!("../../shaders/world.wgsl"), "glowbrick/world.wgsl"),
            traversal: add(include_str!("../../shaders/traversal.wgsl"), "glowbrick/traversal.wgsl"),
            lights: add(include_str!("../../shaders/lights.wgsl"), "glowbrick/lights.wgsl"),
            frame: add(include_str!("../../shaders/frame.wgsl"), "glowbrick/frame.wgsl"),
            primary: add(include_str!("../../shaders/primary.wgsl"), "glowbrick/primary.wgsl"),
            restir_common: add(include_str!("../../shaders/restir_common.wgsl"), "glowbrick/restir_common.wgsl"),
            restir_initial: add(include_str!("../../shaders/restir_initial.wgsl"), "glowbrick/restir_initial.wgsl"),
            restir_spatial: add(include_str!("../../shaders/restir_spatial.wgsl"), "glowbrick/restir_spatial.wgsl"),
            restir_shade: add(include_str!("../../shaders/restir_shade.wgsl"), "glowbrick/restir_shade.wgsl"),
            gi: add(include_str!("../../shaders/gi.wgsl"), "glowbrick/gi.wgsl"),
            gi_refresh: add(include_str!("../../shaders/gi_refresh.wgsl"), "glowbrick/gi_refresh.wgsl"),
            gi_update: add(include_str!("../../shaders/gi_update.wgsl"), "glowbrick/gi_update.wgsl"),
            gi_filter: add(include_str!("../../shaders/gi_filter.wgsl"), "glowbrick/gi_filter.wgsl"),
        };
        let counters =
            app.world_mut().resource_mut::<Assets<bevy::render::storage::ShaderBuffer>>().add(gi::counters_asset());
        let frames = app.world().get_resource::<FramesRendered>().cloned().unwrap_or_default();
        app.insert_resource(handles.clone())
            .insert_resource(frames.clone())
            .init_resource::<RenderSettings>()
            .init_resource::<Highlight>()
            .insert_resource(gi::GiCountersBuffer(counters))
            .init_resource::<upload::UploadState>()
            .init_resource::<upload::WorldUpload>()
            .add_plugins((
                ExtractComponentPlugin::<VoxelCamera>::default(),
                ExtractResourcePlugin::<RenderSettings>::default(),
                ExtractResourcePlugin::<Highlight>::default(),
                ExtractResourcePlugin::<gi::GiCountersBuffer>::default(),
            ))
            .add_systems(PostUpdate, upload::stage_world_upload.run_if(resource_exists::<crate::world::VoxelWorld>));

        let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
        render_app
            .insert_resource(handles)
            .insert_resource(frames)
            .insert_resource(gpu_world::WorldLayout(gpu_world::world_bind_group_layout()))
            .init_resource::<upload::PendingUploads>()
            .add_systems(RenderStartup, primary::init_primary_pipeline)
            .add_systems(ExtractSchedule, upload::extract_world_upload)
            .add_systems(
                Render,
                (gpu_world::prepare_gpu_world, primary::prepare_view_resources)
                    .chain()
                    .after(crate::lights::upload::prepare_gpu_lights)
                    .in_set(RenderSystems::PrepareResources),
            )
            .add_systems(Core3d, primary::primary_pass.after(main_transparent_pass_3d).in_set(Core3dSystems::MainPass));
        gi::add_gi(render_app);
        restir::add_restir_passes(render_app);
    }
}
