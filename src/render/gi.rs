//! The per-voxel-face GI cache (DESIGN.md "GI cache"; seed 001 adapted to voxels with seed 002's hash table).
//!
//! Entries are (surface voxel, face) pairs in a fixed-capacity GPU hash table (`shaders/gi/cache.wgsl`). The primary
//! pass inserts the entries of the faces it sees; `shaders/gi/refresh.wgsl` keeps the entry's own direct light (one
//! shadow ray a frame, `direct.wgsl`) and restarts entries an edit reached (the edit log below); `update.wgsl`
//! traces a few fresh directions per entry and frame (a ray reads the direct light of the face it hits from that
//! face's entry). With `gi_cache=on` refresh instead keeps K fixed directions' static hits per entry, traced once and
//! again only for rays that cross a brick edited since, and update re-shades a few of them; `filter.wgsl` averages
//! same-orientation neighbours; the shading passes interpolate. With GI off the buffers
//! shrink to a placeholder and no GI pass is dispatched; without moving objects their passes are not either.
//! The passes run once per frame before every camera (`frame::world_frame`), in the order listed there.

use super::frame::{Dispatch, VoxelPass};
use super::gpu_types::{
    GI_BOUNCES, GI_CACHE, GI_EDIT_RESTART, GI_FILTER, GI_KEY_BYTES, GI_QMC, GI_RADIANCE_BYTES, GI_RAY_BYTES,
    GI_RESTART, GiEdit, GiEntry, GiParams,
};
use super::scene::SceneUploaded;
use super::scene::lights::GpuLights;
use super::scene::objects::GpuObjects;
use super::scene::world::GpuWorld;
use crate::settings::{GiSettings, RenderSettings, SEED_FRAMES};
use bevy::prelude::*;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, storage_buffer_sized, uniform_buffer_sized,
};
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::{Render, RenderStartup, RenderSystems};
use std::collections::VecDeque;
use std::num::NonZeroU64;

/// Entries in the moving objects' table (a power of two; the static world's is the `gi_table` setting).
pub const DYNAMIC_CAPACITY: u32 = 1 << 12;
/// GPU bytes per entry besides its rays: key, payload, blended and filtered radiance, direct light, its place in
/// the work list.
pub const ENTRY_BYTES: u64 = GI_KEY_BYTES + size_of::<GiEntry>() as u64 + 3 * GI_RADIANCE_BYTES + 4;
/// Bytes per cached ray (face and distance packed in a u32).
pub const RAY_BYTES: u64 = GI_RAY_BYTES;
/// Edited bricks remembered for invalidation; older edits force a retrace of everything traced before them.
const EDIT_LOG: usize = 64;
/// Frames numbering starts here so that "last seen at frame 0" (a fresh entry) is never recent.
const FIRST_FRAME: u32 = 1000;

/// The first GI pass, one thread per slot of both tables: ages the entries and lists those due this frame
/// (`shaders/gi/compact.wgsl`), with the indirect dispatch sizes of the passes below.
pub const COMPACT_PASS: VoxelPass = VoxelPass {
    name: "glowbrick_gi_compact",
    shader: "gi/compact.wgsl",
    entry_point: "compact",
    dispatch: Dispatch::Slots,
};

/// Where the static and the dynamic table's dispatch sizes lie in the work buffer (x, y, z, then the count).
const WORK_STATIC: u64 = 4 * super::gpu_types::GI_WORK_STATIC_WORD as u64;
const WORK_DYNAMIC: u64 = 4 * super::gpu_types::GI_WORK_DYNAMIC_WORD as u64;

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
                storage_buffer_sized(false, None),
                storage_buffer_sized(false, None),
            ),
        ),
    )
}

/// What the table buffers were sized for: nothing (GI off) or the static table's entries (the `gi_table` setting,
/// a power of two) and K rays per entry; the dynamic table follows the static one in the same buffers.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Shape {
    static_entries: u32,
    dynamic_entries: u32,
    rays: u32,
}

impl Shape {
    /// The shape for `settings` on a device whose storage bindings hold at most `max_binding` bytes: the static
    /// table halves (down to 4,096 slots) until its rays buffer, the largest, fits (`gi_table` at 262,144 with
    /// `gi_rays=128` needs 136 MB; lavapipe binds 128 MiB).
    fn of(settings: &GiSettings, max_binding: u64) -> Shape {
        if settings.enabled {
            // Without the static visibility cache no hit is kept: one placeholder ray per entry.
            let rays = if settings.cache { settings.rays } else { 1 };
            let bytes = |entries: u32| (entries + DYNAMIC_CAPACITY) as u64 * rays as u64 * RAY_BYTES;
            let mut static_entries = static_capacity(settings);
            while bytes(static_entries) > max_binding && static_entries > 4096 {
                static_entries /= 2;
            }
            Shape { static_entries, dynamic_entries: DYNAMIC_CAPACITY, rays }
        } else {
            // Bindings need a non-empty buffer: one entry, one ray and the work buffers cost 188 bytes.
            Shape { static_entries: 1, dynamic_entries: 0, rays: 1 }
        }
    }

    fn entries(&self) -> u32 {
        self.static_entries + self.dynamic_entries
    }

    /// Whether the device's binding limit cut the static table below the `gi_table` asked for (never with GI
    /// off, whose placeholder holds one slot whatever the setting).
    fn halved(&self, settings: &GiSettings) -> bool {
        settings.enabled && self.static_entries < static_capacity(settings)
    }
}

/// The static table's slots for `settings`: the `gi_table` setting rounded up to a power of two (the probe
/// sequence masks with it), at least 64 (a compaction workgroup lies in one table).
pub fn static_capacity(settings: &GiSettings) -> u32 {
    settings.table.clamp(64, 1 << 30).next_power_of_two()
}

/// GPU bytes the cache holds for `settings` (with GI off a 188-byte placeholder), on a device that binds
/// buffers of any size (a smaller limit halves the table: `Shape::of`).
pub fn cache_bytes(settings: &GiSettings) -> u64 {
    let shape = Shape::of(settings, u64::MAX);
    shape.entries() as u64 * (ENTRY_BYTES + shape.rays as u64 * RAY_BYTES) + 2 * WORK_BYTES
}

struct Tables {
    keys: Buffer,
    entries: Buffer,
    irradiance: Buffer,
    filtered: Buffer,
    rays: Buffer,
    direct: Buffer,
    /// This frame's work: dispatch sizes and counts (`gi_work`), and the listed slots (`gi_list`).
    work: Buffer,
    list: Buffer,
    /// The work buffer's copy the listed passes take their dispatch sizes from (a buffer bound for writing
    /// cannot also be a dispatch's indirect argument).
    arguments: Buffer,
}

impl Tables {
    fn new(device: &RenderDevice, shape: Shape) -> Tables {
        let buffer = |label: &'static str, bytes: u64, usage: BufferUsages| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: usage | BufferUsages::STORAGE | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let storage = |label: &'static str, bytes: u64| buffer(label, bytes, BufferUsages::empty());
        let n = shape.entries() as u64;
        Tables {
            keys: storage("glowbrick_gi_keys", n * GI_KEY_BYTES),
            entries: storage("glowbrick_gi_entries", n * size_of::<GiEntry>() as u64),
            irradiance: storage("glowbrick_gi_irradiance", n * GI_RADIANCE_BYTES),
            filtered: storage("glowbrick_gi_filtered", n * GI_RADIANCE_BYTES),
            rays: storage("glowbrick_gi_rays", n * shape.rays as u64 * RAY_BYTES),
            direct: storage("glowbrick_gi_direct", n * GI_RADIANCE_BYTES),
            work: buffer("glowbrick_gi_work", WORK_BYTES, BufferUsages::COPY_SRC),
            list: storage("glowbrick_gi_list", n * 4),
            arguments: device.create_buffer(&BufferDescriptor {
                label: Some("glowbrick_gi_arguments"),
                size: WORK_BYTES,
                usage: BufferUsages::INDIRECT | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }
}

/// The work buffer: per table three dispatch sizes and a count.
const WORK_BYTES: u64 = 4 * super::gpu_types::GI_WORK_WORDS as u64;
/// What the work buffer holds before compaction: no workgroups (y = z = 1) and no entries listed.
const EMPTY_WORK: [u32; super::gpu_types::GI_WORK_WORDS as usize] = super::gpu_types::GI_EMPTY_WORK;

/// The render world's GI cache: the tables, the edit log and this frame's bind group.
#[derive(Resource)]
pub struct GiCache {
    params: Buffer,
    edits: Buffer,
    tables: Tables,
    shape: Shape,
    /// Edited bricks, oldest first.
    log: VecDeque<GiEdit>,
    epoch: u32,
    lost_epoch: u32,
    frame: u32,
    /// The `seed` the entries were blended under: their frame stamps count from it, so a change starts over.
    seed: u32,
    /// The lighting the entries were blended under (mode, time of day, sun, shadows); a change restarts them.
    lighting: Option<(crate::settings::Lighting, u32, bool, bool)>,
    /// Frames left in which the entries an edit reached restart theirs.
    edit_restart_frames: u32,
    /// Frames left of a fresh cache's warm-up, which runs WARM_UP_ITERATIONS update iterations a frame.
    warm_up_frames: u32,
    /// Frames that restarted the entries (after a change of light).
    restarts: u32,
    /// Update iterations this frame (RESTART_ITERATIONS in the first frame after a change of light, else 1).
    iterations: u32,
    /// Update iterations run before this frame: where this frame's fresh rays continue their sequences.
    update_run: u32,
    /// 0, 1, .. RESTART_ITERATIONS - 1: copied into the parameters' `iteration` between iterations.
    iteration_indices: Buffer,
    pub bind_group: Option<BindGroup>,
    /// Whether GI runs this frame.
    pub enabled: bool,
}

impl GiCache {
    /// Frames that restarted the entries after a change of light, since the cache was made.
    pub fn restarts(&self) -> u32 {
        self.restarts
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
        iterations: 1,
        update_run: 0,
        restarts: 0,
        iteration_indices,
        edits,
        tables: Tables::new(&device, shape),
        shape,
        log: VecDeque::new(),
        epoch: 1,
        lost_epoch: 0,
        frame: FIRST_FRAME,
        seed: 0,
        lighting: None,
        edit_restart_frames: 0,
        warm_up_frames: WARM_UP_FRAMES,
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
        self.warm_up_frames = WARM_UP_FRAMES;
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
                self.lost_epoch = self.lost_epoch.max(oldest.epoch as u32);
            }
            self.log.push_back(GiEdit { min: lo.to_array(), epoch: self.epoch as i32, max: hi.to_array(), _pad: 0 });
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
    gpu_lights: Option<Res<GpuLights>>,
    gpu_objects: Option<Res<GpuObjects>>,
    layout: Res<GiLayout>,
    pipeline_cache: Res<PipelineCache>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    let fallback;
    let settings = match settings.as_deref() {
        Some(s) => s,
        None => {
            fallback = RenderSettings::default();
            &fallback
        }
    };
    let gi = settings.gi.clone();
    // A change of light restarts the entries: their direct light from several samples, their indirect light
    // from zero with RESTART_ITERATIONS bounces in this one frame, so nothing of the old light is left to drain
    // (with the blend restarted from last frame's values instead, a lamp switched off left its light in the room
    // for 16+ frames at the game's alpha 0.03: docs/bench/denoise.md).
    let lighting = Some((settings.lighting, settings.time.to_bits(), settings.sun, settings.shadows));
    // A moving object that appears or goes is a change of light too (a lantern's core is in no light pool).
    let objects_came_or_went = gpu_objects.as_ref().is_some_and(|o| o.set_changed);
    let restart = gpu_lights.as_ref().is_some_and(|l| l.changed) || objects_came_or_went || cache.lighting != lighting;
    cache.lighting = lighting;
    cache.restarts += restart as u32;
    let max_binding = device.limits().max_storage_buffer_binding_size;
    let shape = Shape::of(&gi, max_binding);
    if shape.halved(&gi) && shape != cache.shape {
        warn!(
            "gi_table={} with gi_rays={} needs more than this GPU binds in one buffer ({max_binding} bytes): the GI \
             table holds {} slots",
            static_capacity(&gi),
            gi.rays,
            shape.static_entries
        );
    }
    if shape != cache.shape || gpu_world.as_ref().is_some_and(|w| w.replaced) || cache.seed != settings.seed {
        cache.seed = settings.seed;
        cache.reset(&device, shape);
    }
    // A fresh cache's entries are all young: each frame's light has travelled one bounce more, and their
    // blends average what came before it (update.wgsl), so a room lit over many bounces starts dark. More
    // iterations a frame while it warms up bring the next bounces within the same frame.
    cache.iterations = if restart {
        RESTART_ITERATIONS
    } else if cache.warm_up_frames > 0 && gi.warm_up {
        WARM_UP_ITERATIONS
    } else {
        1
    };
    cache.warm_up_frames = cache.warm_up_frames.saturating_sub(1);
    // The edit log reaches the GPU only in frames that add to it (a reset empties it: edit_count 0 reads none).
    let mut log_changed = false;
    if let Some(world) = &gpu_world {
        log_changed = !world.edited_bricks.is_empty();
        cache.log_edits(&world.edited_bricks);
    }
    // An edit changes the light of every entry near it, most of them a bounce or two away from the edit itself:
    // their blends restart for a few frames (GI_EDIT_RESTART) so the new light is not averaged with the frames it
    // takes to arrive (an opened doorway: 89% of its light after 30 frames before, docs/bench/gi.md).
    if log_changed {
        cache.edit_restart_frames = EDIT_RESTART_FRAMES;
    }
    let edit_restart = cache.edit_restart_frames > 0;
    cache.edit_restart_frames = cache.edit_restart_frames.saturating_sub(1);
    cache.enabled = gi.enabled;
    cache.frame = cache.frame.wrapping_add(1);
    let flag = |on: bool, bit: u32| if on { bit } else { 0 };
    let params = GiParams {
        enabled: gi.enabled as u32,
        flags: flag(gi.filter, GI_FILTER)
            | flag(gi.bounces, GI_BOUNCES)
            | flag(gi.cache, GI_CACHE)
            | flag(restart, GI_RESTART)
            | flag(edit_restart, GI_EDIT_RESTART)
            | flag(gi.qmc, GI_QMC),
        rays: shape.rays,
        // With cached hits an entry re-shades at most its K directions a frame; fresh ones are drawn as many as asked.
        update_rays: if gi.cache { gi.update_rays.clamp(1, shape.rays) } else { gi.update_rays.max(1) },
        alpha: gi.alpha,
        epoch: cache.epoch,
        lost_epoch: cache.lost_epoch,
        edit_count: cache.log.len() as u32,
        static_capacity: shape.static_entries,
        dynamic_capacity: shape.dynamic_entries,
        frame: cache.frame.wrapping_add(cache.seed.wrapping_mul(SEED_FRAMES)),
        iteration: 0,
        cell_pixels: gi.cell_pixels as f32,
        update_run: cache.update_run.wrapping_add(cache.seed.wrapping_mul(SEED_FRAMES)),
        _pad: [0; 2],
    };
    cache.update_run = cache.update_run.wrapping_add(cache.iterations);
    queue.write_buffer(&cache.params, 0, bytemuck::bytes_of(&params));
    queue.write_buffer(&cache.tables.work, 0, bytemuck::cast_slice(&EMPTY_WORK));
    if log_changed {
        let log: Vec<GiEdit> = cache.log.iter().copied().collect();
        queue.write_buffer(&cache.edits, 0, bytemuck::cast_slice(&log));
    }
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
            t.direct.as_entire_binding(),
            t.work.as_entire_binding(),
            t.list.as_entire_binding(),
        )),
    ));
}

/// Update iterations (update + filter, each one bounce more) in the frame after a change of light, started from
/// zero indirect light (GI_RESTART): the frame shows the new light with this many bounces and none of the old.
pub const RESTART_ITERATIONS: u32 = 4;
/// Frames of a fresh cache's warm-up (a world loaded, the cache's shape or seed changed), and its update
/// iterations a frame.
pub const WARM_UP_FRAMES: u32 = 64;
const WARM_UP_ITERATIONS: u32 = 4;
/// Direct-light samples an entry starts over with after a change of light (`RESTART_SAMPLES` in
/// shaders/gi/direct.wgsl, a shader def).
pub const RESTART_DIRECT_SAMPLES: u32 = 8;
/// Frames the entries an edit reached restart their blends.
const EDIT_RESTART_FRAMES: u32 = 6;

/// Adds the cache and its preparation to the render app (its passes are in `frame::world_frame`).
pub fn add(render_app: &mut SubApp) {
    render_app
        .insert_resource(GiLayout(gi_bind_group_layout()))
        .add_systems(RenderStartup, init_gi_cache)
        .add_systems(Render, prepare_gi.after(SceneUploaded).in_set(RenderSystems::PrepareResources));
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A table whose rays would not fit one binding halves until they do; one that fits keeps its setting.
    #[test]
    fn the_table_shrinks_to_what_the_device_binds() {
        let settings = |rays: u32| GiSettings { enabled: true, rays, cache: true, ..GiSettings::default() };
        let lavapipe = 128 << 20;
        assert_eq!(Shape::of(&settings(64), lavapipe).static_entries, 1 << 18);
        let shrunk = Shape::of(&settings(128), lavapipe);
        assert_eq!(shrunk.static_entries, 1 << 17);
        assert!((shrunk.entries() as u64) * 128 * RAY_BYTES <= lavapipe);
        assert_eq!(Shape::of(&settings(128), 1 << 10).static_entries, 4096, "never below 4,096 slots");
        assert!(shrunk.halved(&settings(128)) && !Shape::of(&settings(64), lavapipe).halved(&settings(64)));
        // Without the visibility cache no hits are kept: the whole table fits whatever K.
        let fresh = GiSettings { enabled: true, rays: 128, cache: false, ..GiSettings::default() };
        assert_eq!(Shape::of(&fresh, lavapipe).static_entries, 1 << 18);
        assert_eq!(Shape::of(&fresh, lavapipe).rays, 1);
        // GI off holds a one-slot placeholder: not a table cut to fit (the soak warned "holds 1 slots").
        let off = GiSettings { enabled: false, ..GiSettings::default() };
        assert!(!Shape::of(&off, lavapipe).halved(&off));
    }
}
