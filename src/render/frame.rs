//! The frame, in one place. Every voxel pass is a row of a table (`VoxelPass`: name, shader, entry point,
//! dispatch shape); two systems list the passes top to bottom:
//!
//! - `view_frame` (Core3d, main pass, once per camera): the G-buffer, then Voxel ReSTIR's three passes when it
//!   lights the view, then the denoiser's passes when it is on; the view's bind group is built once here and
//!   shared by every pass.
//! - `world_frame` (RenderGraph, before every camera, once per frame): the GI cache's passes, which keep a
//!   world-level cache and so must not run once per camera. The cameras' shading reads what they write this
//!   frame (a change of light or an edit shows in the frame it happens); the entries the cameras insert are
//!   updated first next frame.
//!
//! Bind groups: 0 the world (grid, materials, objects, counters; `scene::world`), 1 the view (`ViewResources`;
//! empty for world passes), 2 the lights and scene lighting (`scene::lights`), 3 the GI cache (`gi`).

use super::gi::{self, GiCache};
use super::gpu_types::{
    ACCUMULATION_TEXEL_BYTES, DENOISE_HISTORY, DENOISE_ON, DENOISE_TEXEL_BYTES, FrameParams, GBUFFER_TEXEL_BYTES,
    RESERVOIR_BYTES, RESTIR_LOCAL, RESTIR_ONE_RAY, RESTIR_POINT, RESTIR_SPATIAL, RESTIR_TEMPORAL, RESTIR_UNBIASED,
    shader_defs,
};
use super::scene::lights::{GpuLights, LightsLayout};
use super::scene::objects::GpuObjects;
use super::scene::world::{GpuWorld, WorldLayout};
use super::shaders::GlowbrickShaders;
use super::{FramesRendered, Highlight, VoxelCamera, denoise, primary, restir};
use crate::settings::{DebugView, LightSample, RenderSettings, Reuse, SEED_FRAMES};
use bevy::ecs::system::SystemParam;
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

/// One compute pass of the voxel renderer.
#[derive(Clone, Copy, Debug)]
pub struct VoxelPass {
    /// The name its GPU time is recorded under (`render/<name>/elapsed_gpu`).
    pub name: &'static str,
    /// Its shader, a path under `shaders/`.
    pub shader: &'static str,
    pub entry_point: &'static str,
    pub dispatch: Dispatch,
}

/// How a pass is dispatched, which also says which bind group 1 it gets.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Dispatch {
    /// One thread per pixel of the view, 8x8 workgroups; group 1 is the view.
    Pixels,
    /// One thread per slot of both GI tables, 64 per workgroup; no view.
    Slots,
    /// One thread per entry the GI compaction pass listed: the dispatch size is read from the GI work buffer at
    /// this byte offset; no view.
    Listed(u64),
}

/// Every pass, for pipeline creation and compile errors.
pub fn all_passes() -> Vec<VoxelPass> {
    let mut passes = vec![primary::PRIMARY];
    passes.extend(restir::PASSES);
    passes.extend(denoise::PASSES);
    passes.push(gi::COMPACT_PASS);
    passes.extend(gi::STATIC_PASSES);
    passes.extend(gi::DYNAMIC_PASSES);
    passes
}

/// Per-view, per-frame parameters for `view`'s shaders (`FrameParams`), before the view's own history fields.
pub fn frame_params(settings: &RenderSettings, highlight: &Highlight, frame: u32) -> FrameParams {
    let restir = settings.restir.clone().clamped();
    let flag = |on: bool, bit: u32| if on { bit } else { 0 };
    FrameParams {
        prev_clip_from_world: Mat4::IDENTITY.to_cols_array_2d(),
        prev_camera: [0.0; 4],
        debug_view: settings.debug.shader_index(),
        exposure: settings.exposure,
        frame: frame.wrapping_add(settings.seed.wrapping_mul(SEED_FRAMES)),
        accumulated: 1,
        highlight_target: highlight.target.map_or([0; 4], |(v, face)| [v.x, v.y, v.z, face as i32 + 1]),
        selection_min: highlight.selection.map_or([0; 4], |(a, _)| [a.x, a.y, a.z, 1]),
        selection_max: highlight.selection.map_or([0; 4], |(_, b)| [b.x, b.y, b.z, 1]),
        candidates: restir.candidates,
        taps: restir.taps,
        radius: restir.radius,
        restir_flags: flag(restir.temporal, RESTIR_TEMPORAL)
            | flag(restir.spatial, RESTIR_SPATIAL)
            | flag(restir.sample == LightSample::Point, RESTIR_POINT)
            | flag(restir.reuse == Reuse::Unbiased, RESTIR_UNBIASED)
            | flag(restir.reuse == Reuse::OneRay, RESTIR_ONE_RAY)
            | flag(restir.local_lights, RESTIR_LOCAL),
        denoise: 0,
        _pad: [0; 3],
    }
}

/// A view's own buffers: frame parameters, the running sum of accumulated frames, this and last frame's
/// G-buffer, the two reservoir buffers of Voxel ReSTIR, and the denoiser's noisy frame, history (this and last
/// frame's) and wavelet ping-pong.
#[derive(Component)]
pub struct ViewResources {
    frame_params: Buffer,
    accumulation: Buffer,
    gbuffer: Buffer,
    prev_gbuffer: Buffer,
    reservoirs_temporal: Buffer,
    reservoirs_final: Buffer,
    noisy: Buffer,
    history: Buffer,
    prev_history: Buffer,
    wavelet: Buffer,
    size: UVec2,
    /// What the average so far was rendered with; any difference restarts it.
    last_key: Option<AccumulationKey>,
    accumulated: u32,
    /// Last frame's camera, and whether it ran ReSTIR (its reservoirs are reusable).
    prev_clip_from_world: Mat4,
    prev_camera: Vec3,
    prev_restir: bool,
    /// Whether this frame runs the ReSTIR passes (set in prepare, read by the frame).
    pub run_restir: bool,
    /// Whether last frame ran the denoiser, and whether this one does.
    prev_denoise: bool,
    pub run_denoise: bool,
}

impl ViewResources {
    fn new(device: &RenderDevice, size: UVec2) -> Self {
        let pixels = (size.x.max(1) * size.y.max(1)) as u64;
        let buffer = |label: &'static str, size: u64, usage: BufferUsages| {
            device.create_buffer(&BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        let storage = BufferUsages::STORAGE;
        ViewResources {
            frame_params: buffer(
                "glowbrick_frame_params",
                size_of::<FrameParams>() as u64,
                BufferUsages::UNIFORM | BufferUsages::COPY_DST,
            ),
            accumulation: buffer("glowbrick_accumulation", pixels * ACCUMULATION_TEXEL_BYTES, storage),
            gbuffer: buffer("glowbrick_gbuffer", pixels * GBUFFER_TEXEL_BYTES, storage | BufferUsages::COPY_SRC),
            prev_gbuffer: buffer(
                "glowbrick_prev_gbuffer",
                pixels * GBUFFER_TEXEL_BYTES,
                storage | BufferUsages::COPY_DST,
            ),
            reservoirs_temporal: buffer("glowbrick_reservoirs_temporal", pixels * RESERVOIR_BYTES, storage),
            reservoirs_final: buffer("glowbrick_reservoirs_final", pixels * RESERVOIR_BYTES, storage),
            noisy: buffer("glowbrick_denoise_noisy", pixels * DENOISE_TEXEL_BYTES, storage),
            history: buffer(
                "glowbrick_denoise_history",
                2 * pixels * DENOISE_TEXEL_BYTES,
                storage | BufferUsages::COPY_SRC,
            ),
            prev_history: buffer(
                "glowbrick_denoise_prev_history",
                2 * pixels * DENOISE_TEXEL_BYTES,
                storage | BufferUsages::COPY_DST,
            ),
            wavelet: buffer("glowbrick_denoise_wavelet", 2 * pixels * DENOISE_TEXEL_BYTES, storage),
            size,
            last_key: None,
            accumulated: 0,
            prev_clip_from_world: Mat4::IDENTITY,
            prev_camera: Vec3::ZERO,
            prev_restir: false,
            run_restir: false,
            prev_denoise: false,
            run_denoise: false,
        }
    }
}

/// Everything that must stay the same for frames to be averaged.
#[derive(Clone, Debug, PartialEq)]
struct AccumulationKey {
    clip_from_world: Mat4,
    settings: RenderSettings,
    highlight: Highlight,
}

/// Creates each view's buffers and writes its frame parameters, restarting accumulation when anything that
/// affects the image changed (Render schedule, PrepareResources, after the scene uploads).
#[allow(clippy::too_many_arguments)]
pub fn prepare_view_resources(
    mut commands: Commands,
    mut views: Query<(Entity, &ExtractedView, Option<&mut ViewResources>), With<VoxelCamera>>,
    settings: Option<Res<RenderSettings>>,
    highlight: Option<Res<Highlight>>,
    gpu_world: Option<Res<GpuWorld>>,
    gpu_lights: Option<Res<GpuLights>>,
    objects: Option<Res<GpuObjects>>,
    frames: Res<FramesRendered>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    let settings = settings.map(|s| s.clone()).unwrap_or_default();
    let highlight = highlight.map(|h| *h).unwrap_or_default();
    let lights_changed = gpu_lights.as_ref().is_some_and(|l| l.changed);
    let scene_changed = gpu_world.as_ref().is_some_and(|w| w.uploaded_bytes > 0)
        || lights_changed
        || objects.as_ref().is_some_and(|o| o.changed);
    let light_count = gpu_lights.as_ref().map_or(0, |l| l.light_count);
    let mut params = frame_params(&settings, &highlight, frames.0.load(Ordering::Relaxed));
    // ReSTIR runs only where it has something to sample; its history is valid if last frame ran it too.
    let run_restir = settings.lighting.uses_restir()
        && (settings.debug.is_lit() || settings.debug == DebugView::Reservoir)
        && light_count > 0;
    let run_denoise = settings.denoise && settings.debug.is_lit();
    // The denoiser's history restarts where the image changed without the camera moving: an edit (geometry or
    // lights). Moving objects are left to the reprojection test (their pixels fail it).
    let world_changed = gpu_world.as_ref().is_some_and(|w| w.uploaded_bytes > 0) || lights_changed;
    for (entity, view, resources) in &mut views {
        let size = view.viewport.zw();
        let clip_from_world = view.clip_from_view * view.world_from_view.to_matrix().inverse();
        let key = AccumulationKey { clip_from_world, settings: settings.clone(), highlight };
        let mut created = None;
        let resources: &mut ViewResources = match resources {
            Some(r) if r.size == size => r.into_inner(),
            _ => created.insert(ViewResources::new(&device, size)),
        };
        let same = settings.accumulate && !scene_changed && resources.last_key.as_ref() == Some(&key);
        resources.accumulated = if same { resources.accumulated.saturating_add(1) } else { 1 };
        resources.last_key = Some(key);
        params.accumulated = resources.accumulated;
        resources.run_restir = run_restir;
        params.prev_clip_from_world = resources.prev_clip_from_world.to_cols_array_2d();
        let p = resources.prev_camera;
        // A frame whose light pool changed starts ReSTIR's history afresh: last frame's reservoirs were drawn
        // from other lights, and the temporal MIS weights, which assume last frame could have drawn this
        // frame's samples, would weigh a lamp placed now at M_init / (M_init + history) of its light
        // (measured in tests/gpu/daylight.rs: a lamp placed at night lit 41 of its 340 pixels in its first frame;
        // with the history restarted, 391 of 499).
        let history = resources.prev_restir && run_restir && !lights_changed;
        params.prev_camera = [p.x, p.y, p.z, if history { 1.0 } else { 0.0 }];
        resources.prev_clip_from_world = clip_from_world;
        resources.prev_camera = view.world_from_view.translation();
        resources.prev_restir = run_restir;
        let denoise_history = resources.prev_denoise && run_denoise && !world_changed;
        params.denoise = if run_denoise { DENOISE_ON } else { 0 } | if denoise_history { DENOISE_HISTORY } else { 0 };
        resources.prev_denoise = run_denoise;
        resources.run_denoise = run_denoise;
        queue.write_buffer(&resources.frame_params, 0, bytemuck::bytes_of(&params));
        if let Some(new) = created {
            // A new or resized view: its buffers live on its render-world entity from now on.
            commands.entity(entity).insert(new);
        }
    }
}

/// Layouts of group 1: the view's (`shaders/lib/frame.wgsl`) and the empty one world passes bind instead.
#[derive(Resource)]
pub struct ViewLayouts {
    pub view: BindGroupLayoutDescriptor,
    pub empty: BindGroupLayoutDescriptor,
}

fn view_layouts() -> ViewLayouts {
    let view = BindGroupLayoutDescriptor::new(
        "glowbrick_view_layout",
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
                // The denoiser: noisy frame, history, last frame's history, wavelet ping-pong.
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
            ),
        ),
    );
    ViewLayouts { view, empty: BindGroupLayoutDescriptor::new("glowbrick_no_view_layout", &[]) }
}

/// Every pass's pipeline, in `all_passes` order, and the empty group 1 of world passes.
#[derive(Resource)]
pub struct VoxelPipelines {
    passes: Vec<(VoxelPass, CachedComputePipelineId)>,
    no_view: BindGroup,
}

impl VoxelPipelines {
    /// The compiled pipelines of `passes`, or `None` until all of them are ready.
    fn get<'a>(&self, cache: &'a PipelineCache, passes: &[VoxelPass]) -> Option<Vec<&'a ComputePipeline>> {
        passes
            .iter()
            .map(|pass| {
                let (_, id) = self.passes.iter().find(|(p, _)| p.name == pass.name)?;
                cache.get_compute_pipeline(*id)
            })
            .collect()
    }
}

fn init_pipelines(
    mut commands: Commands,
    pipeline_cache: Res<PipelineCache>,
    device: Res<RenderDevice>,
    shaders: Res<GlowbrickShaders>,
    world_layout: Res<WorldLayout>,
    lights_layout: Res<LightsLayout>,
    gi_layout: Res<gi::GiLayout>,
) {
    let layouts = view_layouts();
    let passes = all_passes()
        .into_iter()
        .map(|pass| {
            let group1 = if pass.dispatch == Dispatch::Pixels { &layouts.view } else { &layouts.empty };
            let id = pipeline_cache.queue_compute_pipeline(ComputePipelineDescriptor {
                label: Some(pass.name.into()),
                layout: vec![world_layout.0.clone(), group1.clone(), lights_layout.0.clone(), gi_layout.0.clone()],
                shader: shaders.get(pass.shader),
                shader_defs: shader_defs(),
                entry_point: Some(pass.entry_point.into()),
                ..default()
            });
            (pass, id)
        })
        .collect();
    let no_view =
        device.create_bind_group("glowbrick_no_view", &pipeline_cache.get_bind_group_layout(&layouts.empty), &[]);
    commands.insert_resource(VoxelPipelines { passes, no_view });
    commands.insert_resource(layouts);
}

/// The first pass whose shader failed to compile, as one message (a shader not loaded yet is not a failure), so
/// headless callers fail fast instead of waiting.
pub fn pipeline_error(render_world: &World) -> Option<String> {
    let pipelines = render_world.get_resource::<VoxelPipelines>()?;
    let cache = render_world.resource::<PipelineCache>();
    pipelines.passes.iter().find_map(|(pass, id)| match cache.get_compute_pipeline_state(*id) {
        CachedPipelineState::Err(e) if !matches!(e, bevy::shader::ShaderCacheError::ShaderNotLoaded(_)) => {
            Some(format!("the {} shader ({}) failed to compile: {e}", pass.name, pass.shader))
        }
        _ => None,
    })
}

/// The bind groups every voxel pass shares: world (0), lights (2) and GI cache (3).
#[derive(SystemParam)]
pub struct SceneBindGroups<'w> {
    world: Option<Res<'w, GpuWorld>>,
    lights: Option<Res<'w, GpuLights>>,
    gi: Option<Res<'w, GiCache>>,
}

/// The passes' encoder, timing and bind groups, for dispatching one pass after another.
struct PassRecorder<'a> {
    encoder: &'a mut CommandEncoder,
    diagnostics: Option<&'a bevy::render::diagnostic::DiagnosticsRecorder>,
    groups: [(&'a BindGroup, &'a [u32]); 4],
    /// The GI cache's slot count and dispatch sizes, for its passes (None in a camera's frame).
    gi_work: Option<(u32, &'a Buffer)>,
}

impl PassRecorder<'_> {
    /// Records `pass` as its own compute pass (each reads what the previous one wrote for other threads), timed
    /// under its name when render diagnostics are on.
    fn dispatch(&mut self, pass: &VoxelPass, pipeline: &ComputePipeline, view_size: Extent3d) {
        let label = Some(pass.name);
        let mut compute = self.encoder.begin_compute_pass(&ComputePassDescriptor { label, timestamp_writes: None });
        let span = self.diagnostics.pass_span(&mut compute, pass.name);
        compute.set_pipeline(pipeline);
        for (index, (group, offsets)) in self.groups.iter().enumerate() {
            compute.set_bind_group(index as u32, *group, offsets);
        }
        match pass.dispatch {
            Dispatch::Pixels => {
                compute.dispatch_workgroups(view_size.width.div_ceil(8), view_size.height.div_ceil(8), 1)
            }
            Dispatch::Slots => {
                let (slots, _) = self.gi_work.expect("GI passes are recorded with the cache's work");
                compute.dispatch_workgroups(slots.div_ceil(64), 1, 1)
            }
            Dispatch::Listed(offset) => {
                let (_, work) = self.gi_work.expect("GI passes are recorded with the cache's work");
                compute.dispatch_workgroups_indirect(work, offset)
            }
        }
        span.end(&mut compute);
    }
}

/// One camera's frame, top to bottom.
#[allow(clippy::too_many_arguments)]
pub fn view_frame(
    view: ViewQuery<(&ViewTarget, &ViewUniformOffset, &ViewResources), With<VoxelCamera>>,
    pipelines: Option<Res<VoxelPipelines>>,
    layouts: Option<Res<ViewLayouts>>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    scene: SceneBindGroups,
    frames: Res<FramesRendered>,
    mut ctx: RenderContext,
) {
    let (target, view_offset, resources) = view.into_inner();
    let (Some(pipelines), Some(layouts), Some(world), Some(lights)) = (pipelines, layouts, scene.world, scene.lights)
    else {
        return;
    };
    let Some(gi_group) = scene.gi.as_ref().and_then(|g| g.bind_group.as_ref()) else { return };
    let Some(primary_pipeline) = pipelines.get(&pipeline_cache, &[primary::PRIMARY]).map(|p| p[0]) else { return };
    // A ReSTIR frame waits until all its passes compiled rather than showing half a frame.
    let restir = match resources.run_restir {
        true => match pipelines.get(&pipeline_cache, &restir::PASSES) {
            Some(restir) => Some(restir),
            None => return,
        },
        false => None,
    };
    let denoise = match resources.run_denoise {
        true => match pipelines.get(&pipeline_cache, &denoise::PASSES) {
            Some(denoise) => Some(denoise),
            None => return,
        },
        false => None,
    };
    let Some(view_binding) = view_uniforms.uniforms.binding() else { return };
    let size = target.main_texture().size();
    let view_group = ctx.render_device().create_bind_group(
        "glowbrick_view",
        &pipeline_cache.get_bind_group_layout(&layouts.view),
        &BindGroupEntries::sequential((
            target.get_unsampled_color_attachment().view,
            view_binding,
            resources.frame_params.as_entire_binding(),
            resources.accumulation.as_entire_binding(),
            resources.gbuffer.as_entire_binding(),
            resources.prev_gbuffer.as_entire_binding(),
            resources.reservoirs_temporal.as_entire_binding(),
            resources.reservoirs_final.as_entire_binding(),
            resources.noisy.as_entire_binding(),
            resources.history.as_entire_binding(),
            resources.prev_history.as_entire_binding(),
            resources.wavelet.as_entire_binding(),
        )),
    );
    let diagnostics = ctx.diagnostic_recorder();
    let encoder = ctx.command_encoder();
    // Keep last frame's G-buffer for the temporal reprojections (ReSTIR's and the denoiser's) before this frame
    // overwrites it, and the denoiser's history likewise; other modes skip the copies.
    if restir.is_some() || denoise.is_some() {
        encoder.copy_buffer_to_buffer(&resources.gbuffer, 0, &resources.prev_gbuffer, 0, resources.gbuffer.size());
    }
    if denoise.is_some() {
        let history = &resources.history;
        encoder.copy_buffer_to_buffer(history, 0, &resources.prev_history, 0, history.size());
    }
    let mut recorder = PassRecorder {
        encoder,
        diagnostics: diagnostics.as_deref(),
        groups: [
            (&world.bind_group, &[]),
            (&view_group, &[view_offset.offset]),
            (&lights.bind_group, &[]),
            (gi_group, &[]),
        ],
        gi_work: None,
    };
    // 1. G-buffer, GI cache entries touched; the image too unless ReSTIR shades it.
    recorder.dispatch(&primary::PRIMARY, primary_pipeline, size);
    // 2-4. Voxel ReSTIR: candidates + temporal reuse, spatial reuse, shading.
    if let Some(restir_pipelines) = restir {
        for (pass, pipeline) in restir::PASSES.iter().zip(restir_pipelines) {
            recorder.dispatch(pass, pipeline, size);
        }
    }
    // 5-9. The denoiser: temporal accumulation, then the wavelet's iterations, the last writing the image.
    if let Some(denoise_pipelines) = denoise {
        for (pass, pipeline) in denoise::PASSES.iter().zip(denoise_pipelines) {
            recorder.dispatch(pass, pipeline, size);
        }
    }
    frames.0.fetch_add(1, Ordering::Relaxed);
}

/// The world-level frame, once before every camera (whose shading then reads this frame's light): the GI cache
/// (work lists, refresh, updates, filters; the moving objects' table only while objects exist).
pub fn world_frame(
    pipelines: Option<Res<VoxelPipelines>>,
    pipeline_cache: Res<PipelineCache>,
    scene: SceneBindGroups,
    objects: Option<Res<GpuObjects>>,
    mut ctx: RenderContext,
) {
    let (Some(pipelines), Some(world), Some(lights), Some(cache)) = (pipelines, scene.world, scene.lights, scene.gi)
    else {
        return;
    };
    let Some(gi_group) = cache.bind_group.as_ref().filter(|_| cache.enabled) else { return };
    let Some(compact) = pipelines.get(&pipeline_cache, &[gi::COMPACT_PASS]) else { return };
    let Some(statics) = pipelines.get(&pipeline_cache, &gi::STATIC_PASSES) else { return };
    let Some(dynamics) = pipelines.get(&pipeline_cache, &gi::DYNAMIC_PASSES) else { return };
    let with_objects = objects.is_some_and(|o| o.count > 0);
    let diagnostics = ctx.diagnostic_recorder();
    let mut recorder = PassRecorder {
        encoder: ctx.command_encoder(),
        diagnostics: diagnostics.as_deref(),
        groups: [(&world.bind_group, &[]), (&pipelines.no_view, &[]), (&lights.bind_group, &[]), (gi_group, &[])],
        gi_work: Some((cache.slots(), cache.arguments())),
    };
    let no_view = Extent3d::default();
    let [refresh, update_static, filter_static] = &gi::STATIC_PASSES;
    let [update_dynamic, filter_dynamic] = &gi::DYNAMIC_PASSES;
    // The work lists first; refresh before update, updates before filters (a filter reads its neighbours' new
    // values).
    recorder.dispatch(&gi::COMPACT_PASS, compact[0], no_view);
    cache.publish_work(recorder.encoder);
    recorder.dispatch(refresh, statics[0], no_view);
    // After a change of light, several iterations: each one bounce more of the new light.
    for iteration in 0..cache.iterations() {
        if iteration > 0 {
            cache.set_iteration(recorder.encoder, iteration);
        }
        recorder.dispatch(update_static, statics[1], no_view);
        if with_objects {
            recorder.dispatch(update_dynamic, dynamics[0], no_view);
        }
        recorder.dispatch(filter_static, statics[2], no_view);
        if with_objects {
            recorder.dispatch(filter_dynamic, dynamics[1], no_view);
        }
    }
}

/// Adds the pipelines, the view preparation and the two frame systems to the render app.
pub fn add(render_app: &mut SubApp) {
    use super::scene::SceneUploaded;
    use bevy::core_pipeline::core_3d::main_transparent_pass_3d;
    use bevy::core_pipeline::schedule::camera_driver;
    use bevy::core_pipeline::{Core3d, Core3dSystems};
    use bevy::render::renderer::{RenderGraph, RenderGraphSystems};
    use bevy::render::{Render, RenderStartup, RenderSystems};
    render_app
        .add_systems(RenderStartup, init_pipelines)
        .add_systems(Render, prepare_view_resources.after(SceneUploaded).in_set(RenderSystems::PrepareResources))
        .add_systems(Core3d, view_frame.after(main_transparent_pass_3d).in_set(Core3dSystems::MainPass))
        .add_systems(RenderGraph, world_frame.before(camera_driver).in_set(RenderGraphSystems::Render));
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::scene::lights::scene_lighting;

    /// The named choices reach the GPU as the bits the shaders test.
    #[test]
    fn named_choices_reach_the_gpu_as_flag_bits() {
        let settings = |pairs: &[&str]| {
            RenderSettings::default().with_pairs(&pairs.iter().map(|p| p.to_string()).collect::<Vec<_>>()).unwrap()
        };
        let default = settings(&[]);
        let params = frame_params(&default, &Highlight::default(), 0);
        // Default: temporal, spatial, one ray per neighbour, local candidates.
        assert_eq!((scene_lighting(&default, 3).power_pick, params.restir_flags), (1, 1 | 2 | 16 | 32));
        assert_eq!(frame_params(&settings(&["reuse=biased"]), &Highlight::default(), 0).restir_flags, 1 | 2 | 32);
        let changed = settings(&["pick=uniform", "sample=point", "reuse=unbiased", "temporal=off", "local_lights=off"]);
        let params = frame_params(&changed, &Highlight::default(), 0);
        assert_eq!((scene_lighting(&changed, 3).power_pick, params.restir_flags), (0, 2 | 4 | 8));
        assert_eq!(scene_lighting(&changed, 3).light_count, 3);
    }
}
