//! The per-voxel-face GI cache (DESIGN.md "GI cache"; seed 001 adapted to voxels with seed 002's hash table).
//!
//! Entries are (surface voxel, face) pairs in a fixed-capacity GPU hash table (`shaders/gi/cache.wgsl`). The primary
//! pass inserts the entries of the faces it sees; `shaders/gi/refresh.wgsl` keeps the entry's own direct light (one
//! shadow ray a frame, `direct.wgsl`) and restarts entries an edit reached (the edit log below); `update.wgsl`
//! traces a few fresh directions per entry and frame (a ray reads the direct light of the face it hits from that
//! face's entry). With `gi_cached_hits=on` refresh instead keeps K fixed directions' static hits per entry, traced once and
//! again only for rays that cross a brick edited since, and update re-shades a few of them; `filter.wgsl` averages
//! same-orientation neighbours; the shading passes interpolate. With GI off the buffers
//! shrink to a placeholder and no GI pass is dispatched; without moving objects their passes are not either.
//! The passes run once per frame before every camera (`frame::world_frame`), in the order listed there.
//!
//! The cache's whole state is in this folder: `tables` (the GPU buffers and their shape), `edit_log` (edited
//! bricks), `schedule` (restarts, warm-up, iterations: a pure function of what changed) and `GiCache` below,
//! which holds them and writes the frame's parameters.

mod edit_log;
mod schedule;
mod tables;

pub use schedule::{RESTART_ITERATIONS, WARM_UP_FRAMES};
pub use tables::{DYNAMIC_CAPACITY, ENTRY_BYTES, RAY_BYTES, cache_bytes, static_capacity};

use super::gpu_types::{
    GI_BOUNCES, GI_CACHE, GI_EDIT_RESTART, GI_FILTER, GI_GUIDING, GI_QMC, GI_RESERVOIRS, GI_RESTART, GiEdit, GiParams,
};
use super::interface::{GpuBinding, GroupInterface};
use super::pass::{Dispatch, VoxelPass};
use super::plan::{FramePlan, FramePlanned};
use super::scene::lights::GpuLights;
use super::scene::objects::GpuObjects;
use super::scene::world::GpuWorld;
use crate::settings::{GiSettings, RenderSettings};
use bevy::prelude::*;
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::{Render, RenderStartup, RenderSystems};
use edit_log::{EDIT_LOG, EditLog};
use schedule::{FrameEvents, GiPlan, GiSchedule, LightingKey};
use tables::{EMPTY_WORK, Shape, Tables, WORK_BYTES, WORK_DYNAMIC, WORK_STATIC};

/// The first GI pass, one thread per slot of both tables: ages the entries and lists those due this frame
/// (`shaders/gi/compact.wgsl`), with the indirect dispatch sizes of the passes below.
pub const COMPACT_PASS: VoxelPass = VoxelPass {
    name: "glowbrick_gi_compact",
    shader: "gi/compact.wgsl",
    entry_point: "compact",
    dispatch: Dispatch::Slots,
};

/// The static world's passes (refresh, update, filter) and the moving objects' (update, filter), which run only
/// while objects exist. One thread per listed entry.
pub const STATIC_PASSES: [VoxelPass; 3] = [
    VoxelPass {
        name: "glowbrick_gi_refresh",
        shader: "gi/refresh.wgsl",
        entry_point: "refresh_static",
        dispatch: Dispatch::Listed(WORK_STATIC),
    },
    VoxelPass {
        name: "glowbrick_gi_update",
        shader: "gi/update.wgsl",
        entry_point: "update_static",
        dispatch: Dispatch::Listed(WORK_STATIC),
    },
    VoxelPass {
        name: "glowbrick_gi_filter",
        shader: "gi/filter.wgsl",
        entry_point: "filter_static",
        dispatch: Dispatch::Listed(WORK_STATIC),
    },
];
pub const DYNAMIC_PASSES: [VoxelPass; 2] = [
    VoxelPass {
        name: "glowbrick_gi_dynamic_update",
        shader: "gi/update.wgsl",
        entry_point: "update_dynamic",
        dispatch: Dispatch::Listed(WORK_DYNAMIC),
    },
    VoxelPass {
        name: "glowbrick_gi_dynamic_filter",
        shader: "gi/filter.wgsl",
        entry_point: "filter_dynamic",
        dispatch: Dispatch::Listed(WORK_DYNAMIC),
    },
];

/// GPU-time names of the static world's GI passes (compaction first), and of the moving objects' ones.
pub const GI_PASS_NAMES: [&str; 4] =
    [COMPACT_PASS.name, STATIC_PASSES[0].name, STATIC_PASSES[1].name, STATIC_PASSES[2].name];
pub const DYNAMIC_GI_PASS_NAMES: [&str; 2] = [DYNAMIC_PASSES[0].name, DYNAMIC_PASSES[1].name];

/// Layout of group 3 (`shaders/gi/cache.wgsl`), shared by every voxel pass.
#[derive(Resource)]
pub struct GiLayout(pub BindGroupLayoutDescriptor);

/// Group 3 (`shaders/gi/cache.wgsl`): the parameters, the tables, the edit log and the work lists.
pub fn gi_interface() -> GroupInterface {
    GroupInterface::new(
        3,
        "glowbrick_gi_layout",
        &[&[
            GpuBinding::uniform("gi", size_of::<GiParams>()),
            GpuBinding::read_write("gi_keys"),
            GpuBinding::read_write("gi_entries"),
            GpuBinding::read_write("gi_irradiance"),
            GpuBinding::read_write("gi_filtered"),
            GpuBinding::read_write("gi_rays"),
            GpuBinding::read("gi_edits"),
            GpuBinding::read_write("gi_direct"),
            GpuBinding::read_write("gi_work"),
            GpuBinding::read_write("gi_list"),
        ]],
    )
}

/// The render world's GI cache: its tables, edit log and schedule, and the bind group over them (made again only
/// when the tables are).
#[derive(Resource)]
pub struct GiCache {
    params: Buffer,
    edits: Buffer,
    /// 0, 1, .. RESTART_ITERATIONS - 1: copied into the parameters' `iteration` between iterations.
    iteration_indices: Buffer,
    tables: Tables,
    shape: Shape,
    log: EditLog,
    schedule: GiSchedule,
    /// Update iterations this frame.
    iterations: u32,
    pub bind_group: Option<BindGroup>,
}

impl GiCache {
    /// Frames that restarted the entries after a change of light, since the cache was made.
    pub fn restarts(&self) -> u32 {
        self.schedule.restarts()
    }

    /// Slots of both tables (the compaction pass's threads).
    pub fn slots(&self) -> u32 {
        self.shape.entries()
    }

    /// Copies the dispatch sizes the compaction pass wrote to where the listed passes read them.
    pub fn publish_work(&self, encoder: &mut CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.tables.work, 0, &self.tables.arguments, 0, WORK_BYTES);
    }

    /// Update iterations this frame.
    pub fn iterations(&self) -> u32 {
        self.iterations
    }

    /// Sets the parameters' `iteration` for the passes recorded after this (the queue's write of the parameters
    /// lands before the frame's commands; this copy between two of them).
    pub fn set_iteration(&self, encoder: &mut CommandEncoder, iteration: u32) {
        let field = std::mem::offset_of!(GiParams, iteration) as u64;
        encoder.copy_buffer_to_buffer(&self.iteration_indices, 4 * iteration as u64, &self.params, field, 4);
    }

    /// The buffer the listed passes take their dispatch sizes from.
    pub fn arguments(&self) -> &Buffer {
        &self.tables.arguments
    }

    /// Resizes the tables for `settings` when their shape changed, and forgets every entry of a replaced world
    /// or another seed.
    fn fit(&mut self, device: &RenderDevice, settings: &RenderSettings, world_replaced: bool) {
        let gi = &settings.gi;
        let max_binding = device.limits().max_storage_buffer_binding_size;
        let shape = Shape::of(gi, max_binding);
        if shape.halved(gi) && shape != self.shape {
            warn!(
                "gi_table={} with gi_cached_rays={} needs more than this GPU binds in one buffer ({max_binding} bytes): \
                 the GI table holds {} slots",
                static_capacity(gi),
                gi.rays,
                shape.static_entries
            );
        }
        if shape != self.shape || world_replaced || self.schedule.seed_changed(settings.seed) {
            self.tables = Tables::new(device, shape);
            self.bind_group = None;
            self.shape = shape;
            self.log = EditLog::default();
            self.schedule.start_fresh(settings.seed);
        }
    }

    /// This frame's parameters (`GiParams`).
    fn params(&self, gi: &GiSettings, plan: &GiPlan) -> GiParams {
        let flag = |on: bool, bit: u32| if on { bit } else { 0 };
        let rays = self.shape.rays;
        GiParams {
            enabled: gi.enabled as u32,
            flags: setting_flags(gi) | flag(plan.restart, GI_RESTART) | flag(plan.edit_restart, GI_EDIT_RESTART),
            rays,
            // With cached hits an entry re-shades at most its K directions a frame; fresh ones are drawn as many
            // as asked.
            update_rays: if gi.cache { gi.update_rays.clamp(1, rays) } else { gi.update_rays.max(1) },
            alpha: gi.alpha,
            epoch: self.log.epoch(),
            lost_epoch: self.log.lost_epoch(),
            edit_count: self.log.count(),
            static_capacity: self.shape.static_entries,
            dynamic_capacity: self.shape.dynamic_entries,
            frame: plan.frame,
            iteration: 0,
            cell_pixels: gi.cell_pixels as f32,
            update_run: plan.update_run,
            period: plan.settled_period(gi.period),
            _pad: 0,
        }
    }

    fn create_bind_group(&self, device: &RenderDevice, layout: &BindGroupLayout) -> BindGroup {
        let t = &self.tables;
        device.create_bind_group(
            "glowbrick_gi",
            layout,
            &gi_interface().entries(vec![
                self.params.as_entire_binding(),
                t.keys.as_entire_binding(),
                t.entries.as_entire_binding(),
                t.irradiance.as_entire_binding(),
                t.filtered.as_entire_binding(),
                t.rays.as_entire_binding(),
                self.edits.as_entire_binding(),
                t.direct.as_entire_binding(),
                t.work.as_entire_binding(),
                t.list.as_entire_binding(),
            ]),
        )
    }
}

pub fn init_gi_cache(mut commands: Commands, device: Res<RenderDevice>) {
    let shape = Shape::of(&GiSettings::default(), u64::MAX);
    let params = device.create_buffer(&BufferDescriptor {
        label: Some("glowbrick_gi_params"),
        size: size_of::<GiParams>() as u64,
        usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let edits = device.create_buffer(&BufferDescriptor {
        label: Some("glowbrick_gi_edits"),
        size: (EDIT_LOG * size_of::<GiEdit>()) as u64,
        usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let indices: Vec<u32> = (0..RESTART_ITERATIONS).collect();
    let iteration_indices = device.create_buffer_with_data(&BufferInitDescriptor {
        label: Some("glowbrick_gi_iteration_indices"),
        contents: bytemuck::cast_slice(&indices),
        usage: BufferUsages::COPY_SRC,
    });
    commands.insert_resource(GiCache {
        params,
        edits,
        iteration_indices,
        tables: Tables::new(&device, shape),
        shape,
        log: EditLog::default(),
        schedule: GiSchedule::default(),
        iterations: 1,
        bind_group: None,
    });
}

/// The `GiParams.flags` bits the settings decide (the rest are this frame's restarts).
pub fn setting_flags(gi: &GiSettings) -> u32 {
    let flag = |on: bool, bit: u32| if on { bit } else { 0 };
    flag(gi.filter, GI_FILTER)
        | flag(gi.bounces, GI_BOUNCES)
        | flag(gi.cache, GI_CACHE)
        | flag(gi.qmc, GI_QMC)
        | flag(gi.reservoirs, GI_RESERVOIRS)
        | flag(gi.guiding, GI_GUIDING)
}

/// Sizes the tables for the settings, logs this frame's edits, plans the frame and writes the parameters (Render
/// schedule, PrepareResources, after the frame plan).
#[allow(clippy::too_many_arguments)]
pub fn prepare_gi(
    mut cache: ResMut<GiCache>,
    settings: Option<Res<RenderSettings>>,
    gpu_world: Option<Res<GpuWorld>>,
    gpu_lights: Option<Res<GpuLights>>,
    gpu_objects: Option<Res<GpuObjects>>,
    layout: Res<GiLayout>,
    plan: Res<FramePlan>,
    pipeline_cache: Res<PipelineCache>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    let fallback = RenderSettings::default();
    let settings = settings.as_deref().unwrap_or(&fallback);
    cache.fit(&device, settings, gpu_world.as_ref().is_some_and(|w| w.replaced));
    // Its buffers change only when `fit` makes new tables.
    if cache.bind_group.is_none() {
        cache.bind_group = Some(cache.create_bind_group(&device, &pipeline_cache.get_bind_group_layout(&layout.0)));
    }
    // The edit log reaches the GPU only in frames that add to it (a fresh log reads as none: edit_count 0).
    let edited = cache.log.record(gpu_world.as_ref().map_or(&[][..], |w| &w.edited_bricks));
    if edited {
        queue.write_buffer(&cache.edits, 0, bytemuck::cast_slice(&cache.log.records()));
    }
    let events = FrameEvents {
        lighting: LightingKey::of(settings),
        lights_changed: gpu_lights.as_ref().is_some_and(|l| l.changed),
        objects_came_or_went: gpu_objects.as_ref().is_some_and(|o| o.set_changed),
        edited,
        warm_up: settings.gi.warm_up,
    };
    // The frame plan holds the cache while a pass this frame runs is still compiling.
    if plan.compiling {
        cache.schedule.hold(events);
        return;
    }
    let gi_plan = cache.schedule.plan(events);
    cache.iterations = gi_plan.iterations;
    queue.write_buffer(&cache.params, 0, bytemuck::bytes_of(&cache.params(&settings.gi, &gi_plan)));
    queue.write_buffer(&cache.tables.work, 0, bytemuck::cast_slice(&EMPTY_WORK));
}

/// Adds the cache and its preparation to the render app (its passes are in `frame::world_frame`).
pub fn add(render_app: &mut SubApp) {
    render_app
        .insert_resource(GiLayout(gi_interface().layout()))
        .add_systems(RenderStartup, init_gi_cache)
        .add_systems(Render, prepare_gi.after(FramePlanned).in_set(RenderSystems::PrepareResources));
}
