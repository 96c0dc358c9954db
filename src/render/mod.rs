//! The voxel renderer, a Bevy render plugin.
//!
//! - `scene/`: the GPU copy of what is traced and lit (world, lights and this frame's lighting, moving objects,
//!   counters): uploads in the main world's PostUpdate, buffers written in `RenderSystems::PrepareResources`.
//! - `gpu_types`: the CPU/GPU contract (every buffer struct, every shared constant as a shader def).
//! - `interface`: each bind group's bindings, declared once (the layouts follow; a CPU test checks the WGSL).
//! - `pass`: a compute pass as a row of a technique's table.
//! - `plan`: the frame plan, what this frame runs and what changed, which `frame` decides and the rest read.
//! - `frame`: the plan, the pipelines, and the passes in order, per camera (`view_frame`) and once per frame
//!   (`world_frame`); it owns no technique's state.
//! - one module per technique, each owning its passes, its buffers and when its history restarts: `primary`
//!   (the G-buffer), `restir` (Voxel ReSTIR direct light, the reservoirs), `denoise` (the denoiser's history),
//!   `gi/` (the per-voxel-face GI cache: tables, edit log, the schedule of restarts and warm-up), `upscale`
//!   (the lighting passes below the output's resolution, brought back to it).
//! - `view`: a camera's group 1, its frame parameters, and the `ViewPart` each technique implements.
//! - `shaders`: the embedded WGSL (`shaders/lib`, `shaders/restir`, `shaders/gi`, `shaders/denoise`).
//!
//! Bevy's tonemapping runs after the voxel passes.

pub mod adapter;
pub mod camera;
pub mod denoise;
pub mod frame;
pub mod gi;
pub mod gpu_types;
pub mod interface;
pub mod pass;
pub mod pass_key;
pub mod plan;
pub mod primary;
pub mod restir;
pub mod scene;
pub mod shaders;
pub mod upscale;
pub mod view;

pub use camera::VoxelCamera;

use crate::settings::RenderSettings;
use bevy::prelude::*;
use bevy::render::RenderApp;
use bevy::render::extract_component::ExtractComponentPlugin;
use bevy::render::extract_resource::{ExtractResource, ExtractResourcePlugin};
use std::sync::Arc;
use std::sync::atomic::AtomicU32;

/// What the primary pass outlines: the player's target voxel and face, and a pending box selection
/// (inclusive corners). Written by the game, read by the renderer.
#[derive(Resource, ExtractResource, Clone, Copy, Debug, Default, PartialEq)]
pub struct Highlight {
    pub target: Option<(IVec3, u8)>,
    pub selection: Option<(IVec3, IVec3)>,
}

/// Camera-frames the primary pass has dispatched: one per camera per frame, so two cameras count two a frame.
/// Shared by both worlds (headless capture waits on it).
#[derive(Resource, Clone, Default)]
pub struct CameraFramesRendered(pub Arc<AtomicU32>);

/// Adds the voxel renderer. Needs `VoxelWorld` and `RenderSettings` resources in the main world.
pub struct VoxelRenderPlugin;

impl Plugin for VoxelRenderPlugin {
    fn build(&self, app: &mut App) {
        let handles = shaders::GlowbrickShaders::load(&mut app.world_mut().resource_mut::<Assets<Shader>>());
        let frames = app.world().get_resource::<CameraFramesRendered>().cloned().unwrap_or_default();
        app.insert_resource(handles.clone())
            .insert_resource(frames.clone())
            .init_resource::<RenderSettings>()
            .init_resource::<Highlight>()
            .add_plugins((
                scene::ScenePlugin,
                ExtractComponentPlugin::<VoxelCamera>::default(),
                ExtractResourcePlugin::<RenderSettings>::default(),
                ExtractResourcePlugin::<Highlight>::default(),
                ExtractResourcePlugin::<upscale::RenderScaleInForce>::default(),
            ));
        let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
        render_app.insert_resource(handles).insert_resource(frames);
        gi::add(render_app);
        frame::add(render_app);
    }
}
