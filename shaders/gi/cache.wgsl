// The per-voxel-face GI cache (DESIGN.md "GI cache", seed 001 adapted with seed 002's hash table): bindings
// (group 3), the hash table of (voxel, face) entries, the fixed ray directions, the cached static hits, and the
// lookups the shading passes use. Kept by refresh.wgsl, update.wgsl and filter.wgsl in this folder.
#define_import_path glowbrick::gi::cache

#import glowbrick::world::{voxel_at, objects, object_voxel, object_index, object_count, world_info, window_hi}
#import glowbrick::traversal::{face_normal, box_entry}
#import glowbrick::random::pcg
#import glowbrick::counters::counters
#import glowbrick::constants::{GI_NO_VALUE, KEY_GENERIC, KEY_GI, KEY_GI_FLAGS, RAY_OFFSET, COUNT_GI_INSERTED, COUNT_GI_FULL, GI_WORK_STATIC_WORD, GI_WORK_DYNAMIC_WORD,
    GI_WORK_COUNT_WORD}

struct GiParams {
    // 1 when the cache is on (the shading passes read it and the primary pass inserts into it).
    enabled: u32,
    // GI_* flags.
    flags: u32,
    // Directions per entry (K) and how many of them an entry re-shades per frame.
    rays: u32,
    update_rays: u32,
    alpha: f32,
    // Edit epoch now: entries traced at an older epoch re-test the edit log.
    epoch: u32,
    // Entries traced before this epoch retrace (edits that fell out of the log may touch them).
    lost_epoch: u32,
    edit_count: u32,
    static_capacity: u32,
    dynamic_capacity: u32,
    frame: u32,
    // This frame's update iteration (more than one only after a change of light).
    iteration: u32,
    // `gi_cell`: the width in pixels a camera's cells have at least.
    cell_pixels: f32,
    // Update iterations run before this frame's (with an offset per `seed`): fresh rays continue the entries'
    // low-discrepancy sequences from there, one run across iterations and frames alike.
    update_run: u32,
    // Frames between two updates of a settled entry this frame (1 while the light is new).
    period: u32,
    // Padding to 16 bytes (GiParams::_pad).
    _pad: u32,
}

// One (voxel, face) entry. The key lives in gi_keys (0 = empty); this is its payload.
struct GiEntry {
    voxel: vec3<i32>,
    face: u32,
    // Frame it was last needed (seen by the camera, or hit by another entry's ray).
    last_used: u32,
    // Edit epoch its static hits were traced at; NEVER_TRACED before the first trace, LOST_FACE to be freed.
    traced_epoch: u32,
    // Frames blended so far (sets the blend weight of young entries); 0 = no value yet.
    samples: u32,
    // 0 for the static world; object index + 1 for a dynamic object's face (its own table).
    object: u32,
    // Bounds of its rays' static segments, for edit invalidation.
    lo: vec3<f32>,
    // Frame the camera last saw it: only such entries insert the entries their rays hit (one level), so the
    // cache follows the view instead of spreading through the world.
    last_seen: u32,
    hi: vec3<f32>,
    // Level of detail: the entry stands for the same-orientation faces of a 2^level voxel cell (`voxel` is the
    // face that inserted it, which its rays start from).
    level: u32,
}

// Frames an entry may go unused before it stops being updated, and before its slot is freed.
const UPDATE_AGE: u32 = 16u;
const MAX_AGE: u32 = 240u;

const NEVER_TRACED: u32 = 0xFFFFFFFFu;
// A coarse entry whose inserting face an edit removed (refresh.wgsl): the next compaction frees it.
const LOST_FACE: u32 = 0xFFFFFFFEu;
const MAX_PROBES: u32 = 16u;
// A cached hit: bits 0-2 the face hit (MISS_FACE: left the world), bits 3-31 the distance in 1/256 voxels.
const MISS_FACE: u32 = 7u;
const DISTANCE_SCALE: f32 = 256.0;


@group(3) @binding(0) var<uniform> gi: GiParams;
@group(3) @binding(1) var<storage, read_write> gi_keys: array<atomic<u32>>;
@group(3) @binding(2) var<storage, read_write> gi_entries: array<GiEntry>;
// Blended incoming radiance (irradiance / pi, rgb) per entry, and its filtered copy that shading reads.
@group(3) @binding(3) var<storage, read_write> gi_irradiance: array<vec4<f32>>;
@group(3) @binding(4) var<storage, read_write> gi_filtered: array<vec4<f32>>;
// K cached static hits per entry.
@group(3) @binding(5) var<storage, read_write> gi_rays: array<u32>;
// Edit log: pairs (min voxel xyz, epoch), (max voxel xyz exclusive, 0) of edited bricks.
@group(3) @binding(6) var<storage, read> gi_edits: array<vec4<i32>>;
// An entry's reservoir of light-pool samples (gi_reservoirs=on, reservoir.wgsl; seed 002): the light's slot and
// generation (a removed or changed light fails the match), the face of its cube and the point on it
// (pack2x16unorm), the candidates it stands for (m) and its contribution weight (big_w; 0 once its shadow ray
// was blocked). GiReservoir in src/render/gpu_types.rs.
struct GiReservoir {
    slot: u32,
    generation: u32,
    face: u32,
    uv: u32,
    w_sum: f32,
    m: f32,
    big_w: f32,
    _pad: f32,
}

// Per entry: the direct light its face reflects, averaged over the face and over frames (rgb), and the samples
// blended so far (w; 0 = no value yet), written by refresh.wgsl, read by update.wgsl at ray hits (direct.wgsl);
// the reservoir it draws the light pool's light from; and the histogram of where its bounce light comes from,
// that its rays are guided by (gi_guiding=on, guide.wgsl: 16 bins, two 16-bit floats a word). One binding: a
// compute stage binds at most 32 storage buffers on lavapipe, and the groups hold 32. GiDirect in
// src/render/gpu_types.rs.
struct GiDirect {
    light: vec4<f32>,
    reservoir: GiReservoir,
    guide: array<vec4<u32>, 2>,
}

@group(3) @binding(7) var<storage, read_write> gi_direct: array<GiDirect>;
// This frame's work (compact.wgsl): per table an indirect dispatch size (x, y, z) and the count of listed
// entries, words WORK_STATIC.. and WORK_DYNAMIC..; and the lists, the static table's due slots from 0, the
// dynamic table's from static_capacity.
@group(3) @binding(8) var<storage, read_write> gi_work: array<atomic<u32>>;
@group(3) @binding(9) var<storage, read_write> gi_list: array<u32>;

const WORK_STATIC: u32 = GI_WORK_STATIC_WORD;
const WORK_DYNAMIC: u32 = GI_WORK_DYNAMIC_WORD;
const WORK_COUNT: u32 = GI_WORK_COUNT_WORD;

// The slot listed at index i of this frame's work for a table (WORK_STATIC or WORK_DYNAMIC), or NOT_FOUND past
// its end (the last workgroup's spare threads).
fn listed_slot(work: u32, i: u32) -> u32 {
    if i >= atomicLoad(&gi_work[work + WORK_COUNT]) {
        return NOT_FOUND;
    }
    return gi_list[select(0u, gi.static_capacity, work == WORK_DYNAMIC) + i];
}

// Level of detail (seed 002's adaptive cells): a cache ray that hits a face far from its entry reads (and may
// insert) the entry of the coarse cell around the hit: a 2^level cube of voxels whose faces of one orientation
// share a value. Level 0 within LOD_NEAR voxels, then one level more each time the distance doubles, up to
// MAX_LEVEL, and never finer than the shooting entry's own level (a coarse entry does not breed fine ones). The
// cameras read the level of their pixel footprint (camera_level).
const MAX_LEVEL: u32 = 3u;
const LOD_NEAR: f32 = 4.0;

fn hit_level(distance: f32, shooter_level: u32) -> u32 {
    var level = 0u;
    if distance >= LOD_NEAR {
        level = min(u32(log2(distance / LOD_NEAR)) + 1u, MAX_LEVEL);
    }
    return max(level, shooter_level);
}

// The cell a voxel lies in at `level` (an arithmetic shift: floor division for negative object coordinates).
fn cell_of(voxel: vec3<i32>, level: u32) -> vec3<i32> {
    return voxel >> vec3(level);
}

fn key_hash(cell: vec3<i32>, face: u32, object: u32, level: u32) -> u32 {
    return pcg(pcg(pcg(pcg(u32(cell.x)) ^ u32(cell.y)) ^ u32(cell.z)) ^ (face | (level << 3u) | (object << 5u)));
}

// Key words besides checksums: an empty slot (ends a probe chain), a freed one (a tombstone: chains go on
// through it, and an insert may reuse it) and one being inserted (its payload is not written yet).
const EMPTY_KEY: u32 = 0u;
const FREED_KEY: u32 = 0xFFFFFFFFu;
const BUSY_KEY: u32 = 0xFFFFFFFEu;

// A second, independent hash stored as the key (never one of the three words above).
fn key_checksum(cell: vec3<i32>, face: u32, object: u32, level: u32) -> u32 {
    let h = pcg(u32(cell.x) * 0x9E3779B9u ^ pcg(u32(cell.y) * 0x85EBCA6Bu ^ pcg(u32(cell.z) ^ (level << 21u) ^ (face << 24u) ^ (object << 27u))));
    return clamp(h, 1u, BUSY_KEY - 1u);
}

// Whether a slot holds a published entry.
fn is_live_key(key: u32) -> bool {
    return key != EMPTY_KEY && key != FREED_KEY && key != BUSY_KEY;
}

// The table an entry belongs to: static entries in [0, static), dynamic ones after them.
fn table_base(object: u32) -> u32 {
    return select(0u, gi.static_capacity, object != 0u);
}

fn table_size(object: u32) -> u32 {
    return select(gi.static_capacity, gi.dynamic_capacity, object != 0u);
}

// The slot after `slot` in its probe order, within the table it lies in (found from the slot itself).
fn next_slot(slot: u32) -> u32 {
    let dynamic = slot >= gi.static_capacity;
    let base = select(0u, gi.static_capacity, dynamic);
    let size = select(gi.static_capacity, gi.dynamic_capacity, dynamic);
    return base + ((slot - base + 1u) & (size - 1u));
}

const NOT_FOUND: u32 = 0xFFFFFFFFu;

// The filtered colour of an entry that holds no value yet (radiance is never negative); the tables start with it
// (src/render/gi/tables.rs).
const NO_VALUE: f32 = f32(GI_NO_VALUE);

// The entry holds no value (its samples count 0, its filtered colour NO_VALUE until the filter pass writes one).
// The update pass's rays tell an entry with a value by its colour, not its count: the update pass writes the
// count of the entries it updates while its other threads read it, so the count's test depended on which
// workgroup ran first; the colour is written only by the filter pass, a later dispatch.
fn forget_value(slot: u32) {
    gi_entries[slot].samples = 0u;
    gi_filtered[slot] = vec4(vec3(NO_VALUE), 0.0);
}

// Whether the entry's filtered colour holds a value (see forget_value).
fn has_filtered_value(slot: u32) -> bool {
    return gi_filtered[slot].r >= 0.0;
}

fn probe_slot(cell: vec3<i32>, face: u32, object: u32, level: u32, i: u32) -> u32 {
    // Capacities are powers of two.
    return table_base(object) + ((key_hash(cell, face, object, level) + i) & (table_size(object) - 1u));
}

// The slot of the entry of `voxel`'s face at `level`, or NOT_FOUND. Freed and busy slots do not end the chain:
// an entry inserted past a slot that was freed since must stay reachable.
fn gi_find(voxel: vec3<i32>, face: u32, object: u32, level: u32) -> u32 {
    return gi_probe(voxel, face, object, level, false, false);
}

// Claims `slot` (empty or freed, as `expected`) for a new entry: marks it busy, writes the payload, then
// publishes the key, so a reader never pairs the key with the previous occupant's payload. Returns the key word
// the slot holds afterwards: `checksum` when this thread (or another, for the same entry) got it.
fn claim(slot: u32, expected: u32, checksum: u32, voxel: vec3<i32>, face: u32, object: u32, level: u32, seen: bool) -> u32 {
    for (var attempt = 0u; attempt < 4u; attempt++) {
        let result = atomicCompareExchangeWeak(&gi_keys[slot], expected, BUSY_KEY);
        if result.exchanged {
            gi_entries[slot].voxel = voxel;
            gi_entries[slot].face = face;
            gi_entries[slot].object = object;
            gi_entries[slot].level = level;
            gi_entries[slot].traced_epoch = NEVER_TRACED;
            forget_value(slot);
            gi_entries[slot].last_used = gi.frame;
            gi_entries[slot].last_seen = select(0u, gi.frame, seen);
            gi_direct[slot].light = vec4(0.0);
            // No light samples of the slot's last occupant.
            gi_direct[slot].reservoir = GiReservoir(0xffffffffu, 0u, 0u, 0u, 0.0, 0.0, 0.0, 0.0);
            // Nor the directions its light came from.
            gi_direct[slot].guide = array(vec4(0u), vec4(0u));
            atomicStore(&gi_keys[slot], checksum);
            atomicAdd(&counters[COUNT_GI_INSERTED], 1u);
            return checksum;
        }
        if result.old_value != expected {
            return result.old_value;
        }
        // A weak exchange may fail spuriously: try again.
    }
    return BUSY_KEY;
}

// Finds or inserts an entry and marks it used this frame (and seen, when the camera sees it). A new entry takes
// the chain's first freed slot once the chain is known not to hold it (the table does not fill with tombstones),
// else the empty slot that ends the chain. NOT_FOUND when the probe window is full (counted) or when another
// thread took the slot first (the entry has no value this frame either way; the next frame inserts it).
fn gi_touch(voxel: vec3<i32>, face: u32, object: u32, level: u32, seen: bool) -> u32 {
    return gi_probe(voxel, face, object, level, true, seen);
}

// gi_touch (`touch`) or gi_find (not), in one body: a caller that decides per thread which one it needs calls
// this once, where two calls would each cost every lane on software Vulkan, which runs both sides of a branch.
fn gi_probe(voxel: vec3<i32>, face: u32, object: u32, level: u32, touch: bool, seen: bool) -> u32 {
    let cell = cell_of(voxel, level);
    let checksum = key_checksum(cell, face, object, level);
    var freed = NOT_FOUND;
    for (var i = 0u; i < MAX_PROBES; i++) {
        let slot = probe_slot(cell, face, object, level, i);
        let key = atomicLoad(&gi_keys[slot]);
        if key == checksum {
            // Every toucher writes the same values: a benign race, and skipped when already set.
            if touch && gi_entries[slot].last_used != gi.frame {
                gi_entries[slot].last_used = gi.frame;
            }
            if touch && seen && gi_entries[slot].last_seen != gi.frame {
                gi_entries[slot].last_seen = gi.frame;
            }
            return slot;
        }
        if key == FREED_KEY && freed == NOT_FOUND {
            freed = slot;
        }
        if key == EMPTY_KEY {
            if !touch {
                return NOT_FOUND;
            }
            let reuse = freed != NOT_FOUND;
            let chosen = select(slot, freed, reuse);
            if claim(chosen, select(EMPTY_KEY, FREED_KEY, reuse), checksum, voxel, face, object, level, seen) == checksum {
                return chosen;
            }
            return NOT_FOUND;
        }
    }
    if !touch {
        return NOT_FOUND;
    }
    if freed != NOT_FOUND && claim(freed, FREED_KEY, checksum, voxel, face, object, level, seen) == checksum {
        return freed;
    }
    atomicAdd(&counters[COUNT_GI_FULL], 1u);
    return NOT_FOUND;
}

// Whether (voxel, face) is a surface of the static world: solid with air in front.
fn is_surface(voxel: vec3<i32>, face: u32) -> bool {
    return voxel_at(voxel) != 0u && voxel_at(voxel + vec3<i32>(face_normal(face))) == 0u;
}

// The face's two in-plane axes.
fn tangent_axes(face: u32) -> vec2<u32> {
    let axis = face / 2u;
    return vec2((axis + 1u) % 3u, (axis + 2u) % 3u);
}

fn unit(axis: u32, s: i32) -> vec3<i32> {
    var v = vec3(0);
    v[axis] = s;
    return v;
}

// The three in-plane neighbours a point on a face interpolates with: towards the point's quadrant.
struct Bilinear {
    step_u: vec3<i32>,
    step_v: vec3<i32>,
    weight: vec2<f32>,
}

// At `level` the neighbours are cells: the steps are 2^level voxels, the weights measured across the cell.
fn bilinear(point: vec3<f32>, voxel: vec3<i32>, face: u32, level: u32) -> Bilinear {
    let t = tangent_axes(face);
    let size = 1 << level;
    let local = (point - vec3<f32>(cell_of(voxel, level) * size)) / f32(size) - vec3(0.5);
    let fu = clamp(local[t.x], -0.5, 0.5);
    let fv = clamp(local[t.y], -0.5, 0.5);
    return Bilinear(unit(t.x, select(size, -size, fu < 0.0)), unit(t.y, select(size, -size, fv < 0.0)), vec2(abs(fu), abs(fv)));
}

// Corner i of a bilinear footprint: 0 the face's own voxel, 1 the neighbour along u, 2 along v, 3 along both.
fn bilinear_voxel(voxel: vec3<i32>, b: Bilinear, i: u32) -> vec3<i32> {
    return voxel + select(vec3(0), b.step_u, (i & 1u) != 0u) + select(vec3(0), b.step_v, (i & 2u) != 0u);
}

// The level a camera reads a surface at, from its pixel footprint (voxels across one pixel there): the finest
// whose cells are at least `gi.cell_pixels` pixels wide (up to MAX_LEVEL), so a far or low-resolution view keeps
// few entries. (`gi_cell=1` reproduces the older rule, the coarsest at most 2 pixels wide.) Moving
// objects stay at 0.
fn camera_level(voxels_per_pixel: f32, object: u32) -> u32 {
    let cells = voxels_per_pixel * gi.cell_pixels;
    if object != 0u || !(cells > 1.0) {
        return 0u;
    }
    return min(u32(ceil(log2(cells))), MAX_LEVEL);
}

// Whether (local voxel, face) is a surface of moving object `index`: solid, with the object's air in front.
fn is_object_surface(index: u32, voxel: vec3<i32>, face: u32) -> bool {
    let o = objects[index];
    return object_voxel(o, voxel) != 0u && object_voxel(o, voxel + vec3<i32>(face_normal(face))) == 0u;
}

// Where a surface point lies in the frame its entries are keyed in: world coordinates for the static world, the
// object's local ones for a moving object. w is 0 when the object is gone.
fn entry_frame_point(point: vec3<f32>, object: u32) -> vec4<f32> {
    if object == 0u {
        return vec4(point, 1.0);
    }
    let index = object_index(object);
    if index == object_count() {
        return vec4(0.0);
    }
    return vec4(point - objects[index].min, 1.0);
}

// Inserts (or refreshes) the entries a pixel seeing `point` on `face` (of the static world, or of object
// `object`) reads at `level` (camera_level): its own face's and the three in-plane neighbours it interpolates
// with (at a coarse level, the neighbouring cells, through the voxel of the same plane in each).
fn gi_touch_surface(point: vec3<f32>, face: u32, object: u32, level: u32) {
    let p = entry_frame_point(point, object);
    if p.w == 0.0 {
        return;
    }
    let voxel = vec3<i32>(floor(p.xyz - face_normal(face) * 0.5));
    let b = bilinear(p.xyz, voxel, face, level);
    let index = object_index(object);
    // The face itself, then its three interpolation neighbours that are surfaces. One loop and one call site:
    // software Vulkan inlines every call and runs each copy under a mask, so a separate call for the face itself
    // cost every pixel a second copy of the probe.
    for (var i = 0u; i < 4u; i++) {
        let neighbour = bilinear_voxel(voxel, b, i);
        let surface = select(is_object_surface(index, neighbour, face), is_surface(neighbour, face), object == 0u);
        if i == 0u || surface {
            gi_touch(neighbour, face, object, level, true);
        }
    }
}

// An entry's shading value, or `fallback` when it does not exist or has no value yet (padding).
fn filtered_or(voxel: vec3<i32>, face: u32, object: u32, level: u32, fallback: vec3<f32>) -> vec3<f32> {
    let slot = gi_find(voxel, face, object, level);
    if slot == NOT_FOUND || gi_entries[slot].samples == 0u {
        return fallback;
    }
    return gi_filtered[slot].rgb;
}

// Whether a frame stamp is within the last `frames` frames. Written as an addition: Mesa 22's lavapipe crashes
// (segfault in its queue thread) on `gi.frame - stamp` compared in these passes.
fn used_within(stamp: u32, frames: u32) -> bool {
    return stamp + frames >= gi.frame;
}

// Blended frames after which an entry is settled: its blend weight has fallen to alpha (update.wgsl,
// blend_estimate) and another frame's estimate only averages noise away.
fn settled_samples() -> u32 {
    return u32(ceil(2.0 / gi.alpha));
}

fn settled(samples: u32) -> bool {
    return samples >= settled_samples();
}

// Whether a settled entry updates this frame: one frame in gi.period, the frames spread over the slots (a slot
// is a hash of the entry's cell) so each frame takes an even share. The moving objects' entries and unsettled
// ones update every frame (compact.wgsl).
fn settled_turn(slot: u32) -> bool {
    return (slot + gi.frame) % gi.period == 0u;
}

// Where an entry's low-discrepancy runs (its rays, its direct light's points) stand for a run counter `n` that
// steps once a frame: a settled entry, updated every gi.period frames, takes one step per update, so the
// points of its consecutive updates stay consecutive.
fn sequence_step(n: u32, e: GiEntry) -> u32 {
    return select(n, n / gi.period, e.object == 0u && settled(e.samples));
}

// Whether GI is on, and its setting bits (GI_CACHE, GI_FILTER, GI_BOUNCES, GI_QMC; not the per-frame restarts):
// the pipeline's own (constants.wgsl, KEY_*) or the uniform's in a generic build.
fn gi_on() -> bool {
    if KEY_GI == KEY_GENERIC {
        return gi.enabled == 1u;
    }
    return KEY_GI == 1u;
}

fn gi_setting(bit: u32) -> bool {
    if KEY_GI_FLAGS == KEY_GENERIC {
        return (gi.flags & bit) != 0u;
    }
    return (KEY_GI_FLAGS & bit) != 0u;
}

// Incoming indirect radiance (irradiance / pi) at `point` on `face` (of the static world, or of object
// `object`) read at `level` (camera_level): bilinear over the face's entry (or cell's) and its three in-plane
// neighbours of the same orientation in the same table; a missing neighbour repeats the face's own value. Static surfaces never read a moving object's entries.
fn gi_incoming(point: vec3<f32>, face: u32, object: u32, level: u32) -> vec3<f32> {
    let p = entry_frame_point(point, object);
    if p.w == 0.0 {
        return vec3(0.0);
    }
    let voxel = vec3<i32>(floor(p.xyz - face_normal(face) * 0.5));
    let b = bilinear(p.xyz, voxel, face, level);
    // The face's own value (0 without one), then the neighbours' along u, v and both (the face's own without
    // one), in one loop with one lookup (one inlined copy of the probe, as in gi_touch_surface).
    var values: array<vec3<f32>, 4>;
    for (var i = 0u; i < 4u; i++) {
        let neighbour = bilinear_voxel(voxel, b, i);
        values[i] = filtered_or(neighbour, face, object, level, select(values[0], vec3(0.0), i == 0u));
    }
    return mix(mix(values[0], values[1], b.weight.x), mix(values[2], values[3], b.weight.x), b.weight.y);
}

// Direction i of K for an entry: a Hammersley point, Cranley-Patterson rotated per entry so neighbours do not
// share directions, mapped to the cosine-weighted hemisphere around the face normal.
fn ray_direction(face: u32, i: u32, k: u32, seed: u32) -> vec3<f32> {
    return cosine_direction(face, ray_square_point(i, k, seed));
}

// Direction i of k's point of the unit square (cosine_direction's): a Hammersley set shifted by the seed.
fn ray_square_point(i: u32, k: u32, seed: u32) -> vec2<f32> {
    let rotation = vec2(f32(pcg(seed) >> 8u), f32(pcg(seed ^ 0x68E31DA4u) >> 8u)) * (1.0 / 16777216.0);
    let u = fract((f32(i) + 0.5) / f32(k) + rotation.x);
    let v = fract(f32(reverseBits(i)) * 2.3283064e-10 + rotation.y);
    return vec2(u, v);
}

// The cosine-weighted direction around the face normal at `u` of the unit square.
fn cosine_direction(face: u32, u: vec2<f32>) -> vec3<f32> {
    let r = sqrt(u.x);
    let phi = 6.2831853 * u.y;
    let t = tangent_axes(face);
    var d = face_normal(face) * sqrt(max(1.0 - u.x, 0.0));
    d[t.x] = r * cos(phi);
    d[t.y] = r * sin(phi);
    return normalize(d);
}

// Where an entry's rays start: the face's centre, just off the surface (`base` is the object's corner, or 0).
fn ray_origin(voxel: vec3<i32>, face: u32, base: vec3<f32>) -> vec3<f32> {
    return base + vec3<f32>(voxel) + vec3(0.5) + face_normal(face) * (0.5 + RAY_OFFSET);
}

// Per-entry seed for its directions: fixed for the entry's life so the cached hits stay valid.
fn slot_seed(slot: u32) -> u32 {
    return atomicLoad(&gi_keys[slot]);
}

fn encode_hit(found: bool, face: u32, distance: f32) -> u32 {
    if !found {
        return MISS_FACE;
    }
    let d = u32(clamp(distance * DISTANCE_SCALE, 0.0, f32(0x1FFFFFFFu)));
    return (d << 3u) | face;
}

fn hit_face(code: u32) -> u32 {
    return code & 7u;
}

fn hit_distance(code: u32) -> f32 {
    return f32(code >> 3u) / DISTANCE_SCALE;
}

// How far a ray from `origin` inside the world goes before it leaves it.
fn world_exit(origin: vec3<f32>, dir: vec3<f32>) -> f32 {
    return max(box_entry(origin, dir, vec3<f32>(world_info.window_lo), vec3<f32>(window_hi())).y, 0.0);
}
