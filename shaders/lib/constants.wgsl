// Every constant the shaders share with Rust, from the one table in src/render/gpu_types.rs (shader defs). This
// is the only WGSL file that reads a shader def: import the names from here, never write the numbers again.
#define_import_path glowbrick::constants

// The brick grid (src/world/grid.rs): top-cell flag of a pooled brick, brick edge, log2 of it, u32 words per brick,
// the largest world edge.
const POOLED_FLAG: u32 = #{POOLED_FLAG}u;
const BRICK_SIZE: i32 = #{BRICK_SIZE};
const BRICK_SHIFT: u32 = #{BRICK_SHIFT}u;
const BRICK_WORDS: u32 = #{BRICK_WORDS}u;
const MAX_WORLD_EDGE: u32 = #{MAX_WORLD_EDGE}u;
// The brick pool's part shift when it is one buffer (src/render/scene/world.rs).
const ONE_POOL_PART: u32 = #{ONE_POOL_PART}u;
// The occupancy walk (src/world/occupancy.rs): log2 of a brick cell's, a sector's and a region's edge (a brick's is
// BRICK_SHIFT), the walk level of a box of brick cells, u32 words of a brick's voxel mask.
const CELL_SHIFT: u32 = #{CELL_SHIFT}u;
const SECTOR_SHIFT: u32 = #{SECTOR_SHIFT}u;
const REGION_SHIFT: u32 = #{REGION_SHIFT}u;
const CELL_BOX_LEVEL: u32 = #{CELL_BOX_LEVEL}u;
const VOXEL_MASK_WORDS: u32 = #{VOXEL_MASK_WORDS}u;
// A moving object's DDA steps at most (three per voxel of the largest model edge, src/dynamic/model.rs).
const OBJECT_TRACE_STEPS: i32 = #{OBJECT_TRACE_STEPS};

// Secondary rays start RAY_OFFSET off their surface (src/world/traversal.rs; the CPU reference uses the same).
const RAY_OFFSET_INVERSE: u32 = #{RAY_OFFSET_INVERSE}u;
const RAY_OFFSET: f32 = 1.0 / f32(RAY_OFFSET_INVERSE);
const PI: f32 = 3.14159265;

// A light slot's packed edge (low bits) and exposed-face mask (src/render/gpu_types.rs, GpuLight).
const LIGHT_FACES_SHIFT: u32 = #{LIGHT_FACES_SHIFT}u;
const LIGHT_SIZE_MASK: u32 = #{LIGHT_SIZE_MASK}u;

// The light index (src/lights/index.rs): an empty entry, and light_hash's multipliers (per coordinate, then
// murmur3's finaliser).
const NO_COLUMN: u32 = #{NO_COLUMN}u;
const LIGHT_HASH_X: u32 = #{LIGHT_HASH_X}u;
const LIGHT_HASH_Y: u32 = #{LIGHT_HASH_Y}u;
const LIGHT_HASH_Z: u32 = #{LIGHT_HASH_Z}u;
const LIGHT_HASH_MIX_1: u32 = #{LIGHT_HASH_MIX_1}u;
const LIGHT_HASH_MIX_2: u32 = #{LIGHT_HASH_MIX_2}u;

// Within NEAR_FACE face sizes of a light face's centre, its point is drawn by solid angle, not by area
// (src/reference/sampling.rs switches at the same distance).
const NEAR_FACE: u32 = #{NEAR_FACE}u;

// Lighting modes and debug views (src/settings.rs).
const LIGHTING_SUN: u32 = #{LIGHTING_SUN}u;
const LIGHTING_NEE: u32 = #{LIGHTING_NEE}u;
const LIGHTING_EMITTERS: u32 = #{LIGHTING_EMITTERS}u;
const LIGHTING_FULL: u32 = #{LIGHTING_FULL}u;
const DEBUG_NONE: u32 = #{DEBUG_NONE}u;
const DEBUG_ALBEDO: u32 = #{DEBUG_ALBEDO}u;
const DEBUG_NORMAL: u32 = #{DEBUG_NORMAL}u;
const DEBUG_HIT: u32 = #{DEBUG_HIT}u;
const DEBUG_DEPTH: u32 = #{DEBUG_DEPTH}u;
const DEBUG_RESERVOIR: u32 = #{DEBUG_RESERVOIR}u;
const DEBUG_VARIANCE: u32 = #{DEBUG_VARIANCE}u;
const DEBUG_HISTORY: u32 = #{DEBUG_HISTORY}u;
const DEBUG_INDIRECT: u32 = #{DEBUG_INDIRECT}u;

// FrameParams.restir_flags bits and the largest spatial tap count.
const RESTIR_TEMPORAL: u32 = #{RESTIR_TEMPORAL}u;
const RESTIR_SPATIAL: u32 = #{RESTIR_SPATIAL}u;
const RESTIR_POINT: u32 = #{RESTIR_POINT}u;
const RESTIR_UNBIASED: u32 = #{RESTIR_UNBIASED}u;
const RESTIR_ONE_RAY: u32 = #{RESTIR_ONE_RAY}u;
const RESTIR_LOCAL: u32 = #{RESTIR_LOCAL}u;
const RESTIR_INITIAL_VISIBILITY: u32 = #{RESTIR_INITIAL_VISIBILITY}u;
const RESTIR_LIGHT_TILES: u32 = #{RESTIR_LIGHT_TILES}u;
// Light tiles (restir/tiles.wgsl): how many, and lights in each (a power of two).
const LIGHT_TILES: u32 = #{LIGHT_TILES}u;
const LIGHT_TILE_SIZE: u32 = #{LIGHT_TILE_SIZE}u;
const DENOISE_ON: u32 = #{DENOISE_ON}u;
const DENOISE_HISTORY: u32 = #{DENOISE_HISTORY}u;
const UPSCALE_ON: u32 = #{UPSCALE_ON}u;
const UPSCALE_HISTORY: u32 = #{UPSCALE_HISTORY}u;
const MAX_TAPS: u32 = #{MAX_TAPS}u;

// GiParams.flags bits.
const GI_FILTER: u32 = #{GI_FILTER}u;
const GI_BOUNCES: u32 = #{GI_BOUNCES}u;
const GI_CACHE: u32 = #{GI_CACHE}u;
const GI_RESTART: u32 = #{GI_RESTART}u;
const GI_EDIT_RESTART: u32 = #{GI_EDIT_RESTART}u;
const GI_QMC: u32 = #{GI_QMC}u;
const GI_RESERVOIRS: u32 = #{GI_RESERVOIRS}u;
const GI_GUIDING: u32 = #{GI_GUIDING}u;
// The filtered colour of a GI entry with no value yet (shaders/gi/cache.wgsl's forget_value).
const GI_NO_VALUE: i32 = #{GI_NO_VALUE};
// Direct-light samples an entry starts over with after a change of light (gi/direct.wgsl).
const GI_RESTART_SAMPLES: u32 = #{GI_RESTART_SAMPLES}u;
// The GI work buffer (gi/cache.wgsl, gi_work), in words: where the static and the dynamic table's dispatch size
// (x, y, z) start, and the word after them that counts the entries listed.
const GI_WORK_STATIC_WORD: u32 = #{GI_WORK_STATIC_WORD}u;
const GI_WORK_DYNAMIC_WORD: u32 = #{GI_WORK_DYNAMIC_WORD}u;
const GI_WORK_COUNT_WORD: u32 = #{GI_WORK_COUNT_WORD}u;

// The G-buffer's packed hit: bit 0 hit, then the face, the material and the moving object's id.
const GBUFFER_FACE_SHIFT: u32 = #{GBUFFER_FACE_SHIFT}u;
const GBUFFER_MATERIAL_SHIFT: u32 = #{GBUFFER_MATERIAL_SHIFT}u;
const GBUFFER_MATERIAL_MASK: u32 = #{GBUFFER_MATERIAL_MASK}u;
const GBUFFER_OBJECT_SHIFT: u32 = #{GBUFFER_OBJECT_SHIFT}u;

// Counter indices (GpuCounter): the COUNT_GI_* to COUNT_RAYS_UPSCALE restart every frame, the rest count since the
// start.
const COUNT_GI_UPDATED: u32 = #{COUNT_GI_UPDATED}u;
const COUNT_GI_RETRACED: u32 = #{COUNT_GI_RETRACED}u;
const COUNT_GI_LIVE: u32 = #{COUNT_GI_LIVE}u;
const COUNT_GI_EVICTED: u32 = #{COUNT_GI_EVICTED}u;
const COUNT_GI_FULL: u32 = #{COUNT_GI_FULL}u;
const COUNT_GI_INSERTED: u32 = #{COUNT_GI_INSERTED}u;
const COUNT_GI_RAYS_TRACED: u32 = #{COUNT_GI_RAYS_TRACED}u;
const COUNT_GI_BORROWED: u32 = #{COUNT_GI_BORROWED}u;
const COUNT_GI_DIRECT_TRACED: u32 = #{COUNT_GI_DIRECT_TRACED}u;
const COUNT_RAYS_PRIMARY: u32 = #{COUNT_RAYS_PRIMARY}u;
const COUNT_RAYS_RESTIR_INITIAL: u32 = #{COUNT_RAYS_RESTIR_INITIAL}u;
const COUNT_RAYS_RESTIR_SPATIAL: u32 = #{COUNT_RAYS_RESTIR_SPATIAL}u;
const COUNT_RAYS_RESTIR_SHADE: u32 = #{COUNT_RAYS_RESTIR_SHADE}u;
const COUNT_PRIMARY_HITS: u32 = #{COUNT_PRIMARY_HITS}u;
const COUNT_TRACE_STEPS: u32 = #{COUNT_TRACE_STEPS}u;
const COUNT_TRACE_LOADS: u32 = #{COUNT_TRACE_LOADS}u;
const COUNT_RAYS_GI: u32 = #{COUNT_RAYS_GI}u;
const COUNT_RAYS_UPSCALE: u32 = #{COUNT_RAYS_UPSCALE}u;
const COUNT_RESERVOIR_RESETS: u32 = #{COUNT_RESERVOIR_RESETS}u;
const COUNT_GI_RESETS: u32 = #{COUNT_GI_RESETS}u;
const COUNT_GI_FREED_TOTAL: u32 = #{COUNT_GI_FREED_TOTAL}u;

// The settings each pipeline is compiled for (src/render/pass_key.rs, `PassKey`): the code for other values is not
// in it, which a GPU pays for in registers and software Vulkan in time (Mesa 22.3's lavapipe runs both sides of
// every branch). Read them through the accessors beside their uniforms (`lighting_mode`, `debug_view`,
// `restir_flag`, `gi_on`, `gi_setting`, `object_count`, ...). KEY_GENERIC: not compiled in, the accessor reads the uniform (the
// tests that compose one library function alone).
const KEY_GENERIC: u32 = #{KEY_GENERIC}u;
const KEY_LIGHTING: u32 = #{KEY_LIGHTING}u;
const KEY_SHADOWS: u32 = #{KEY_SHADOWS}u;
const KEY_POWER_PICK: u32 = #{KEY_POWER_PICK}u;
const KEY_DEBUG_VIEW: u32 = #{KEY_DEBUG_VIEW}u;
const KEY_RESTIR_FLAGS: u32 = #{KEY_RESTIR_FLAGS}u;
const KEY_GI: u32 = #{KEY_GI}u;
const KEY_GI_FLAGS: u32 = #{KEY_GI_FLAGS}u;
// 0: the world has no moving objects this frame; 1: it has.
const KEY_OBJECTS: u32 = #{KEY_OBJECTS}u;
// 0: the world's brick pool is one buffer; 1: it is in parts (`pooled_voxel`).
const KEY_POOL_PARTS: u32 = #{KEY_POOL_PARTS}u;
