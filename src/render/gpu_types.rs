//! The CPU/GPU contract in one place: every struct a buffer holds, with its size checked at compile time, and
//! one table of every constant, mode, flag, counter index and bit width the WGSL shares with Rust. The table
//! reaches the shaders as shader defs, which `shaders/lib/constants.wgsl` (and only it) turns into WGSL
//! constants of the same names; no number is written on both sides.

use crate::dynamic::MAX_OBJECT_ID;
use crate::dynamic::model::MAX_MODEL_EDGE;
use crate::lights::index;
use crate::settings::{DebugView, Lighting};
use crate::world::grid::{BRICK_SIZE, BRICK_VOXELS, MAX_WORLD_EDGE, POOLED_FLAG};
use crate::world::occupancy;
use crate::world::traversal::RAY_OFFSET_INVERSE;
use bevy::shader::ShaderDefVal;

/// Group 0, binding 0 (`WorldInfo` in `shaders/lib/world.wgsl`): the world's size and the moving-object count
/// every trace loops over.
#[derive(Clone, Copy, Debug, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct WorldInfo {
    /// World size in voxels.
    pub size: [i32; 3],
    pub object_count: u32,
    /// World size in bricks.
    pub bricks: [i32; 3],
    /// Where the pool slots' voxel masks start in the occupancy buffer (`VOXEL_MASK_WORDS` a slot).
    pub voxel_mask_base: u32,
    /// Sector grid size (4^3 bricks each) and where the sector masks start in the occupancy buffer.
    pub sectors: [i32; 3],
    pub sector_base: u32,
    /// Region grid size (4^3 sectors each) and where the region masks start.
    pub regions: [i32; 3],
    pub region_base: u32,
    /// The voxels `[occupied_lo, occupied_hi)` that may hold a solid one (`BrickGrid::occupied_box`): the
    /// occupancy walk starts where a ray enters it and misses where it leaves.
    pub occupied_lo: [i32; 3],
    /// Pool slots per part of the brick pool, as a shift (`render::scene::world::pool_part_shift`): slot `s` is slot
    /// `s & (2^shift - 1)` of part `s >> shift`. `ONE_POOL_PART` keeps every slot in the first.
    pub pool_part_shift: u32,
    pub occupied_hi: [i32; 3],
    pub _pad_hi: u32,
    /// The world coordinates of voxel (0, 0, 0) (`VoxelWorld::detail_origin`): per-voxel detail hashes world
    /// coordinates, so a window of the endless world shades each voxel as it would anywhere else.
    pub detail_origin: [i32; 3],
    pub _pad_detail: u32,
    /// The window's voxels `[window_lo, window_hi)` (`BrickGrid::window`; `[0, size)` in a bounded world) and the
    /// voxel stored first before the wrap (`BrickGrid::wrap_base`): a brick is stored at its offset from
    /// `wrap_base`, less the grid where that reaches past it, so a scroll rewrites only the bricks that enter.
    pub window_lo: [i32; 3],
    pub _pad_window_lo: u32,
    pub window_hi: [i32; 3],
    pub _pad_window_hi: u32,
    pub wrap_base: [i32; 3],
    pub _pad_wrap: u32,
}

/// A grid's window and where its storage wraps (`BrickGrid::window`, `BrickGrid::wrap_base`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GridWindow {
    pub lo: bevy::math::IVec3,
    pub hi: bevy::math::IVec3,
    pub wrap_base: bevy::math::IVec3,
}

impl GridWindow {
    pub fn of(grid: &crate::world::grid::BrickGrid) -> Self {
        let (lo, hi) = grid.window();
        GridWindow { lo, hi, wrap_base: grid.wrap_base() }
    }
}

/// All zero but the pool's part shift: a pool in one buffer (a shift of 0 would put every slot in a part of its own).
impl Default for WorldInfo {
    fn default() -> Self {
        WorldInfo { pool_part_shift: ONE_POOL_PART, ..bytemuck::Zeroable::zeroed() }
    }
}

impl WorldInfo {
    /// This info with the occupied box `(lo, hi)`.
    pub fn with_occupied(self, (lo, hi): (bevy::math::IVec3, bevy::math::IVec3)) -> Self {
        WorldInfo { occupied_lo: lo.to_array(), occupied_hi: hi.to_array(), ..self }
    }

    /// This info with the window `[lo, hi)` stored from `wrap_base` (`BrickGrid::window`, `wrap_base`).
    pub fn with_window(self, window: GridWindow) -> Self {
        WorldInfo {
            window_lo: window.lo.to_array(),
            window_hi: window.hi.to_array(),
            wrap_base: window.wrap_base.to_array(),
            ..self
        }
    }
}

/// One material (`Material` in `shaders/lib/world.wgsl`), indexed by voxel id (entry 0 is air).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuMaterial {
    /// Linear albedo (rgb) and the material's per-voxel variation (w).
    pub albedo: [f32; 4],
    pub radiance: [f32; 4],
}

/// One moving object (`Object` in `shaders/lib/world.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuObject {
    /// World position of the model's minimum corner.
    pub min: [f32; 3],
    pub id: u32,
    pub size: [u32; 3],
    /// First voxel in `object_voxels`.
    pub offset: u32,
    /// `min` last frame (the same for an object that just appeared): the denoiser reprojects its pixels by it.
    pub previous_min: [f32; 3],
    pub _pad: u32,
}

/// One light slot (`Light` in `shaders/lib/lights.wgsl`); `size == 0` marks a free slot.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuLight {
    pub min: [i32; 3],
    /// Edge in voxels (bits 0-7; 0 marks a free slot) and the exposed-face mask (bit `LIGHT_FACES_SHIFT + f`).
    pub size_faces: i32,
    pub radiance: [f32; 3],
    pub generation: u32,
}

/// `GpuLight::size_faces`: the edge in the low bits, the exposed-face mask above them.
pub const LIGHT_FACES_SHIFT: u32 = 8;
pub const LIGHT_SIZE_MASK: u32 = (1 << LIGHT_FACES_SHIFT) - 1;
// A brick light's edge must fit below the face mask.
const _: () = assert!(crate::world::grid::BRICK_SIZE as u32 <= LIGHT_SIZE_MASK);

/// Group 2, binding 2 (`SceneLighting` in `shaders/lib/lights.wgsl`): how the scene is lit this frame, the
/// same for every camera and for the GI cache.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct SceneLighting {
    /// xyz: unit direction towards the sun (or the moon at night); w: 1 when its disk gives light.
    pub sun: [f32; 4],
    /// rgb: the disk's irradiance over pi (`lights::daylight::Daylight::disk`); w: its cone, 1 - cos(radius).
    pub sun_radiance: [f32; 4],
    pub sky_zenith: [f32; 4],
    pub sky_horizon: [f32; 4],
    /// `LIGHTING_*`.
    pub mode: u32,
    /// 1: pick lights by power (alias table); 0: uniformly.
    pub power_pick: u32,
    pub light_count: u32,
    pub shadows: u32,
}

/// Group 1, binding 2 (`FrameParams` in `shaders/lib/frame.wgsl`): one view's parameters this frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct FrameParams {
    /// Last frame's clip_from_world (temporal reprojection).
    pub prev_clip_from_world: [[f32; 4]; 4],
    /// Last frame's camera position; w = 1 when last frame's G-buffer and reservoirs may be reused.
    pub prev_camera: [f32; 4],
    /// `DEBUG_*`.
    pub debug_view: u32,
    pub exposure: f32,
    /// Frame number, seeds the per-pixel random numbers.
    pub frame: u32,
    /// Frames averaged including this one; 1 restarts the average.
    pub accumulated: u32,
    /// Targeted voxel (xyz) and face + 1 (w; 0 = none).
    pub highlight_target: [i32; 4],
    /// Box selection corners, inclusive; `selection_min.w` is 1 when a selection is shown.
    pub selection_min: [i32; 4],
    pub selection_max: [i32; 4],
    /// Voxel ReSTIR: M_init, spatial taps, radius in pixels, `RESTIR_*` flags.
    pub candidates: u32,
    pub taps: u32,
    pub radius: f32,
    pub restir_flags: u32,
    /// `DENOISE_*` flags: the denoiser runs; its history (last frame's) may be reused.
    pub denoise: u32,
    /// `UPSCALE_*` flags: the lighting passes run below the output's resolution; the upscaler's history holds.
    pub upscale: u32,
    /// The lighting passes' pixels (the output's at render scale 1).
    pub render_size: [u32; 2],
    /// Where in its footprint each render pixel takes its output pixel this frame, in [0, 1) per axis.
    pub jitter: [f32; 2],
    pub _pad: [u32; 2],
}

/// Group 3, binding 0 (`GiParams` in `shaders/gi/cache.wgsl`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GiParams {
    pub enabled: u32,
    /// `GI_*` flags.
    pub flags: u32,
    pub rays: u32,
    pub update_rays: u32,
    pub alpha: f32,
    pub epoch: u32,
    pub lost_epoch: u32,
    pub edit_count: u32,
    pub static_capacity: u32,
    pub dynamic_capacity: u32,
    pub frame: u32,
    /// Which of this frame's update iterations runs (0 but in the frames after a change of light); the GPU
    /// copies it in between the iterations.
    pub iteration: u32,
    /// `gi_cell`: a camera's cells span at least this many pixels.
    pub cell_pixels: f32,
    /// Update iterations run before this frame's (offset per `seed`): where fresh rays continue the entries'
    /// low-discrepancy sequences.
    pub update_run: u32,
    /// Frames between two updates of a settled entry this frame (`FramePlan::settled_period`).
    pub period: u32,
    pub _pad: u32,
}

/// One GI cache entry's payload (`GiEntry` in `shaders/gi/cache.wgsl`); only the GPU writes it, Rust sizes it.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GiEntry {
    pub voxel: [i32; 3],
    pub face: u32,
    pub last_used: u32,
    pub traced_epoch: u32,
    pub samples: u32,
    pub object: u32,
    pub lo: [f32; 3],
    pub last_seen: u32,
    pub hi: [f32; 3],
    /// Level of detail: the entry covers a 2^level voxel cell.
    pub level: u32,
}

/// One GI entry's reservoir of light samples (`GiReservoir` in `shaders/gi/cache.wgsl`); only the GPU writes it,
/// Rust sizes it.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GiReservoir {
    pub slot: u32,
    pub generation: u32,
    pub face: u32,
    pub uv: u32,
    pub w_sum: f32,
    pub m: f32,
    pub big_w: f32,
    pub _pad: f32,
}

const _: () = assert!(size_of::<GiReservoir>() == 32);

/// One GI entry's direct light, its reservoir and its rays' guide (`GiDirect` in `shaders/gi/cache.wgsl`, the
/// `gi_direct` buffer).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GiDirect {
    pub light: [f32; 4],
    pub reservoir: GiReservoir,
    /// Where the entry's bounce light came from: 16 bins of the cosine lobe, two 16-bit floats a word
    /// (`shaders/gi/guide.wgsl`, `gi_guiding`).
    pub guide: [u32; 8],
}

const _: () = assert!(size_of::<GiDirect>() == 80);

/// One edit-log record (two `vec4<i32>` in `gi_edits`): an edited brick's box and the epoch of the edit.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GiEdit {
    pub min: [i32; 3],
    pub epoch: i32,
    /// Exclusive.
    pub max: [i32; 3],
    pub _pad: i32,
}

/// A G-buffer texel (`vec4<f32>` in `shaders/lib/frame.wgsl`): hit point and the packed hit.
pub const GBUFFER_TEXEL_BYTES: u64 = 16;
/// Regions of the output's pixels in each G-buffer (`shaders/lib/frame.wgsl`): the lighting passes' texels, then
/// below render scale 1 the output's own, the upscaler's history (demodulated light, length) and its history of
/// the disk's visibility.
pub const GBUFFER_REGIONS: u64 = 4;
/// A reservoir (`Reservoir` in `shaders/restir/common.wgsl`): light slot, generation, sample, w_sum, M, W and
/// the target at the sample.
pub const RESERVOIR_BYTES: u64 = 32;
/// An accumulation texel (rgb sum, `vec4<f32>`).
pub const ACCUMULATION_TEXEL_BYTES: u64 = 16;
/// The denoiser's per-pixel texels (`vec4<f32>`): the noisy frame (one), the history (two: colour and length,
/// moments), the wavelet's ping-pong (two: colour and variance).
pub const DENOISE_TEXEL_BYTES: u64 = 16;
/// A GI entry's radiance (blended or filtered, `vec4<f32>`) and a GI table key (`u32`).
pub const GI_RADIANCE_BYTES: u64 = 16;
pub const GI_KEY_BYTES: u64 = 4;
/// A cached GI ray (face hit, starting voxel in its cell and distance packed in a u32: `shaders/gi/cache.wgsl`).
pub const GI_RAY_BYTES: u64 = 4;

/// The GI work buffer (`gi_work` in `shaders/gi/cache.wgsl`, written by compact.wgsl), in u32 words: per table
/// (static, then dynamic) an indirect dispatch size x, y, z and the count of entries listed. The dispatches read
/// x, y, z at `4 * GI_WORK_STATIC_WORD` and `4 * GI_WORK_DYNAMIC_WORD` bytes.
pub const GI_WORK_STATIC_WORD: u32 = 0;
pub const GI_WORK_DYNAMIC_WORD: u32 = 4;
/// The count's word within a table's four.
pub const GI_WORK_COUNT_WORD: u32 = 3;
pub const GI_WORK_WORDS: u32 = 8;
const _: () = assert!(GI_WORK_STATIC_WORD + GI_WORK_COUNT_WORD < GI_WORK_DYNAMIC_WORD);
const _: () = assert!(GI_WORK_DYNAMIC_WORD + GI_WORK_COUNT_WORD < GI_WORK_WORDS);
/// What the work buffer holds before compaction: no workgroups (y = z = 1, so x alone decides) and nothing listed.
pub const GI_EMPTY_WORK: [u32; GI_WORK_WORDS as usize] = {
    let mut work = [0; GI_WORK_WORDS as usize];
    let tables = [GI_WORK_STATIC_WORD as usize, GI_WORK_DYNAMIC_WORD as usize];
    let mut t = 0;
    while t < tables.len() {
        work[tables[t] + 1] = 1;
        work[tables[t] + 2] = 1;
        t += 1;
    }
    work
};

// The shaders read these structs at exactly these sizes (WGSL alignment rules included).
const _: () = assert!(size_of::<WorldInfo>() == 160);
const _: () = assert!(size_of::<GpuMaterial>() == 32);
const _: () = assert!(size_of::<GpuObject>() == 48);
const _: () = assert!(size_of::<GpuLight>() == 32);
const _: () = assert!(size_of::<crate::lights::AliasEntry>() == 16);
const _: () = assert!(size_of::<SceneLighting>() == 80);
const _: () = assert!(size_of::<FrameParams>() == 192);
const _: () = assert!(size_of::<GiParams>() == 64);
const _: () = assert!(size_of::<GiEntry>() == 64);
const _: () = assert!(size_of::<GiEdit>() == 32);

/// What the counters buffer counts (`COUNT_*`; group 0, `shaders/lib/counters.wgsl`). The first
/// `PER_FRAME_COUNTERS` restart every frame, the rest count since the renderer started.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GpuCounter {
    /// GI entries re-shaded this frame.
    GiUpdated = 0,
    /// GI entries with at least one of their K static hits (re)traced this frame.
    GiRetraced = 1,
    /// GI entries in the tables.
    GiLive = 2,
    /// GI entries freed after going unused.
    GiEvicted = 3,
    /// GI inserts that found their probe window full.
    GiFull = 4,
    /// GI entries inserted this frame.
    GiInserted = 5,
    /// Static GI rays traced to (re)fill the cached hits this frame.
    GiRaysTraced = 6,
    /// GI ray hits whose face had no cached value and borrowed the shooting entry's indirect light.
    GiBorrowed = 7,
    /// GI ray hits whose face had no direct-light estimate yet and traced their own shadow ray.
    GiDirectTraced = 8,
    /// Brick-grid rays (walks of the world's DDA) the primary pass traced this frame.
    RaysPrimary = 9,
    /// Brick-grid rays ReSTIR's candidates' visibility and temporal pass (restir/temporal.wgsl) traced this frame.
    RaysRestirInitial = 10,
    /// Brick-grid rays ReSTIR's spatial pass traced this frame.
    RaysRestirSpatial = 11,
    /// Brick-grid rays ReSTIR's shading pass traced this frame.
    RaysRestirShade = 12,
    /// Pixels whose primary ray hit a voxel this frame (the pixels direct light is computed for).
    PrimaryHits = 13,
    /// Traversal steps (the walk's loop steps: a brick or voxel of the DDA, a cell left by the occupancy walk) of
    /// the per-pixel passes' rays this frame.
    TraceSteps = 14,
    /// Memory loads of the same rays' traversal (masks, top cells, voxels; a mask bit a ray holds is not one).
    TraceLoads = 15,
    /// Brick-grid rays the GI cache's refresh and update passes traced this frame (cached hits, fresh
    /// directions, the entries' own shadow rays).
    RaysGi = 16,
    /// Brick-grid rays the upscaler traced this frame: the disk's shadow rays of output pixels on a shadow edge.
    RaysUpscale = 17,
    /// Since the start: ReSTIR reservoirs read with a non-finite field (reset to empty).
    ReservoirResets = 18,
    /// Since the start: GI estimates that came out non-finite (replaced by zero).
    GiResets = 19,
    /// Since the start: GI entries freed (unused, their object gone, or their face lost to an edit).
    GiFreedTotal = 20,
}

impl GpuCounter {
    pub const ALL: [(GpuCounter, &'static str); COUNTERS] = [
        (GpuCounter::GiUpdated, "COUNT_GI_UPDATED"),
        (GpuCounter::GiRetraced, "COUNT_GI_RETRACED"),
        (GpuCounter::GiLive, "COUNT_GI_LIVE"),
        (GpuCounter::GiEvicted, "COUNT_GI_EVICTED"),
        (GpuCounter::GiFull, "COUNT_GI_FULL"),
        (GpuCounter::GiInserted, "COUNT_GI_INSERTED"),
        (GpuCounter::GiRaysTraced, "COUNT_GI_RAYS_TRACED"),
        (GpuCounter::GiBorrowed, "COUNT_GI_BORROWED"),
        (GpuCounter::GiDirectTraced, "COUNT_GI_DIRECT_TRACED"),
        (GpuCounter::RaysPrimary, "COUNT_RAYS_PRIMARY"),
        (GpuCounter::RaysRestirInitial, "COUNT_RAYS_RESTIR_INITIAL"),
        (GpuCounter::RaysRestirSpatial, "COUNT_RAYS_RESTIR_SPATIAL"),
        (GpuCounter::RaysRestirShade, "COUNT_RAYS_RESTIR_SHADE"),
        (GpuCounter::PrimaryHits, "COUNT_PRIMARY_HITS"),
        (GpuCounter::TraceSteps, "COUNT_TRACE_STEPS"),
        (GpuCounter::TraceLoads, "COUNT_TRACE_LOADS"),
        (GpuCounter::RaysGi, "COUNT_RAYS_GI"),
        (GpuCounter::RaysUpscale, "COUNT_RAYS_UPSCALE"),
        (GpuCounter::ReservoirResets, "COUNT_RESERVOIR_RESETS"),
        (GpuCounter::GiResets, "COUNT_GI_RESETS"),
        (GpuCounter::GiFreedTotal, "COUNT_GI_FREED_TOTAL"),
    ];
}

/// Words in the counters buffer, and how many of the first ones restart every frame.
pub const COUNTERS: usize = 21;
pub const PER_FRAME_COUNTERS: usize = 18;
const _: () = assert!(GpuCounter::RaysUpscale as usize + 1 == PER_FRAME_COUNTERS);
const _: () = assert!((GpuCounter::GiFreedTotal as usize) < COUNTERS);

/// `restir_flags` bits.
pub const RESTIR_TEMPORAL: u32 = 1;
pub const RESTIR_SPATIAL: u32 = 2;
pub const RESTIR_POINT: u32 = 4;
pub const RESTIR_UNBIASED: u32 = 8;
pub const RESTIR_ONE_RAY: u32 = 16;
/// Some candidates are drawn among the lights beside the shaded face (`local_lights`).
pub const RESTIR_LOCAL: u32 = 32;
/// The initial pass tests its chosen candidate's visibility (`initial_visibility`).
pub const RESTIR_INITIAL_VISIBILITY: u32 = 64;
/// The initial pass draws its candidates from this frame's light tiles (`light_tiles`).
pub const RESTIR_LIGHT_TILES: u32 = 128;
/// Light tiles: how many, and lights in each (a power of two). A tile is 12 KB the 16 lanes of a 4x4 pixel
/// block share; tiles x size draws per frame is small beside the candidates (57,600 pixels x 32 at 320x180).
pub const LIGHT_TILES: u32 = 32;
pub const LIGHT_TILE_SIZE: u32 = 1024;
const _: () = assert!(LIGHT_TILE_SIZE.is_power_of_two());

/// A light of a light tile (`TileLight` in `shaders/restir/common.wgsl`): a copy of the light slot, the slot, and
/// the power pick's probability of it. Written by the GPU only; the Rust side is its layout.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuTileLight {
    pub light: GpuLight,
    pub slot: u32,
    pub pdf: f32,
    /// WGSL rounds the struct up to its 16-byte alignment.
    pub _pad: [u32; 2],
}

pub const TILE_LIGHT_BYTES: u64 = size_of::<GpuTileLight>() as u64;
/// `FrameParams::denoise`: the denoiser runs this frame.
pub const DENOISE_ON: u32 = 1;
/// `FrameParams::denoise`: last frame's denoiser history is valid (same size, nothing in the scene changed).
pub const DENOISE_HISTORY: u32 = 2;

/// `FrameParams::upscale`: the lighting passes run at the render size and the upscaler writes the image.
pub const UPSCALE_ON: u32 = 1;
/// `FrameParams::upscale`: last frame's upscaled history is valid (nothing in the scene changed).
pub const UPSCALE_HISTORY: u32 = 2;

/// `GiParams::flags` bits.
pub const GI_FILTER: u32 = 1;
pub const GI_BOUNCES: u32 = 2;
pub const GI_CACHE: u32 = 4;
/// `GiParams::flags`: the light changed this frame (a lamp placed or removed, the time of day, the lighting
/// mode): entries start over. Their direct light from several samples; their indirect light from zero, the
/// update iterating (one bounce more each) and taking the last iteration's estimate alone; from there they
/// average as young entries do.
pub const GI_RESTART: u32 = 8;
/// `GiParams::flags`: the world was edited in the last few frames: entries an edit reached (refresh.wgsl marks
/// them with one sample) take this frame's estimate alone, so their average starts once the new light has
/// travelled the bounces, not with the frames in between.
pub const GI_EDIT_RESTART: u32 = 16;
/// `GiParams::flags`: fresh rays and direct-light points from each entry's low-discrepancy sequence (`gi_qmc`).
pub const GI_QMC: u32 = 32;
/// `GiParams::flags`: entries draw their light-pool light through reservoirs kept from frame to frame
/// (`gi_reservoirs`, `shaders/gi/reservoir.wgsl`).
pub const GI_RESERVOIRS: u32 = 64;
/// `GiParams::flags`: fresh rays drawn from a mixture of the cosine lobe and each entry's learnt histogram of
/// incoming light (`gi_guiding`, `shaders/gi/guide.wgsl`).
pub const GI_GUIDING: u32 = 128;
/// The filtered colour of a GI entry that holds no value yet (radiance is never negative): the tables start with
/// it and `forget_value` (`shaders/gi/cache.wgsl`) writes it back. An integer, as the shared table holds them.
pub const GI_NO_VALUE: i32 = -1;
/// Direct-light samples a GI entry starts over with after a change of light (`RESTART_SAMPLES` in
/// `shaders/gi/direct.wgsl`).
pub const GI_RESTART_DIRECT_SAMPLES: u32 = 8;

/// The brick pool's part shift that keeps every slot in the first part (`WorldInfo::pool_part_shift`).
pub const ONE_POOL_PART: u32 = 31;

/// The G-buffer's packed hit: bit 0 hit, bits 1-3 face, bits 4-19 material, bits 20-31 the moving object's id.
pub const GBUFFER_FACE_SHIFT: u32 = 1;
pub const GBUFFER_MATERIAL_SHIFT: u32 = 4;
pub const GBUFFER_MATERIAL_BITS: u32 = 16;
pub const GBUFFER_OBJECT_SHIFT: u32 = GBUFFER_MATERIAL_SHIFT + GBUFFER_MATERIAL_BITS;
pub const GBUFFER_OBJECT_BITS: u32 = 32 - GBUFFER_OBJECT_SHIFT;
// Every object id must fit in its G-buffer bits, and every material id in its.
const _: () = assert!(MAX_OBJECT_ID < 1 << GBUFFER_OBJECT_BITS);
const _: () = assert!(crate::world::palette::MAX_MATERIALS < 1 << GBUFFER_MATERIAL_BITS);

/// Spatial taps a ReSTIR pixel merges at most (the `taps` setting's upper end).
pub const MAX_TAPS: u32 = crate::settings::MAX_TAPS;

/// A constant's value as a shader def.
#[derive(Clone, Copy, Debug)]
pub enum Shared {
    U32(u32),
    I32(i32),
}

const _: () = assert!(occupancy::BRICK_SHIFT as u32 == BRICK_SIZE.trailing_zeros());

/// Every constant the WGSL shares with Rust, by the name both sides use.
pub fn shared_constants() -> Vec<(&'static str, Shared)> {
    use Shared::{I32, U32};
    let brick_shift = BRICK_SIZE.trailing_zeros();
    let mut table = vec![
        // The brick grid (src/world/grid.rs).
        ("POOLED_FLAG", U32(POOLED_FLAG)),
        ("BRICK_SIZE", I32(BRICK_SIZE)),
        ("BRICK_SHIFT", U32(brick_shift)),
        ("BRICK_WORDS", U32((BRICK_VOXELS / 2) as u32)),
        ("MAX_WORLD_EDGE", U32(MAX_WORLD_EDGE)),
        // The pool's part shift of a pool in one buffer (src/render/scene/world.rs).
        ("ONE_POOL_PART", U32(ONE_POOL_PART)),
        // The occupancy walk's levels (src/world/occupancy.rs): log2 of a brick cell's, a sector's and a
        // region's edge, the walk level of a box of brick cells, and u32 words of a brick's voxel mask.
        ("CELL_SHIFT", U32(occupancy::CELL_SHIFT as u32)),
        ("SECTOR_SHIFT", U32(occupancy::SECTOR_SHIFT as u32)),
        ("REGION_SHIFT", U32(occupancy::REGION_SHIFT as u32)),
        ("CELL_BOX_LEVEL", U32(occupancy::CELL_BOX_LEVEL as u32)),
        ("VOXEL_MASK_WORDS", U32(occupancy::VOXEL_MASK_WORDS as u32)),
        // A moving object's DDA crosses at most three faces per voxel of its largest edge (src/dynamic/model.rs).
        ("OBJECT_TRACE_STEPS", I32(3 * MAX_MODEL_EDGE as i32)),
        // Secondary rays start this far off their surface (the CPU reference uses the same).
        ("RAY_OFFSET_INVERSE", U32(RAY_OFFSET_INVERSE)),
        // A light slot's packed edge and exposed faces.
        ("LIGHT_FACES_SHIFT", U32(LIGHT_FACES_SHIFT)),
        ("LIGHT_SIZE_MASK", U32(LIGHT_SIZE_MASK)),
        // The light index (src/lights/index.rs): its empty entry and its hash's multipliers.
        ("NO_COLUMN", U32(index::NO_COLUMN)),
        ("LIGHT_HASH_X", U32(index::LIGHT_HASH_X)),
        ("LIGHT_HASH_Y", U32(index::LIGHT_HASH_Y)),
        ("LIGHT_HASH_Z", U32(index::LIGHT_HASH_Z)),
        ("LIGHT_HASH_MIX_1", U32(index::LIGHT_HASH_MIX_1)),
        ("LIGHT_HASH_MIX_2", U32(index::LIGHT_HASH_MIX_2)),
        // Face sizes from a light face's centre within which its point is drawn by solid angle (the CPU
        // reference switches at the same distance).
        ("NEAR_FACE", U32(crate::reference::sampling::NEAR_FACE)),
        // Lighting modes and debug views (src/settings).
        ("LIGHTING_SUN", U32(Lighting::Sun as u32)),
        ("LIGHTING_NEE", U32(Lighting::Nee as u32)),
        ("LIGHTING_EMITTERS", U32(Lighting::Emitters as u32)),
        ("LIGHTING_FULL", U32(Lighting::Full as u32)),
        ("DEBUG_NONE", U32(DebugView::None.shader_index())),
        ("DEBUG_ALBEDO", U32(DebugView::Albedo.shader_index())),
        ("DEBUG_NORMAL", U32(DebugView::Normal.shader_index())),
        ("DEBUG_HIT", U32(DebugView::Hit.shader_index())),
        ("DEBUG_DEPTH", U32(DebugView::Depth.shader_index())),
        ("DEBUG_RESERVOIR", U32(DebugView::Reservoir.shader_index())),
        ("DEBUG_VARIANCE", U32(DebugView::Variance.shader_index())),
        ("DEBUG_HISTORY", U32(DebugView::History.shader_index())),
        ("DEBUG_INDIRECT", U32(DebugView::Indirect.shader_index())),
        // Flags.
        ("RESTIR_TEMPORAL", U32(RESTIR_TEMPORAL)),
        ("RESTIR_SPATIAL", U32(RESTIR_SPATIAL)),
        ("RESTIR_POINT", U32(RESTIR_POINT)),
        ("RESTIR_UNBIASED", U32(RESTIR_UNBIASED)),
        ("RESTIR_ONE_RAY", U32(RESTIR_ONE_RAY)),
        ("RESTIR_LOCAL", U32(RESTIR_LOCAL)),
        ("RESTIR_INITIAL_VISIBILITY", U32(RESTIR_INITIAL_VISIBILITY)),
        ("RESTIR_LIGHT_TILES", U32(RESTIR_LIGHT_TILES)),
        ("LIGHT_TILES", U32(LIGHT_TILES)),
        ("LIGHT_TILE_SIZE", U32(LIGHT_TILE_SIZE)),
        ("DENOISE_ON", U32(DENOISE_ON)),
        ("DENOISE_HISTORY", U32(DENOISE_HISTORY)),
        ("UPSCALE_ON", U32(UPSCALE_ON)),
        ("UPSCALE_HISTORY", U32(UPSCALE_HISTORY)),
        ("MAX_TAPS", U32(MAX_TAPS)),
        ("GI_FILTER", U32(GI_FILTER)),
        ("GI_BOUNCES", U32(GI_BOUNCES)),
        ("GI_CACHE", U32(GI_CACHE)),
        ("GI_RESTART", U32(GI_RESTART)),
        ("GI_EDIT_RESTART", U32(GI_EDIT_RESTART)),
        ("GI_QMC", U32(GI_QMC)),
        ("GI_RESERVOIRS", U32(GI_RESERVOIRS)),
        ("GI_GUIDING", U32(GI_GUIDING)),
        ("GI_NO_VALUE", I32(GI_NO_VALUE)),
        ("GI_RESTART_SAMPLES", U32(GI_RESTART_DIRECT_SAMPLES)),
        // The GI work buffer's words.
        ("GI_WORK_STATIC_WORD", U32(GI_WORK_STATIC_WORD)),
        ("GI_WORK_DYNAMIC_WORD", U32(GI_WORK_DYNAMIC_WORD)),
        ("GI_WORK_COUNT_WORD", U32(GI_WORK_COUNT_WORD)),
        // The G-buffer's packed hit.
        ("GBUFFER_FACE_SHIFT", U32(GBUFFER_FACE_SHIFT)),
        ("GBUFFER_MATERIAL_SHIFT", U32(GBUFFER_MATERIAL_SHIFT)),
        ("GBUFFER_MATERIAL_MASK", U32((1 << GBUFFER_MATERIAL_BITS) - 1)),
        ("GBUFFER_OBJECT_SHIFT", U32(GBUFFER_OBJECT_SHIFT)),
    ];
    table.extend(GpuCounter::ALL.iter().map(|&(counter, name)| (name, U32(counter as u32))));
    table
}

/// The shared constants as shader defs, for every voxel pipeline.
pub fn shader_defs() -> Vec<ShaderDefVal> {
    shared_constants()
        .into_iter()
        .map(|(name, value)| match value {
            Shared::U32(v) => ShaderDefVal::UInt(name.into(), v),
            Shared::I32(v) => ShaderDefVal::Int(name.into(), v),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `constants.wgsl` declares every shared constant once, from its def, and no other shader reads a def.
    #[test]
    fn every_shared_constant_reaches_the_wgsl_once_and_only_through_constants_wgsl() {
        let constants = include_str!("../../shaders/lib/constants.wgsl");
        for (name, value) in shared_constants() {
            let suffix = if matches!(value, Shared::U32(_)) { "u" } else { "" };
            let declaration =
                format!("const {name}: {} = #{{{name}}}{suffix};", if suffix == "u" { "u32" } else { "i32" });
            assert_eq!(constants.matches(&declaration).count(), 1, "constants.wgsl lacks `{declaration}`");
        }
        // The pass key's defs (`pass_key`): KEY_GENERIC and one per specialised setting.
        for name in super::super::pass_key::KEY_NAMES.iter().chain(&["KEY_GENERIC"]) {
            let declaration = format!("const {name}: u32 = #{{{name}}}u;");
            assert_eq!(constants.matches(&declaration).count(), 1, "constants.wgsl lacks `{declaration}`");
        }
        let defs = constants.matches("#{").count();
        assert_eq!(
            defs,
            shared_constants().len() + super::super::pass_key::KEY_NAMES.len() + 1,
            "constants.wgsl reads a def the table does not have"
        );
        for (path, source) in super::super::shaders::SOURCES {
            if !path.ends_with("constants.wgsl") {
                assert!(!source.contains("#{"), "{path} reads a shader def; use glowbrick::constants instead");
            }
        }
    }

    #[test]
    fn names_are_unique() {
        let mut names: Vec<&str> = shared_constants().iter().map(|(n, _)| *n).collect();
        names.sort();
        let count = names.len();
        names.dedup();
        assert_eq!(names.len(), count);
    }
}
