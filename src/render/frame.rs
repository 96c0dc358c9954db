//! The frame, in one place. Every voxel pass is a row of a technique's table (`pass::VoxelPass`); each frame
//! `plan_frame` decides the frame plan (`plan::FramePlan`: which passes run, whether they are compiled, what
//! changed), and two systems list the passes top to bottom:
//!
//! - `view_frame` (Core3d, main pass, once per camera): the G-buffer, then Voxel ReSTIR's passes (light tiles,
//!   candidates, temporal, spatial, shade) as the plan says, then the denoiser's six when it is on; below render
//!   scale 1 the upscaler's `pick` follows the G-buffer and its last pass writes the image (`upscale`). The
//!   G-buffer and the upscaler run at the output's pixels, the rest at the plan's render size. The view's bind
//!   group is built once here and shared by every pass.
//! - `world_frame` (RenderGraph, before every camera, once per frame): the GI cache's passes, which keep a
//!   world-level cache and so must not run once per camera. The cameras' shading reads what they write this
//!   frame (a change of light or an edit shows in the frame it happens); the entries the cameras insert are
//!   updated first next frame.
//!
//! Bind groups (each declared once, `interface`): 0 the world (grid, materials, objects, counters;
//! `scene::world`), 1 the view (`view`, then the techniques' parts listed by `view_parts`; empty for world
//! passes), 2 the lights and scene lighting (`scene::lights`), 3 the GI cache (`gi`).

use super::gi::{self, GiCache};
use super::gpu_types::{ONE_POOL_PART, shader_defs};
use super::interface::GroupInterface;
use super::pass::{Dispatch, LINEAR_WORKGROUP, PIXEL_WORKGROUP_EDGE, VoxelPass};
use super::pass_key::PassKey;
use super::plan::{FramePlan, FramePlanned, RestirPasses, SceneChanges};
use super::scene::SceneUploaded;
use super::scene::lights::{GpuLights, LightsLayout, lights_interface};
use super::scene::objects::GpuObjects;
use super::scene::world::{GpuWorld, WorldLayout, world_interface};
use super::shaders::GlowbrickShaders;
use super::upscale::{self, RenderScaleInForce};
use super::view::{ViewParts, ViewResources, view_interface};
use super::{CameraFramesRendered, VoxelCamera, denoise, primary, restir};
use crate::settings::{RenderSettings, Traversal};
use bevy::ecs::system::SystemParam;
use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderAdapterInfo, RenderContext, RenderDevice, ViewQuery};
use bevy::render::view::{ViewTarget, ViewUniformOffset, ViewUniforms};
use std::collections::HashMap;
use std::sync::atomic::Ordering;

/// The techniques' parts of a view's group 1, in binding order.
fn view_parts() -> ViewParts {
    ViewParts(vec![primary::VIEW_PART, restir::VIEW_PART, denoise::VIEW_PART, upscale::VIEW_PART])
}

/// Every bind group's interface, groups 0 to 3: the layouts are built from these, and a CPU test checks the
/// shaders against them.
pub fn bind_groups() -> [GroupInterface; 4] {
    [world_interface(), view_interface(&view_parts()), lights_interface(), gi::gi_interface()]
}

/// Every pass, for pipeline creation and compile errors.
pub fn all_passes() -> Vec<VoxelPass> {
    let mut passes = vec![primary::PRIMARY];
    passes.extend(restir::PASSES);
    passes.extend(denoise::PASSES);
    passes.extend(upscale::PASSES);
    passes.push(gi::COMPACT_PASS);
    passes.extend(gi::STATIC_PASSES);
    passes.extend(gi::DYNAMIC_PASSES);
    passes
}

/// Layouts of group 1: the view's (`shaders/lib/frame.wgsl`) and the empty one world passes bind instead.
#[derive(Resource)]
pub struct ViewLayouts {
    /// Group 1's declaration, made once (the view's bind groups are built from it).
    pub interface: GroupInterface,
    pub view: BindGroupLayoutDescriptor,
    pub empty: BindGroupLayoutDescriptor,
}

fn view_layouts(parts: &ViewParts) -> ViewLayouts {
    let empty = BindGroupLayoutDescriptor::new("glowbrick_no_view_layout", &[]);
    let interface = view_interface(parts);
    ViewLayouts { view: interface.layout(), interface, empty }
}

/// Every pass's pipeline, in `all_passes` order, for each `PassKey` (the walk and the settings the shaders
/// branch on) a frame has asked for, each set queued the first time; and the empty group 1 of world passes. Sets
/// are kept, so a setting toggled back costs nothing.
#[derive(Resource)]
pub struct VoxelPipelines {
    sets: HashMap<PassKey, Vec<(VoxelPass, CachedComputePipelineId)>>,
    /// The key of this frame's passes (the extracted settings, `auto` resolved for the adapter).
    key: PassKey,
    /// Whether the adapter is a CPU (software Vulkan): what `traversal=auto` means.
    cpu_adapter: bool,
    no_view: BindGroup,
}

/// Keep the generic pipelines (`PassKey::generic`, right for any settings) compiled beside each key's, and run
/// them while a new key's set compiles: the game inserts this, so a settings change (a debug view, a lighting
/// toggle) never shows a blank frame. Headless renders wait for the key's set instead of compiling two.
#[derive(Resource)]
pub struct GenericFallback;

impl VoxelPipelines {
    /// The compiled pipelines of `passes` for this frame's key (or, with `GenericFallback`, the generic ones while
    /// the key's compile), or `None` until all of them are ready.
    fn get<'a>(&self, cache: &'a PipelineCache, passes: &[VoxelPass]) -> Option<Vec<&'a ComputePipeline>> {
        let ready = |key: &PassKey| -> Option<Vec<&'a ComputePipeline>> {
            let set = self.sets.get(key)?;
            passes
                .iter()
                .map(|pass| {
                    let (_, id) = set.iter().find(|(p, _)| p.name == pass.name)?;
                    cache.get_compute_pipeline(*id)
                })
                .collect()
        };
        ready(&self.key).or_else(|| ready(&PassKey::generic(self.key.traversal)))
    }

    /// Whether a camera's passes are compiled for this frame's key (or the generic fallback's): the primary
    /// pass, and ReSTIR's, the denoiser's and the upscaler's where they run.
    pub fn views_ready(&self, cache: &PipelineCache, restir: bool, denoise: bool, upscales: bool) -> bool {
        let ready = |runs: bool, passes: &[VoxelPass]| !runs || self.get(cache, passes).is_some();
        ready(true, &[primary::PRIMARY])
            && ready(restir, &restir::PASSES)
            && ready(denoise, &denoise::PASSES)
            && ready(upscales, &upscale::PASSES)
    }

    /// Whether every GI pass is compiled for this frame's key.
    pub fn gi_ready(&self, cache: &PipelineCache) -> bool {
        [&[gi::COMPACT_PASS][..], &gi::STATIC_PASSES, &gi::DYNAMIC_PASSES]
            .iter()
            .all(|passes| self.get(cache, passes).is_some())
    }
}

/// Every pass's pipeline for one key.
fn queue_passes(
    cache: &PipelineCache,
    shaders: &GlowbrickShaders,
    layouts: &ViewLayouts,
    groups: [&BindGroupLayoutDescriptor; 3],
    key: &PassKey,
) -> Vec<(VoxelPass, CachedComputePipelineId)> {
    let mut defs = shader_defs();
    defs.extend(key.shader_defs());
    all_passes()
        .into_iter()
        .map(|pass| {
            let group1 = if pass.dispatch.per_view() { &layouts.view } else { &layouts.empty };
            let id = cache.queue_compute_pipeline(ComputePipelineDescriptor {
                label: Some(pass.name.into()),
                layout: vec![groups[0].clone(), group1.clone(), groups[1].clone(), groups[2].clone()],
                shader: shaders.get(pass.shader),
                shader_defs: defs.clone(),
                entry_point: Some(pass.entry_point.into()),
                ..default()
            });
            (pass, id)
        })
        .collect()
}

/// Follows the settings: this frame's key, its pipelines queued the first time it is met.
#[allow(clippy::too_many_arguments)]
fn follow_settings(
    settings: Option<Res<RenderSettings>>,
    pipelines: Option<ResMut<VoxelPipelines>>,
    cache: Res<PipelineCache>,
    shaders: Res<GlowbrickShaders>,
    layouts: Option<Res<ViewLayouts>>,
    world_layout: Res<WorldLayout>,
    lights_layout: Res<LightsLayout>,
    gi_layout: Res<gi::GiLayout>,
    objects: Option<Res<GpuObjects>>,
    gpu_world: Option<Res<GpuWorld>>,
    generic_fallback: Option<Res<GenericFallback>>,
) {
    let (Some(mut pipelines), Some(layouts)) = (pipelines, layouts) else { return };
    let fallback = RenderSettings::default();
    let settings = settings.as_deref().unwrap_or(&fallback);
    let objects = objects.is_some_and(|o| o.count > 0);
    let pool_parts = gpu_world.is_some_and(|w| w.info.pool_part_shift != ONE_POOL_PART);
    let traversal = settings.traversal.resolve(pipelines.cpu_adapter);
    let key = PassKey::of(settings, traversal, objects, pool_parts);
    let generic = generic_fallback.map(|_| PassKey::generic(traversal));
    for key in std::iter::once(key).chain(generic) {
        pipelines.sets.entry(key).or_insert_with(|| {
            let groups = [&world_layout.0, &lights_layout.0, &gi_layout.0];
            queue_passes(&cache, &shaders, &layouts, groups, &key)
        });
    }
    if pipelines.key != key {
        pipelines.key = key;
    }
}

fn init_pipelines(
    mut commands: Commands,
    pipeline_cache: Res<PipelineCache>,
    device: Res<RenderDevice>,
    adapter: Res<RenderAdapterInfo>,
    parts: Res<ViewParts>,
) {
    let layouts = view_layouts(&parts);
    // The pipelines are queued by `follow_settings`, which knows the settings.
    let cpu_adapter = adapter.device_type == wgpu::DeviceType::Cpu;
    let no_view =
        device.create_bind_group("glowbrick_no_view", &pipeline_cache.get_bind_group_layout(&layouts.empty), &[]);
    let key = PassKey::of(&RenderSettings::default(), Traversal::Auto.resolve(cpu_adapter), false, false);
    commands.insert_resource(VoxelPipelines { sets: HashMap::new(), key, cpu_adapter, no_view });
    commands.insert_resource(layouts);
}

/// The first pass whose shader failed to compile, as one message (a shader not loaded yet is not a failure), so
/// headless callers fail fast instead of waiting.
pub fn pipeline_error(render_world: &World) -> Option<String> {
    let pipelines = render_world.get_resource::<VoxelPipelines>()?;
    let cache = render_world.resource::<PipelineCache>();
    pipelines.sets.values().flatten().find_map(|(pass, id)| match cache.get_compute_pipeline_state(*id) {
        CachedPipelineState::Err(e) if !matches!(e, bevy::shader::ShaderCacheError::ShaderNotLoaded(_)) => {
            Some(format!("the {} shader ({}) failed to compile: {e}", pass.name, pass.shader))
        }
        _ => None,
    })
}

/// Decides this frame's plan (`plan::FramePlan`): which passes run, whether they are compiled, what changed in
/// the scene. The one place that decides what runs; the views, the GI cache and both frame systems read it.
#[allow(clippy::too_many_arguments)]
fn plan_frame(
    mut plan: ResMut<FramePlan>,
    settings: Option<Res<RenderSettings>>,
    pipelines: Option<Res<VoxelPipelines>>,
    pipeline_cache: Res<PipelineCache>,
    gpu_world: Option<Res<GpuWorld>>,
    gpu_lights: Option<Res<GpuLights>>,
    objects: Option<Res<GpuObjects>>,
    scale_in_force: Option<Res<RenderScaleInForce>>,
) {
    let fallback = RenderSettings::default();
    let settings = settings.as_deref().unwrap_or(&fallback);
    let changes = scene_changes(gpu_world.as_deref(), gpu_lights.as_deref(), objects.as_deref());
    let restir = RestirPasses {
        shades: restir::shades(settings),
        samples: restir::samples(settings, changes.light_count),
        tiles: settings.restir.light_tiles,
    };
    let denoise = denoise::runs(settings);
    let render_scale = upscale::frame_scale(settings, scale_in_force.map(|s| *s), restir.shades);
    // A frame whose GI passes are not compiled yet must not use up the GI cache's first restart or its warm-up.
    // Nor must one whose cameras cannot draw yet: the cache would spend its warm-up on frames no camera drew.
    let ready = pipelines.is_some_and(|p| {
        p.gi_ready(&pipeline_cache) && p.views_ready(&pipeline_cache, restir.shades, denoise, render_scale < 1.0)
    });
    let gi = settings.gi.enabled;
    *plan = FramePlan { render_scale, restir, denoise, gi, compiling: gi && !ready, changes };
}

/// What changed in the scene this frame, as the views' histories see it.
fn scene_changes(world: Option<&GpuWorld>, lights: Option<&GpuLights>, objects: Option<&GpuObjects>) -> SceneChanges {
    let lights_changed = lights.is_some_and(|l| l.changed);
    let world_changed = world.is_some_and(|w| w.uploaded_bytes > 0) || lights_changed;
    SceneChanges {
        lights: lights_changed,
        world: world_changed,
        anything: world_changed || objects.is_some_and(|o| o.changed),
        light_count: lights.map_or(0, |l| l.light_count),
    }
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
    /// under its name when render diagnostics are on. `sizes`: the view's render and output pixels.
    fn dispatch(&mut self, pass: &VoxelPass, pipeline: &ComputePipeline, sizes: ViewSizes) {
        let label = Some(pass.name);
        let mut compute = self.encoder.begin_compute_pass(&ComputePassDescriptor { label, timestamp_writes: None });
        let span = self.diagnostics.pass_span(&mut compute, pass.name);
        compute.set_pipeline(pipeline);
        for (index, (group, offsets)) in self.groups.iter().enumerate() {
            compute.set_bind_group(index as u32, *group, offsets);
        }
        match pass.dispatch {
            Dispatch::Pixels | Dispatch::OutputPixels => {
                let size = if pass.dispatch == Dispatch::Pixels { sizes.render } else { sizes.output };
                compute.dispatch_workgroups(
                    size.x.div_ceil(PIXEL_WORKGROUP_EDGE),
                    size.y.div_ceil(PIXEL_WORKGROUP_EDGE),
                    1,
                )
            }
            Dispatch::LightTiles => compute.dispatch_workgroups(restir::TILE_THREADS.div_ceil(LINEAR_WORKGROUP), 1, 1),
            Dispatch::Slots => {
                let (slots, _) = self.gi_work.expect("GI passes are recorded with the cache's work");
                compute.dispatch_workgroups(slots.div_ceil(LINEAR_WORKGROUP), 1, 1)
            }
            Dispatch::Listed(offset) => {
                let (_, work) = self.gi_work.expect("GI passes are recorded with the cache's work");
                compute.dispatch_workgroups_indirect(work, offset)
            }
        }
        span.end(&mut compute);
    }
}

/// A view's pixels: the lighting passes' (`render`) and the output's.
#[derive(Clone, Copy, Debug, Default)]
struct ViewSizes {
    render: UVec2,
    output: UVec2,
}

/// A technique's passes this frame.
enum TechniquePipelines<'a> {
    /// It does not run.
    Skipped,
    /// It runs, but its pipelines are still compiling: the frame waits for all of them rather than showing half.
    Compiling,
    Ready(Vec<&'a ComputePipeline>),
}

impl<'a> TechniquePipelines<'a> {
    fn of(runs: bool, pipelines: &VoxelPipelines, cache: &'a PipelineCache, passes: &[VoxelPass]) -> Self {
        if !runs {
            return TechniquePipelines::Skipped;
        }
        pipelines.get(cache, passes).map_or(TechniquePipelines::Compiling, TechniquePipelines::Ready)
    }

    /// The pipelines to dispatch: none when skipped.
    fn dispatched(self) -> Vec<&'a ComputePipeline> {
        match self {
            TechniquePipelines::Ready(ready) => ready,
            _ => Vec::new(),
        }
    }
}

/// One camera's frame, top to bottom.
#[allow(clippy::too_many_arguments)]
pub fn view_frame(
    view: ViewQuery<(&ViewTarget, &ViewUniformOffset, &ViewResources), With<VoxelCamera>>,
    plan: Res<FramePlan>,
    pipelines: Option<Res<VoxelPipelines>>,
    layouts: Option<Res<ViewLayouts>>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    scene: SceneBindGroups,
    frames: Res<CameraFramesRendered>,
    mut ctx: RenderContext,
) {
    let (target, view_offset, resources) = view.into_inner();
    let (Some(pipelines), Some(layouts), Some(world), Some(lights)) = (pipelines, layouts, scene.world, scene.lights)
    else {
        return;
    };
    // GI on but not compiled yet: the frame waits for it, as for ReSTIR and the denoiser below.
    let Some(gi_group) = scene.gi.as_ref().filter(|_| !plan.compiling).and_then(|g| g.bind_group.as_ref()) else {
        return;
    };
    let Some(primary_pipeline) = pipelines.get(&pipeline_cache, &[primary::PRIMARY]).map(|p| p[0]) else { return };
    let restir = TechniquePipelines::of(plan.restir.shades, &pipelines, &pipeline_cache, &restir::PASSES);
    let denoise = TechniquePipelines::of(plan.denoise, &pipelines, &pipeline_cache, &denoise::PASSES);
    let upscale = TechniquePipelines::of(plan.upscales(), &pipelines, &pipeline_cache, &upscale::PASSES);
    if [&restir, &denoise, &upscale].iter().any(|t| matches!(t, TechniquePipelines::Compiling)) {
        return;
    }
    let (Some(view_binding), Some(view_buffer)) = (view_uniforms.uniforms.binding(), view_uniforms.uniforms.buffer())
    else {
        return;
    };
    let output = target.main_texture().size();
    let size = ViewSizes { render: resources.render_size(), output: UVec2::new(output.width, output.height) };
    // Last frame's G-buffer and denoiser history become the previous ones that the temporal reprojections read.
    resources.swap();
    let layout = pipeline_cache.get_bind_group_layout(&layouts.view);
    let view_group =
        resources.bind_group(ctx.render_device(), &layouts.interface, &layout, target, view_buffer, view_binding);
    let diagnostics = ctx.diagnostic_recorder();
    let encoder = ctx.command_encoder();
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
    let upscale = upscale.dispatched();
    // Below render scale 1: the lighting passes' G-buffer, one output texel per render pixel.
    if let Some(pick) = upscale.first() {
        recorder.dispatch(&upscale::PASSES[0], pick, size);
    }
    // 2-6. Voxel ReSTIR: the light tiles (when the candidates read them), candidates, their visibility and
    // temporal reuse, spatial reuse (when there are lights to sample), shading.
    for (pass, pipeline) in restir::PASSES.iter().zip(restir.dispatched()) {
        if restir::dispatches(&plan.restir, pass) {
            recorder.dispatch(pass, pipeline, size);
        }
    }
    // 7-12. The denoiser: temporal accumulation, then the wavelet's five iterations, the last writing the image
    // (or, below render scale 1, the upscaler's input).
    for (pass, pipeline) in denoise::PASSES.iter().zip(denoise.dispatched()) {
        recorder.dispatch(pass, pipeline, size);
    }
    // 13. Below render scale 1: the upscaler writes the image at the output's pixels.
    if let Some(main) = upscale.get(1) {
        recorder.dispatch(&upscale::PASSES[1], main, size);
    }
    frames.0.fetch_add(1, Ordering::Relaxed);
}

/// The world-level frame, once before every camera (whose shading then reads this frame's light): the GI cache
/// (work lists, refresh, updates, filters; the moving objects' table only while objects exist).
pub fn world_frame(
    plan: Res<FramePlan>,
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
    let Some(gi_group) = cache.bind_group.as_ref().filter(|_| plan.gi && !plan.compiling) else { return };
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
    let no_view = ViewSizes::default();
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

/// Adds the pipelines, the frame plan, the view preparation and the two frame systems to the render app.
pub fn add(render_app: &mut SubApp) {
    use bevy::core_pipeline::core_3d::main_transparent_pass_3d;
    use bevy::core_pipeline::schedule::camera_driver;
    use bevy::core_pipeline::{Core3d, Core3dSystems};
    use bevy::render::renderer::{RenderGraph, RenderGraphSystems};
    use bevy::render::{Render, RenderStartup, RenderSystems};
    render_app
        .insert_resource(view_parts())
        .init_resource::<FramePlan>()
        .configure_sets(Render, FramePlanned.in_set(RenderSystems::PrepareResources))
        .add_systems(RenderStartup, init_pipelines)
        .add_systems(
            Render,
            (follow_settings, plan_frame)
                .chain()
                .after(SceneUploaded)
                .before(FramePlanned)
                .in_set(RenderSystems::PrepareResources),
        )
        .add_systems(Core3d, view_frame.after(main_transparent_pass_3d).in_set(Core3dSystems::MainPass))
        .add_systems(RenderGraph, world_frame.before(camera_driver).in_set(RenderGraphSystems::Render));
    super::view::add(render_app);
}
