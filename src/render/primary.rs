//! The primary-ray pass: a compute shader per camera that traces the brick grid, lights the hit (sun and sky,
//! or next-event estimation over the light pool), optionally accumulates frames, and writes the HDR view target.
//! Runs in Bevy's `Core3d` schedule after the (empty) main passes and before tonemapping.

use super::gpu_world::{GpuWorld, WorldLayout};
use super::{FramesRendered, GlowbrickShaders, Highlight, VoxelCamera, shader_defs};
use crate::lights::upload::{GpuLights, LightsLayout};
use crate::settings::{LightPick, LightSample, Lighting, RenderSettings, Reuse};
use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::binding_types::{
    storage_buffer_sized, texture_storage_2d, uniform_buffer, uniform_buffer_sized,
};
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::view::{ExtractedView, ViewTarget, ViewUniform, ViewUniformOffset, ViewUniforms};
use std::num::NonZeroU64;
use std::sync::atomic::Ordering;

/// Per-view, per-frame parameters (`FrameParams` in `shaders/primary.wgsl`).
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct FrameParams {
    /// Last frame's clip_from_world (temporal reprojection).
    pub prev_clip_from_world: [[f32; 4]; 4],
    /// Last frame's camera position; w = 1 when last frame's G-buffer and reservoirs may be reused.
    pub prev_camera: [f32; 4],
    pub sun: [f32; 4],
    pub sun_radiance: [f32; 4],
    pub sky_zenith: [f32; 4],
    pub sky_horizon: [f32; 4],
    pub debug_view: u32,
    pub shadows: u32,
    pub exposure: f32,
    /// Frame number, seeds the per-pixel random numbers.
    pub frame: u32,
    /// Targeted voxel (xyz) and face + 1 (w; 0 = none).
    pub target: [i32; 4],
    /// Box selection corners, inclusive; `selection_min.w` is 1 when a selection is shown.
    pub selection_min: [i32; 4],
    pub selection_max: [i32; 4],
    /// 0: sun and sky; 1: next-event estimation over the light pool.
    pub lighting: u32,
    /// 1: pick lights by power (alias table); 0: uniformly.
    pub power_pick: u32,
    pub light_count: u32,
    /// Frames averaged including this one; 1 restarts the average.
    pub accumulated: u32,
    /// Voxel ReSTIR: M_init, spatial taps, radius in pixels, `RESTIR_*` flags.
    pub candidates: u32,
    pub taps: u32,
    pub radius: f32,
    pub restir_flags: u32,
}

/// `restir_flags` bits (shaders/frame.wgsl).
const RESTIR_TEMPORAL: u32 = 1;
const RESTIR_SPATIAL: u32 = 2;
const RESTIR_POINT: u32 = 4;
const RESTIR_UNBIASED: u32 = 8;

impl FrameParams {
    pub fn new(settings: &RenderSettings, highlight: &Highlight, frame: u32) -> Self {
        let sun = Vec3::new(0.45, 0.8, 0.3).normalize();
        let restir = settings.restir.clone().clamped();
        let flag = |on: bool, bit: u32| if on { bit } else { 0 };
        FrameParams {
            prev_clip_from_world: Mat4::IDENTITY.to_cols_array_2d(),
            prev_camera: [0.0; 4],
            sun: [sun.x, sun.y, sun.z, if settings.sun { 1.0 } else { 0.0 }],
            sun_radiance: [1.1, 1.0, 0.9, 0.0],
            sky_zenith: [0.35, 0.55, 0.95, 0.0],
            sky_horizon: [0.75, 0.82, 0.9, 0.0],
            debug_view: settings.debug.shader_index(),
            shadows: settings.shadows as u32,
            exposure: settings.exposure,
            frame,
            target: highlight.target.map_or([0; 4], |(v, face)| [v.x, v.y, v.z, face as i32 + 1]),
            selection_min: highlight.selection.map_or([0; 4], |(a, _)| [a.x, a.y, a.z, 1]),
            selection_max: highlight.selection.map_or([0; 4], |(_, b)| [b.x, b.y, b.z, 1]),
            lighting: match settings.lighting {
                Lighting::Sun => 0,
                Lighting::Nee => 1,
                Lighting::Restir => 2,
            },
            power_pick: (settings.pick == LightPick::Power) as u32,
            light_count: 0,
            accumulated: 1,
            candidates: restir.candidates,
            taps: restir.taps,
            radius: restir.radius,
            restir_flags: flag(restir.temporal, RESTIR_TEMPORAL)
                | flag(restir.spatial, RESTIR_SPATIAL)
                | flag(restir.sample == LightSample::Point, RESTIR_POINT)
                | flag(restir.reuse == Reuse::Unbiased, RESTIR_UNBIASED),
        }
    }
}

/// The name the pass's GPU time is recorded under.
pub const PRIMARY_PASS_NAME: &str = "glowbrick_primary";

/// The pipeline and the per-view layout every voxel pass shares (group 1, `shaders/frame.wgsl`).
#[derive(Resource)]
pub struct PrimaryPipeline {
    pub view_layout: BindGroupLayoutDescriptor,
    pipeline: CachedComputePipelineId,
}

/// Bytes per pixel of the G-buffer and of a reservoir (`shaders/frame.wgsl`, `shaders/restir_common.wgsl`).
const GBUFFER_TEXEL_BYTES: u64 = 16;
pub const RESERVOIR_BYTES: u64 = 32;

/// A view's own buffers: frame parameters, the running sum of accumulated frames, this and last frame's
/// G-buffer, and the two reservoir buffers of Voxel ReSTIR.
#[derive(Component)]
pub struct PrimaryViewResources {
    frame_params: Buffer,
    accumulation: Buffer,
    gbuffer: Buffer,
    prev_gbuffer: Buffer,
    reservoirs_temporal: Buffer,
    reservoirs_final: Buffer,
    size: UVec2,
    /// What the average so far was rendered with; any difference restarts it.
    last_key: Option<AccumulationKey>,
    accumulated: u32,
    /// Last frame's camera, and whether it ran ReSTIR (its reservoirs are reusable).
    prev_clip_from_world: Mat4,
    prev_camera: Vec3,
    prev_restir: bool,
    /// Whether this frame runs the ReSTIR passes (set in prepare, read by the passes).
    pub run_restir: bool,
}

/// Everything that must stay the same for frames to be averaged.
#[derive(Clone, Debug, PartialEq)]
struct AccumulationKey {
    clip_from_world: Mat4,
    settings: RenderSettings,
    highlight: Highlight,
}

pub fn init_primary_pipeline(
    mut commands: Commands,
    pipeline_cache: Res<PipelineCache>,
    shaders: Res<GlowbrickShaders>,
    world_layout: Res<WorldLayout>,
    lights_layout: Res<LightsLayout>,
    gi_layout: Res<super::gi::GiLayout>,
) {
    let view_layout = BindGroupLayoutDescriptor::new(
        "glowbrick_primary_view_layout",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                texture_storage_2d(TextureFormat::Rgba16Float, StorageTextureAccess::WriteOnly),
                uniform_buffer::<ViewUniform>(true),
                uniform_buffer_sized(false, NonZeroU64::new(size_of::<FrameParams>() as u64)),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
            ),
        ),
    );
    let pipeline = pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
        label: Some("glowbrick_primary".into()),
        layout: vec![world_layout.0.clone(), view_layout.clone(), lights_layout.0.clone(), gi_layout.0.clone()],
        shader: shaders.primary.clone(),
        shader_defs: shader_defs(),
        entry_point: Some("main".into()),
        ..default()
    });
    commands.insert_resource(PrimaryPipeline { view_layout, pipeline });
}

/// The primary pipeline's compile error, if it failed (so headless callers fail fast instead of waiting).
pub fn pipeline_error(render_world: &World) -> Option<String> {
    let pipeline = render_world.get_resource::<PrimaryPipeline>()?;
    match render_world.resource::<PipelineCache>().get_compute_pipeline_state(pipeline.pipeline) {
        CachedPipelineState::Err(e) if !matches!(e, bevy::shader::ShaderCacheError::ShaderNotLoaded(_)) => {
            Some(format!("the primary-ray shader failed to compile: {e}"))
        }
        _ => None,
    }
}

/// Creates each view's buffers and writes its frame parameters, restarting accumulation when anything that
/// affects the image changed (Render schedule, PrepareResources, after the world and light uploads).
#[allow(clippy::too_many_arguments)]
pub fn prepare_view_resources(
    mut commands: Commands,
    mut views: Query<(Entity, &ExtractedView, Option<&mut PrimaryViewResources>), With<VoxelCamera>>,
    settings: Option<Res<RenderSettings>>,
    highlight: Option<Res<Highlight>>,
    gpu_world: Option<Res<GpuWorld>>,
    gpu_lights: Option<Res<GpuLights>>,
    objects: Option<Res<crate::dynamic::upload::GpuObjects>>,
    frames: Res<FramesRendered>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    let settings = settings.map(|s| s.clone()).unwrap_or_default();
    let highlight = highlight.map(|h| *h).unwrap_or_default();
    let scene_changed = gpu_world.as_ref().is_some_and(|w| w.uploaded_bytes > 0)
        || gpu_lights.as_ref().is_some_and(|l| l.changed)
        || objects.as_ref().is_some_and(|o| o.changed);
    let mut params = FrameParams::new(&settings, &highlight, frames.0.load(Ordering::Relaxed));
    params.light_count = gpu_lights.as_ref().map_or(0, |l| l.light_count);
    for (entity, view, resources) in &mut views {
        let size = view.viewport.zw();
        let clip_from_world = view.clip_from_view * view.world_from_view.to_matrix().inverse();
        let key = AccumulationKey { clip_from_world, settings: settings.clone(), highlight };
        let pixels = (size.x.max(1) * size.y.max(1)) as u64;
        let buffer = |device: &RenderDevice, label: &'static str, size: u64, usage: BufferUsages| {
            device.create_buffer(&BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let storage = BufferUsages::STORAGE;
        let fresh = |device: &RenderDevice| PrimaryViewResources {
            frame_params: buffer(
                device,
                "glowbrick_frame_params",
                size_of::<FrameParams>() as u64,
                BufferUsages::UNIFORM | BufferUsages::COPY_DST,
            ),
            accumulation: buffer(device, "glowbrick_accumulation", pixels * 16, storage),
            gbuffer: buffer(
                device,
                "glowbrick_gbuffer",
                pixels * GBUFFER_TEXEL_BYTES,
                storage | BufferUsages::COPY_SRC,
            ),
            prev_gbuffer: buffer(
                device,
                "glowbrick_prev_gbuffer",
                pixels * GBUFFER_TEXEL_BYTES,
                storage | BufferUsages::COPY_DST,
            ),
            reservoirs_temporal: buffer(device, "glowbrick_reservoirs_temporal", pixels * RESERVOIR_BYTES, storage),
            reservoirs_final: buffer(device, "glowbrick_reservoirs_final", pixels * RESERVOIR_BYTES, storage),
            size,
            last_key: None,
            accumulated: 0,
            prev_clip_from_world: Mat4::IDENTITY,
            prev_camera: Vec3::ZERO,
            prev_restir: false,
            run_restir: false,
        };
        let mut created = None;
        let resources: &mut PrimaryViewResources = match resources {
            Some(r) if r.size == size => r.into_inner(),
            _ => created.insert(fresh(&device)),
        };
        let same = settings.accumulate && !scene_changed && resources.last_key.as_ref() == Some(&key);
        resources.accumulated = if same { resources.accumulated.saturating_add(1) } else { 1 };
        resources.last_key = Some(key);
        params.accumulated = resources.accumulated;
        // ReSTIR runs only where it has something to sample; its history is valid if last frame ran it too.
        use crate::settings::DebugView;
        resources.run_restir = settings.lighting == Lighting::Restir
            && matches!(settings.debug, DebugView::None | DebugView::Reservoir)
            && params.light_count > 0;
        params.prev_clip_from_world = resources.prev_clip_from_world.to_cols_array_2d();
        let p = resources.prev_camera;
        params.prev_camera = [p.x, p.y, p.z, if resources.prev_restir && resources.run_restir { 1.0 } else { 0.0 }];
        resources.prev_clip_from_world = clip_from_world;
        resources.prev_camera = view.world_from_view.translation();
        resources.prev_restir = resources.run_restir;
        queue.write_buffer(&resources.frame_params, 0, bytemuck::bytes_of(&params));
        if let Some(new) = created {
            // A new or resized view: its buffers live on its render-world entity from now on.
            commands.entity(entity).insert(new);
        }
    }
}

/// Records one voxel compute pass over the view (8x8 workgroups) with the world, view, light and GI bind groups,
/// timed under `name` when render diagnostics are on.
pub fn dispatch_voxel_pass(
    encoder: &mut CommandEncoder,
    diagnostics: Option<&bevy::render::diagnostic::DiagnosticsRecorder>,
    name: &'static str,
    pipeline: &ComputePipeline,
    groups: [(&BindGroup, &[u32]); 4],
    size: Extent3d,
) {
    let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor { label: Some(name), timestamp_writes: None });
    let span = diagnostics.pass_span(&mut pass, name);
    pass.set_pipeline(pipeline);
    for (index, (group, offsets)) in groups.into_iter().enumerate() {
        pass.set_bind_group(index as u32, group, offsets);
    }
    pass.dispatch_workgroups(size.width.div_ceil(8), size.height.div_ceil(8), 1);
    span.end(&mut pass);
}

/// The per-view bind group (group 1) every voxel pass uses.
pub fn view_bind_group(
    ctx: &RenderContext,
    pipeline_cache: &PipelineCache,
    layout: &BindGroupLayoutDescriptor,
    target: &ViewTarget,
    view_binding: BindingResource,
    resources: &PrimaryViewResources,
) -> BindGroup {
    ctx.render_device().create_bind_group(
        "glowbrick_view",
        &pipeline_cache.get_bind_group_layout(layout),
        &BindGroupEntries::sequential((
            target.get_unsampled_color_attachment().view,
            view_binding,
            resources.frame_params.as_entire_binding(),
            resources.accumulation.as_entire_binding(),
            resources.gbuffer.as_entire_binding(),
            resources.prev_gbuffer.as_entire_binding(),
            resources.reservoirs_temporal.as_entire_binding(),
            resources.reservoirs_final.as_entire_binding(),
        )),
    )
}

/// Dispatches the primary-ray shader for the current camera.
#[allow(clippy::too_many_arguments)]
pub fn primary_pass(
    view: ViewQuery<(&ViewTarget, &ViewUniformOffset, &PrimaryViewResources), With<VoxelCamera>>,
    pipeline: Option<Res<PrimaryPipeline>>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    gpu_world: Option<Res<GpuWorld>>,
    gpu_lights: Option<Res<GpuLights>>,
    restir: Option<Res<super::restir::RestirPipelines>>,
    gi: Option<Res<super::gi::GiCache>>,
    frames: Res<FramesRendered>,
    mut ctx: RenderContext,
) {
    let (target, view_offset, resources) = view.into_inner();
    let (Some(pipeline), Some(gpu_world), Some(gpu_lights)) = (pipeline, gpu_world, gpu_lights) else { return };
    let Some(gi_group) = gi.as_ref().and_then(|g| g.bind_group.as_ref()) else { return };
    if resources.run_restir && !super::restir::ready(restir.as_deref(), &pipeline_cache) {
        return;
    }
    let Some(compute) = pipeline_cache.get_compute_pipeline(pipeline.pipeline) else { return };
    let Some(view_binding) = view_uniforms.uniforms.binding() else { return };
    let size = target.main_texture().size();
    let view_group = view_bind_group(&ctx, &pipeline_cache, &pipeline.view_layout, target, view_binding, resources);
    // Keep last frame's G-buffer for ReSTIR's temporal reprojection before this frame overwrites it (only
    // ReSTIR reads it, so other modes skip the copy).
    if resources.run_restir {
        ctx.command_encoder().copy_buffer_to_buffer(
            &resources.gbuffer,
            0,
            &resources.prev_gbuffer,
            0,
            resources.gbuffer.size(),
        );
    }
    let diagnostics = ctx.diagnostic_recorder();
    // GPU time under "render/glowbrick_primary/elapsed_gpu" when RenderDiagnosticsPlugin is on (the bench).
    let groups = [
        (&gpu_world.bind_group, &[][..]),
        (&view_group, &[view_offset.offset][..]),
        (&gpu_lights.bind_group, &[][..]),
        (gi_group, &[][..]),
    ];
    dispatch_voxel_pass(ctx.command_encoder(), diagnostics.as_deref(), PRIMARY_PASS_NAME, compute, groups, size);
    frames.0.fetch_add(1, Ordering::Relaxed);
}
