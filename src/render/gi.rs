//! The per-voxel-face GI cache (DESIGN.md "GI cache"; seed 001 adapted to voxels with seed 002's hash table).
//!
//! Entries are (surface voxel, face) pairs in a fixed-capacity GPU hash table (`shaders/gi.wgsl`). The primary
//! pass inserts the entries of the faces it sees; `gi_refresh.wgsl` keeps K static ray hits per entry, traced once
//! and traced again only for rays that cross a brick edited since (the edit log below); `gi_update.wgsl`
//! re-shades a few of them per frame (and traces moving objects' entries outright); `gi_filter.wgsl` averages
//! same-orientation neighbours; the shading passes interpolate (one frame of latency). With GI off the buffers
//! shrink to a placeholder and no GI pass is dispatched; without moving objects their passes are not either.

use super::gpu_world::{GpuWorld, WorldLayout};
use super::primary::PrimaryPipeline;
use super::{GlowbrickShaders, VoxelCamera, shader_defs};
use crate::lights::upload::{GpuLights, LightsLayout};
use crate::settings::{GiSettings, RenderSettings};
use bevy::prelude::*;
use bevy::render::diagnostic::RecordDiagnostics;
use bevy::render::extract_resource::ExtractResource;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, storage_buffer_sized, uniform_buffer_sized,
};
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderContext, RenderDevice, RenderQueue, ViewQuery};
use bevy::render::storage::{GpuShaderBuffer, ShaderBuffer};
use bevy::render::view::{ViewTarget, ViewUniformOffset, ViewUniforms};
use std::collections::VecDeque;
use std::num::NonZeroU64;

/// Entries in the static world's table and in the dynamic objects' table (powers of two).
pub const STATIC_CAPACITY: u32 = 1 << 16;
pub const DYNAMIC_CAPACITY: u32 = 1 << 12;
/// GPU bytes per entry besides its rays: key 4, payload 64, blended and filtered radiance 16 each.
pub const ENTRY_BYTES: u64 = 4 + 64 + 16 + 16;
/// Bytes per cached ray (face and distance packed in a u32).
pub const RAY_BYTES: u64 = 4;
/// Edited bricks remembered for invalidation; older edits force a retrace of everything traced before them.
const EDIT_LOG: usize = 64;
/// Frames numbering starts here so that "last seen at frame 0" (a fresh entry) is never recent.
const FIRST_FRAME: u32 = 1000;

/// GPU-time names of the static world's GI passes (update, filter), and of the moving objects' ones, which run
/// only while objects exist.
pub const GI_PASS_NAMES: [&str; 3] = ["glowbrick_gi_refresh", "glowbrick_gi_update", "glowbrick_gi_filter"];
pub const DYNAMIC_GI_PASS_NAMES: [&str; 2] = ["glowbrick_gi_dynamic_update", "glowbrick_gi_dynamic_filter"];

/// What the GI counters buffer counts each frame (`COUNT_*` in `shaders/gi.wgsl`).
#[derive(Clone, Copy, Debug)]
pub enum GiCounter {
    /// Entries re-shaded this frame.
    Updated = 0,
    /// Entries with at least one of their K static hits (re)traced this frame.
    Retraced = 1,
    /// Entries in the tables.
    Live = 2,
    /// Entries freed after going unused.
    Evicted = 3,
    /// Inserts that found their probe window full.
    Full = 4,
    /// Entries inserted this frame.
    Inserted = 5,
    /// Static rays traced to (re)fill the cached hits this frame.
    RaysTraced = 6,
    /// Ray hits whose face had no cached value and borrowed the shooting entry's indirect light.
    Borrowed = 7,
    /// Since the renderer started: ReSTIR reservoirs read with a non-finite field (reset to empty).
    ReservoirResets = 8,
    /// Since the renderer started: GI estimates that came out non-finite (replaced by zero).
    GiResets = 9,
}
/// Counter words; the first `PER_FRAME_COUNTERS` restart every frame, the rest count since the start.
pub const GI_COUNTERS: usize = 16;
const PER_FRAME_COUNTERS: usize = 8;

/// `GiParams` in `shaders/gi.wgsl`.
#[derive(Clone, Copy, Debug, Default, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct GiParams {
    enabled: u32,
    flags: u32,
    rays: u32,
    update_rays: u32,
    alpha: f32,
    epoch: u32,
    lost_epoch: u32,
    edit_count: u32,
    static_capacity: u32,
    dynamic_capacity: u32,
    frame: u32,
    _pad: u32,
}

const GI_FILTER: u32 = 1;
const GI_BOUNCES: u32 = 2;
const GI_CACHE: u32 = 4;

/// Layout of group 3 (`shaders/gi.wgsl`), shared by every voxel pass.
#[derive(Resource)]
pub struct GiLayout(pub BindGroupLayoutDescriptor);

pub fn gi_bind_group_layout() -> BindGroupLayoutDescriptor {
    BindGroupLayoutDescriptor::new(
        "glowbrick_gi_layout",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer_sized(false, NonZeroU64::new(size_of::<GiParams>() as u64)),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
                storage_buffer_read_only_sized(false, None),
                storage_buffer_sized(false, None),
            ),
        ),
    )
}

/// The counters buffer, an asset of the main world so tests and the bench can read it back.
#[derive(Resource, ExtractResource, Clone)]
pub struct GiCountersBuffer(pub Handle<ShaderBuffer>);

pub fn counters_asset() -> ShaderBuffer {
    ShaderBuffer::new(&[0u8; GI_COUNTERS * 4], bevy::asset::RenderAssetUsages::default())
}

/// What the table buffers were sized for: nothing (GI off) or K rays per entry.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Shape {
    entries: u32,
    rays: u32,
}

impl Shape {
    fn of(settings: &GiSettings) -> Shape {
        if settings.enabled {
            Shape { entries: STATIC_CAPACITY + DYNAMIC_CAPACITY, rays: settings.rays }
        } else {
            // Bindings need a non-empty buffer; one entry and one ray cost 104 bytes.
            Shape { entries: 1, rays: 1 }
        }
    }
}

/// GPU bytes the cache holds for `settings` (0 with GI off, besides a 104-byte placeholder).
pub fn cache_bytes(settings: &GiSettings) -> u64 {
    let shape = Shape::of(settings);
    shape.entries as u64 * (ENTRY_BYTES + shape.rays as u64 * RAY_BYTES)
}

struct Tables {
    keys: Buffer,
    entries: Buffer,
    irradiance: Buffer,
    filtered: Buffer,
    rays: Buffer,
}

impl Tables {
    fn new(device: &RenderDevice, shape: Shape) -> Tables {
        let storage = |label: &'static str, bytes: u64| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let n = shape.entries as u64;
        Tables {
            keys: storage("glowbrick_gi_keys", n * 4),
            entries: storage("glowbrick_gi_entries", n * 64),
            irradiance: storage("glowbrick_gi_irradiance", n * 16),
            filtered: storage("glowbrick_gi_filtered", n * 16),
            rays: storage("glowbrick_gi_rays", n * shape.rays as u64 * RAY_BYTES),
        }
    }
}

/// The render world's GI cache: the tables, the edit log and this frame's bind group.
#[derive(Resource)]
pub struct GiCache {
    params: Buffer,
    edits: Buffer,
    tables: Tables,
    shape: Shape,
    /// (min voxel, epoch), (max voxel exclusive, 0) per edited brick, oldest first.
    log: VecDeque<[i32; 8]>,
    epoch: u32,
    lost_epoch: u32,
    frame: u32,
    pub bind_group: Option<BindGroup>,
    /// Whether GI runs this frame.
    pub enabled: bool,
}

pub fn init_gi_cache(mut commands: Commands, device: Res<RenderDevice>) {
    let shape = Shape::of(&GiSettings::default());
    let params = device.create_buffer(&BufferDescriptor {
        label: Some("glowbrick_gi_params"),
        size: size_of::<GiParams>() as u64,
        usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let edits = device.create_buffer(&BufferDescriptor {
        label: Some("glowbrick_gi_edits"),
        size: (EDIT_LOG * 32) as u64,
        usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    commands.insert_resource(GiCache {
        params,
        edits,
        tables: Tables::new(&device, shape),
        shape,
        log: VecDeque::new(),
        epoch: 1,
        lost_epoch: 0,
        frame: FIRST_FRAME,
        bind_group: None,
        enabled: false,
    });
}

impl GiCache {
    /// Forgets every entry (new world, or new buffer shape).
    fn reset(&mut self, device: &RenderDevice, shape: Shape) {
        self.tables = Tables::new(device, shape);
        self.shape = shape;
        self.log.clear();
        self.epoch = 1;
        self.lost_epoch = 0;
    }

    /// Records this frame's edited bricks under a new epoch. Many bricks in one frame become one box.
    fn log_edits(&mut self, bricks: &[UVec3]) {
        if bricks.is_empty() {
            return;
        }
        self.epoch += 1;
        let edge = crate::world::grid::BRICK_SIZE;
        let boxes: Vec<(IVec3, IVec3)> = if bricks.len() <= 16 {
            bricks.iter().map(|b| (b.as_ivec3() * edge, (b.as_ivec3() + 1) * edge)).collect()
        } else {
            let lo = bricks.iter().fold(IVec3::MAX, |a, b| a.min(b.as_ivec3()));
            let hi = bricks.iter().fold(IVec3::MIN, |a, b| a.max(b.as_ivec3()));
            vec![(lo * edge, (hi + 1) * edge)]
        };
        for (lo, hi) in boxes {
            if self.log.len() == EDIT_LOG
                && let Some(oldest) = self.log.pop_front()
            {
                // Entries traced before the forgotten edit can no longer tell whether it reached them.
                self.lost_epoch = self.lost_epoch.max(oldest[3] as u32);
            }
            self.log.push_back([lo.x, lo.y, lo.z, self.epoch as i32, hi.x, hi.y, hi.z, 0]);
        }
    }
}

/// Sizes the tables for the settings, logs this frame's edits and writes the parameters (Render schedule,
/// PrepareResources, after the world upload).
#[allow(clippy::too_many_arguments)]
pub fn prepare_gi(
    mut cache: ResMut<GiCache>,
    settings: Option<Res<RenderSettings>>,
    gpu_world: Option<Res<GpuWorld>>,
    counters: Option<Res<GiCountersBuffer>>,
    buffers: Res<RenderAssets<GpuShaderBuffer>>,
    layout: Res<GiLayout>,
    pipeline_cache: Res<PipelineCache>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    let gi = settings.map(|s| s.gi.clone()).unwrap_or_default();
    let shape = Shape::of(&gi);
    if shape != cache.shape || gpu_world.as_ref().is_some_and(|w| w.replaced) {
        cache.reset(&device, shape);
    }
    // The edit log reaches the GPU only in frames that add to it (a reset empties it: edit_count 0 reads none).
    let mut log_changed = false;
    if let Some(world) = &gpu_world {
        log_changed = !world.edited_bricks.is_empty();
        cache.log_edits(&world.edited_bricks);
    }
    cache.enabled = gi.enabled;
    cache.frame = cache.frame.wrapping_add(1);
    let flag = |on: bool, bit: u32| if on { bit } else { 0 };
    let params = GiParams {
        enabled: gi.enabled as u32,
        flags: flag(gi.filter, GI_FILTER) | flag(gi.bounces, GI_BOUNCES) | flag(gi.cache, GI_CACHE),
        rays: shape.rays,
        update_rays: gi.update_rays.clamp(1, shape.rays),
        alpha: gi.alpha,
        epoch: cache.epoch,
        lost_epoch: cache.lost_epoch,
        edit_count: cache.log.len() as u32,
        static_capacity: if gi.enabled { STATIC_CAPACITY } else { 1 },
        dynamic_capacity: if gi.enabled { DYNAMIC_CAPACITY } else { 0 },
        frame: cache.frame,
        _pad: 0,
    };
    queue.write_buffer(&cache.params, 0, bytemuck::bytes_of(&params));
    if log_changed {
        let log: Vec<i32> = cache.log.iter().flatten().copied().collect();
        queue.write_buffer(&cache.edits, 0, bytemuck::cast_slice(&log));
    }
    let Some(counters) = counters.and_then(|c| buffers.get(&c.0)) else {
        cache.bind_group = None;
        return;
    };
    queue.write_buffer(&counters.buffer, 0, &[0u8; PER_FRAME_COUNTERS * 4]);
    let t = &cache.tables;
    cache.bind_group = Some(device.create_bind_group(
        "glowbrick_gi",
        &pipeline_cache.get_bind_group_layout(&layout.0),
        &BindGroupEntries::sequential((
            cache.params.as_entire_binding(),
            t.keys.as_entire_binding(),
            t.entries.as_entire_binding(),
            t.irradiance.as_entire_binding(),
            t.filtered.as_entire_binding(),
            t.rays.as_entire_binding(),
            cache.edits.as_entire_binding(),
            counters.buffer.as_entire_binding(),
        )),
    ));
}

/// Refresh, update and filter of the static table, then update and filter of the objects' table.
#[derive(Resource)]
pub struct GiPipelines {
    passes: [CachedComputePipelineId; 5],
}

/// Pass names in the order of `GiPipelines::passes`.
const PIPELINE_NAMES: [&str; 5] =
    [GI_PASS_NAMES[0], GI_PASS_NAMES[1], GI_PASS_NAMES[2], DYNAMIC_GI_PASS_NAMES[0], DYNAMIC_GI_PASS_NAMES[1]];

pub fn init_gi_pipelines(
    mut commands: Commands,
    pipeline_cache: Res<PipelineCache>,
    shaders: Res<GlowbrickShaders>,
    world_layout: Res<WorldLayout>,
    lights_layout: Res<LightsLayout>,
    gi_layout: Res<GiLayout>,
    primary: Res<PrimaryPipeline>,
) {
    let queue = |name: &'static str, shader: &Handle<Shader>, entry: &'static str| {
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
            entry_point: Some(entry.into()),
            ..default()
        })
    };
    let passes = [
        queue(PIPELINE_NAMES[0], &shaders.gi_refresh, "refresh_static"),
        queue(PIPELINE_NAMES[1], &shaders.gi_update, "update_static"),
        queue(PIPELINE_NAMES[2], &shaders.gi_filter, "filter_static"),
        queue(PIPELINE_NAMES[3], &shaders.gi_update, "update_dynamic"),
        queue(PIPELINE_NAMES[4], &shaders.gi_filter, "filter_dynamic"),
    ];
    commands.insert_resource(GiPipelines { passes });
}

/// A GI pipeline's compile error, if one failed.
pub fn pipeline_error(render_world: &World) -> Option<String> {
    let pipelines = render_world.get_resource::<GiPipelines>()?;
    super::compile_error(render_world, &pipelines.passes, &PIPELINE_NAMES)
}

/// Updates and filters the cache after the camera's passes inserted this frame's entries (which shade with
/// last frame's values: one frame of latency).
#[allow(clippy::too_many_arguments)]
pub fn gi_passes(
    view: ViewQuery<(&ViewTarget, &ViewUniformOffset, &super::primary::PrimaryViewResources), With<VoxelCamera>>,
    primary: Option<Res<PrimaryPipeline>>,
    pipelines: Option<Res<GiPipelines>>,
    cache: Option<Res<GiCache>>,
    pipeline_cache: Res<PipelineCache>,
    view_uniforms: Res<ViewUniforms>,
    gpu_world: Option<Res<GpuWorld>>,
    gpu_lights: Option<Res<GpuLights>>,
    objects: Option<Res<crate::dynamic::upload::GpuObjects>>,
    mut ctx: RenderContext,
) {
    let (target, view_offset, resources) = view.into_inner();
    let (Some(primary), Some(pipelines), Some(cache), Some(gpu_world), Some(gpu_lights)) =
        (primary, pipelines, cache, gpu_world, gpu_lights)
    else {
        return;
    };
    let with_objects = objects.is_some_and(|o| o.count > 0);
    let Some(gi_group) = cache.bind_group.as_ref().filter(|_| cache.enabled) else { return };
    let Some(computes) =
        pipelines.passes.iter().map(|id| pipeline_cache.get_compute_pipeline(*id)).collect::<Option<Vec<_>>>()
    else {
        return;
    };
    let Some(view_binding) = view_uniforms.uniforms.binding() else { return };
    let view_group =
        super::primary::view_bind_group(&ctx, &pipeline_cache, &primary.view_layout, target, view_binding, resources);
    let diagnostics = ctx.diagnostic_recorder();
    let diagnostics = diagnostics.as_deref();
    let encoder = ctx.command_encoder();
    // Refresh before update, updates before filters (a filter reads its neighbours' new values); the objects'
    // table only while objects exist.
    let order = [
        (0, STATIC_CAPACITY),
        (1, STATIC_CAPACITY),
        (3, DYNAMIC_CAPACITY),
        (2, STATIC_CAPACITY),
        (4, DYNAMIC_CAPACITY),
    ];
    for (index, threads) in order {
        if index >= 3 && !with_objects {
            continue;
        }
        let (compute, name) = (computes[index], PIPELINE_NAMES[index]);
        let mut pass = encoder.begin_compute_pass(&ComputePassDescriptor { label: Some(name), timestamp_writes: None });
        let span = diagnostics.pass_span(&mut pass, name);
        pass.set_pipeline(compute);
        pass.set_bind_group(0, &gpu_world.bind_group, &[]);
        pass.set_bind_group(1, &view_group, &[view_offset.offset]);
        pass.set_bind_group(2, &gpu_lights.bind_group, &[]);
        pass.set_bind_group(3, gi_group, &[]);
        pass.dispatch_workgroups(threads.div_ceil(64), 1, 1);
        span.end(&mut pass);
    }
}

/// Adds the cache's systems to the render app.
pub fn add_gi(render_app: &mut SubApp) {
    use bevy::core_pipeline::{Core3d, Core3dSystems};
    use bevy::render::{Render, RenderStartup, RenderSystems};
    render_app
        .insert_resource(GiLayout(gi_bind_group_layout()))
        .add_systems(RenderStartup, (init_gi_cache, init_gi_pipelines.after(super::primary::init_primary_pipeline)))
        .add_systems(
            Render,
            prepare_gi.after(super::gpu_world::prepare_gpu_world).in_set(RenderSystems::PrepareResources),
        )
        .add_systems(Core3d, gi_passes.after(super::restir::restir_passes).in_set(Core3dSystems::MainPass));
}
