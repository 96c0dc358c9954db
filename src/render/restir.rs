//! Voxel ReSTIR direct lighting (seed 000, DESIGN.md "Voxel ReSTIR"): three compute passes per camera after the
//! primary pass has written the G-buffer: candidates + temporal reuse (`shaders/restir_initial.wgsl`), spatial
//! reuse (`restir_spatial.wgsl`) and shading (`restir_shade.wgsl`). They share the view's bind group with the
//! primary pass. None of them runs when the scene has no lights (or ReSTIR is not the lighting mode): the primary
//! pass then shows emission alone, and the skipped passes record no GPU time.

use super::gpu_world::{GpuWorld, WorldLayout};
use super::primary::{PrimaryPipeline, PrimaryViewResources, dispatch_voxel_pass, primary_pass, view_bind_group};
use super::{GlowbrickShaders, VoxelCamera, shader_defs};
use crate::lights::upload::{GpuLights, LightsLayout};
use bevy::prelude::*;
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderContext, ViewQuery};
use bevy::render::view::{ViewTarget, ViewUniformOffset, ViewUniforms};

/// GPU-time names of the three passes, in dispatch order.
pub const RESTIR_PASS_NAMES: [&str; 3] =
    ["glowbrick_restir_initial", "glowbrick_restir_spatial", "glowbrick_restir_shade"];

#[derive(Resource)]
pub struct RestirPipelines {
    passes: [CachedComputePipelineId; 3],
}

pub fn init_restir_pipelines(
    mut commands: Commands,
    pipeline_cache: Res<PipelineCache>,
    shaders: Res<GlowbrickShaders>,
    world_layout: Res<WorldLayout>,
    lights_layout: Res<LightsLayout>,
    gi_layout: Res<super::gi::GiLayout>,
    primary: Res<PrimaryPipeline>,
) {
    let queue = |name: &'static str, shader: &Handle<Shader>| {
        pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
            label: Some(name.into()),
            layout: vec![
                world_layout.0.clone(),
                primary.view_layout.clone(),
                lights_layout.0.clone(),
                gi_layout.0.clone(),
            ],
            shader: shader.clone(),
            shader_defs: shader_defs(),
            entry_point: Some("main".into()),
            ..default()
        })
    };
    let passes = [
        queue(RESTIR_PASS_NAMES[0], &shaders.restir_initial),
        queue(RESTIR_PASS_NAMES[1], &shaders.restir_spatial),
        queue(RESTIR_PASS_NAMES[2], &shaders.restir_shade),
    ];
    commands.insert_resource(RestirPipelines { passes });
}

/// Whether all three passes are compiled (until then a ReSTIR frame is not rendered, rather than half-rendered).
pub fn ready(pipelines: Option<&RestirPipelines>, cache: &PipelineCache) -> bool {
    pipelines.is_some_and(|p| p.passes.iter().all(|id| cache.get_compute_pipeline(*id).is_some()))
}

/// A ReSTIR pipeline's compile error, if one failed.
pub fn pipeline_error(render_world: &World) -> Option<String> {
    let pipelines = render_world.get_resource::<RestirPipelines>()?;
    super::compile_error(render_world, &pipelines.passes, &RESTIR_PASS_NAMES)
}

/// Dispatches the three ReSTIR passes for the current camera, after `primary_pass` wrote the G-buffer.
#[allow(clippy::too_many_arguments)]
pub fn restir_passes(
    view: ViewQuery<(&ViewTarget, &ViewUniformOffset, &PrimaryViewResources), With<VoxelCamera>>,
    primary: Option<Res<PrimaryPipeline>>,
    pipelines: Option<Res<RestirPipelines>>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    gpu_world: Option<Res<GpuWorld>>,
    gpu_lights: Option<Res<GpuLights>>,
    gi: Option<Res<super::gi::GiCache>>,
    mut ctx: RenderContext,
) {
    let (target, view_offset, resources) = view.into_inner();
    if !resources.run_restir {
        return;
    }
    let (Some(primary), Some(pipelines), Some(gpu_world), Some(gpu_lights)) =
        (primary, pipelines, gpu_world, gpu_lights)
    else {
        return;
    };
    let Some(gi_group) = gi.as_ref().and_then(|g| g.bind_group.as_ref()) else { return };
    let Some(computes) =
        pipelines.passes.iter().map(|id| pipeline_cache.get_compute_pipeline(*id)).collect::<Option<Vec<_>>>()
    else {
        return;
    };
    let Some(view_binding) = view_uniforms.uniforms.binding() else { return };
    let size = target.main_texture().size();
    let view_group = view_bind_group(&ctx, &pipeline_cache, &primary.view_layout, target, view_binding, resources);
    let diagnostics = ctx.diagnostic_recorder();
    let encoder = ctx.command_encoder();
    // Separate compute passes: each reads what the previous one wrote for other pixels.
    for (compute, name) in computes.into_iter().zip(RESTIR_PASS_NAMES) {
        let groups = [
            (&gpu_world.bind_group, &[][..]),
            (&view_group, &[view_offset.offset][..]),
            (&gpu_lights.bind_group, &[][..]),
            (gi_group, &[][..]),
        ];
        dispatch_voxel_pass(encoder, diagnostics.as_deref(), name, compute, groups, size);
    }
}

/// Orders the passes after the primary pass in the same schedule.
pub fn add_restir_passes(render_app: &mut SubApp) {
    use bevy::core_pipeline::{Core3d, Core3dSystems};
    render_app
        .add_systems(bevy::render::RenderStartup, init_restir_pipelines.after(super::primary::init_primary_pipeline))
        .add_systems(Core3d, restir_passes.after(primary_pass).in_set(Core3dSystems::MainPass));
}
