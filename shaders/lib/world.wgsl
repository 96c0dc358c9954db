// The brick grid on the GPU: bindings and voxel lookup. Mirrors src/world/grid.rs.
#define_import_path glowbrick::world

#import glowbrick::constants::{POOLED_FLAG, BRICK_SIZE, BRICK_SHIFT, BRICK_WORDS, KEY_OBJECTS, KEY_POOL_PARTS, KEY_GENERIC,
                            ONE_POOL_PART}

// WorldInfo in src/render/gpu_types.rs.
struct WorldInfo {
    // World size in voxels, the number of moving objects, world size in bricks, where the pool slots' voxel masks
    // start in `occupancy` (8 a slot: one per 4^3 quadrant of the brick).
    size: vec3<i32>,
    object_count: u32,
    bricks: vec3<i32>,
    voxel_mask_base: u32,
    // Sector grid size (4^3 bricks) and region grid size (4^3 sectors), and where their masks start in
    // `occupancy`.
    sectors: vec3<i32>,
    sector_base: u32,
    regions: vec3<i32>,
    region_base: u32,
    // The voxels [occupied_lo, occupied_hi) that may hold a solid one: the occupancy walk starts where a ray
    // enters them and misses where it leaves (empty when lo == hi).
    occupied_lo: vec3<i32>,
    // Pool slots per part of the brick pool, as a shift: slot s is slot s & (2^shift - 1) of part s >> shift.
    pool_part_shift: u32,
    occupied_hi: vec3<i32>,
    _pad_hi: u32,
    // The world coordinates of voxel (0, 0, 0): per-voxel detail hashes world coordinates.
    detail_origin: vec3<i32>,
    _pad_detail: u32,
    // The window's voxels [window_lo, window_hi) ([0, size) in a bounded world) and the voxel stored first before
    // the wrap: a brick (a sector, a region) is stored at its offset from wrap_base, less the grid where that
    // reaches past it, so an endless world's scroll rewrites only the bricks that enter (BrickGrid::begin_scroll).
    window_lo: vec3<i32>,
    _pad_window_lo: u32,
    window_hi: vec3<i32>,
    _pad_window_hi: u32,
    wrap_base: vec3<i32>,
    _pad_wrap: u32,
}

struct Material {
    // Linear albedo (rgb) and per-voxel variation (w): read it through albedo_at.
    albedo: vec4<f32>,
    // Emitted radiance (rgb) = emission colour x strength.
    radiance: vec4<f32>,
}

@group(0) @binding(0) var<uniform> world_info: WorldInfo;
@group(0) @binding(1) var<storage, read> top_cells: array<u32>;
// Pooled bricks, two u16 voxels per word, little-endian: voxel i of a slot is in word i / 2, low half when even.
// In up to four parts (bindings 2 to 5) of 2^pool_part_shift slots each, so a pool can be larger than the
// GPU binds in one buffer (`pooled_voxel`); a world that fits in one binds small placeholders for the others.
@group(0) @binding(2) var<storage, read> brick_pool: array<u32>;
@group(0) @binding(3) var<storage, read> brick_pool_1: array<u32>;
@group(0) @binding(4) var<storage, read> brick_pool_2: array<u32>;
@group(0) @binding(5) var<storage, read> brick_pool_3: array<u32>;
@group(0) @binding(7) var<storage, read> materials: array<Material>;
// The occupancy masks (src/world/occupancy.rs), 64 bits each, low word first: per brick (by top-grid index) its
// cells of 2^3 voxels that hold a solid voxel, then per sector its bricks that are not empty, then per region its
// sectors that are not empty. The counters are the last binding (shaders/lib/counters.wgsl).
@group(0) @binding(6) var<storage, read> occupancy: array<vec2<u32>>;

// A moving voxel object (src/dynamic): a small voxel grid translated to `min`, never rotated.
struct Object {
    min: vec3<f32>,
    // Stable id, 1..4095 (keys its GI entries and marks its pixels in the G-buffer).
    id: u32,
    size: vec3<u32>,
    // First voxel in object_voxels; x fastest, then y, then z.
    offset: u32,
    // min last frame: where its surfaces were (the denoiser's motion vectors).
    previous_min: vec3<f32>,
    _pad: u32,
}

@group(0) @binding(8) var<storage, read> objects: array<Object>;
@group(0) @binding(9) var<storage, read> object_voxels: array<u32>;

// Pipelines compiled for a world without moving objects (KEY_OBJECTS 0) hold none of their code: every
// `trace_scene` is the static walk alone.
fn object_count() -> u32 {
    if KEY_OBJECTS == 0u {
        return 0u;
    }
    return world_info.object_count;
}

// The voxel id at a local coordinate of object o (air outside it).
fn object_voxel(o: Object, local: vec3<i32>) -> u32 {
    if any(local < vec3(0)) || any(vec3<u32>(local) >= o.size) {
        return 0u;
    }
    let l = vec3<u32>(local);
    return object_voxels[o.offset + l.x + o.size.x * (l.y + o.size.y * l.z)];
}

// The index of the object with `id`, or object_count() when it is gone.
fn object_index(id: u32) -> u32 {
    let count = object_count();
    for (var i = 0u; i < count; i++) {
        if objects[i].id == id {
            return i;
        }
    }
    return count;
}

// How far moving object `id` moved since last frame (0 for the static world, or an object that is gone).
fn object_motion(id: u32) -> vec3<f32> {
    if id == 0u {
        return vec3(0.0);
    }
    let i = object_index(id);
    if i >= object_count() {
        return vec3(0.0);
    }
    return objects[i].min - objects[i].previous_min;
}

// Where cell `c` of a level of cells 2^shift voxels wide (`dims` of them: bricks, sectors or regions) is stored,
// for a cell inside the window: BrickGrid::brick_index and Occupancy's `wrapped`.
fn stored_index(c: vec3<i32>, dims: vec3<i32>, shift: u32) -> u32 {
    let s = c - (world_info.wrap_base >> vec3(shift));
    let w = select(s, s - dims, s >= dims);
    return u32(w.x + dims.x * (w.y + dims.y * w.z));
}

// Whether brick `brick` holds a voxel of the window.
fn brick_in_window(brick: vec3<i32>) -> bool {
    let lo = world_info.window_lo >> vec3(BRICK_SHIFT);
    let hi = (world_info.window_hi + vec3(BRICK_SIZE - 1)) >> vec3(BRICK_SHIFT);
    return all(brick >= lo) && all(brick < hi);
}

fn brick_cell(brick: vec3<i32>) -> u32 {
    if !brick_in_window(brick) {
        return 0u;
    }
    return top_cells[stored_index(brick, world_info.bricks, BRICK_SHIFT)];
}

// The window's voxels are [window_lo, window_hi()).
fn window_hi() -> vec3<i32> {
    return world_info.window_hi;
}

// The voxel id inside a pooled brick slot.
fn pooled_voxel(slot: u32, local: vec3<i32>) -> u32 {
    let index = u32(local.x + BRICK_SIZE * (local.y + BRICK_SIZE * local.z));
    var word = 0u;
    if pool_in_parts() {
        let shift = world_info.pool_part_shift;
        word = pool_part_word(slot >> shift, (slot & ((1u << shift) - 1u)) * BRICK_WORDS + index / 2u);
    } else {
        word = brick_pool[slot * BRICK_WORDS + index / 2u];
    }
    return (word >> (16u * (index & 1u))) & 0xFFFFu;
}

// Whether the pool is in parts (pipelines compiled for a world whose pool is one buffer hold no part's choice).
fn pool_in_parts() -> bool {
    if KEY_POOL_PARTS != KEY_GENERIC {
        return KEY_POOL_PARTS == 1u;
    }
    return world_info.pool_part_shift != ONE_POOL_PART;
}

// Word `at` of pool part `part`.
fn pool_part_word(part: u32, at: u32) -> u32 {
    switch part {
        case 0u: { return brick_pool[at]; }
        case 1u: { return brick_pool_1[at]; }
        case 2u: { return brick_pool_2[at]; }
        default: { return brick_pool_3[at]; }
    }
}

fn in_world(p: vec3<i32>) -> bool {
    return all(p >= world_info.window_lo) && all(p < window_hi());
}

// The voxel id at p; 0 (air) outside the world.
fn voxel_at(p: vec3<i32>) -> u32 {
    if !in_world(p) {
        return 0u;
    }
    let cell = brick_cell(p >> vec3(BRICK_SHIFT));
    if (cell & POOLED_FLAG) != 0u {
        return pooled_voxel(cell & ~POOLED_FLAG, p & vec3(BRICK_SIZE - 1));
    }
    return cell;
}

// The hash behind per-voxel variation: world::palette::voxel_hash, bit for bit.
fn variation_pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

fn voxel_hash(voxel: vec3<i32>) -> u32 {
    let v = bitcast<vec3<u32>>(voxel);
    return variation_pcg(v.x ^ variation_pcg(v.y ^ variation_pcg(v.z)));
}

// The albedo of a voxel of `material` (Material::albedo_at): scaled by 1 + variation * (2u - 1), u a hash of the
// world voxel in [0, 1), at world coordinates (an endless world's window starts at detail_origin). Moving
// objects' voxels (object != 0) keep the flat colour.
fn albedo_at(material: u32, voxel: vec3<i32>, object: u32) -> vec3<f32> {
    let m = materials[material];
    if m.albedo.w == 0.0 || object != 0u {
        return m.albedo.rgb;
    }
    let u = f32(voxel_hash(voxel + world_info.detail_origin) >> 8u) / 16777216.0;
    return min(m.albedo.rgb * (1.0 + m.albedo.w * (2.0 * u - 1.0)), vec3(1.0));
}
