// Ray traversal of the brick grid, two ways to the same hits (the `traversal` setting): the plain two-level DDA,
// and a walk through the occupancy hierarchy that jumps empty cells of 128 down to 2 voxels whole. Mirrors
// src/world/traversal.rs step for step (same boundary formulas and tie rules) so GPU and CPU agree.
#define_import_path glowbrick::traversal

#import glowbrick::world::{world_info, top_cells, occupancy, brick_cell, pooled_voxel, stored_index, window_hi, objects, object_count, object_voxel, Object}
#import glowbrick::constants::{POOLED_FLAG, BRICK_SIZE, BRICK_SHIFT, MAX_WORLD_EDGE, COUNT_TRACE_STEPS, COUNT_TRACE_LOADS,
    CELL_SHIFT, SECTOR_SHIFT, REGION_SHIFT, CELL_BOX_LEVEL, VOXEL_MASK_WORDS, OBJECT_TRACE_STEPS}
#import glowbrick::counters::counters

const INF: f32 = 3.0e38;

// Brick-grid rays (calls of `trace`) this invocation traced, added to a pass's per-frame counter once per
// invocation by a pass whose entry point ends with `count_rays` (same-address atomics from a SIMD group are
// combined by the compiler on GPUs; a workgroup sum with two barriers cost more on software Vulkan).
var<private> rays_traced: u32;
// Their steps (loop steps: a brick or voxel of the DDA, a cell left at any level of the occupancy walk) and
// memory loads (masks, top cells, voxels). Added to the frame's totals by the same call.
var<private> trace_steps: u32;
var<private> trace_loads: u32;

// For the GI cache's passes: their rays only (their steps are not the per-pixel passes' totals).
fn count_rays_only(counter: u32) {
    if rays_traced > 0u {
        atomicAdd(&counters[counter], rays_traced);
    }
}

fn count_rays(counter: u32) {
    if rays_traced > 0u {
        atomicAdd(&counters[counter], rays_traced);
        atomicAdd(&counters[COUNT_TRACE_STEPS], trace_steps);
        atomicAdd(&counters[COUNT_TRACE_LOADS], trace_loads);
    }
}

struct Hit {
    // The voxel hit: world coordinates, or the object's local ones when `object` is not 0.
    voxel: vec3<i32>,
    // Face entered: 0 +X, 1 -X, 2 +Y, 3 -Y, 4 +Z, 5 -Z.
    face: u32,
    distance: f32,
    material: u32,
    found: bool,
    // 0 for the static world, else the moving object's id.
    object: u32,
}

fn miss() -> Hit {
    return Hit(vec3(0), 0u, INF, 0u, false, 0u);
}

fn face_entered(axis: u32, dir_positive: bool) -> u32 {
    return axis * 2u + select(0u, 1u, dir_positive);
}

fn face_normal(face: u32) -> vec3<f32> {
    var n = vec3(0.0);
    n[face / 2u] = select(1.0, -1.0, (face & 1u) == 1u);
    return n;
}

fn inverse_dir(dir: vec3<f32>) -> vec3<f32> {
    return select(vec3(INF), 1.0 / dir, dir != vec3(0.0));
}

fn cross_t(origin: f32, dir: f32, inv: f32, plane: f32) -> f32 {
    return select((plane - origin) * inv, INF, dir == 0.0);
}

// (t_enter, t_exit, axis of t_enter) of the box [lo, hi]; t_enter > t_exit on a miss.
fn box_entry(origin: vec3<f32>, dir: vec3<f32>, lo: vec3<f32>, hi: vec3<f32>) -> vec3<f32> {
    let inv = inverse_dir(dir);
    var t_enter = -INF;
    var t_exit = INF;
    var axis = 0u;
    for (var a = 0u; a < 3u; a++) {
        if dir[a] == 0.0 {
            if origin[a] < lo[a] || origin[a] > hi[a] {
                return vec3(INF, -INF, 0.0);
            }
            continue;
        }
        let near = select(hi[a], lo[a], dir[a] > 0.0);
        let far = select(lo[a], hi[a], dir[a] > 0.0);
        let t0 = (near - origin[a]) * inv[a];
        let t1 = (far - origin[a]) * inv[a];
        if t0 > t_enter {
            t_enter = t0;
            axis = a;
        }
        t_exit = min(t_exit, t1);
    }
    return vec3(t_enter, t_exit, f32(axis));
}

fn min_axis(v: vec3<f32>) -> u32 {
    if v.x <= v.y && v.x <= v.z {
        return 0u;
    }
    if v.y <= v.z {
        return 1u;
    }
    return 2u;
}

// The first solid voxel along the ray (unit `dir`) within max_distance, by the walk the `traversal` setting picks:
// a shader def of its own pipelines (both walks in one shader cost lavapipe much of a frame, either one run);
// both find the same voxel.
fn trace(origin: vec3<f32>, dir: vec3<f32>, max_distance: f32) -> Hit {
    rays_traced += 1u;
#ifdef TRAVERSAL_OCCUPANCY
    return trace_occupancy(origin, dir, max_distance);
#else
    return trace_dda(origin, dir, max_distance);
#endif
}

#ifndef TRAVERSAL_OCCUPANCY
// Voxel DDA inside the pooled brick `brick` (pool slot `slot`), entered at parameter t through `entry_axis`.
fn trace_in_brick(origin: vec3<f32>, dir: vec3<f32>, inv: vec3<f32>, brick: vec3<i32>, slot: u32, t_start: f32,
                  t_end: f32, entry_axis: u32) -> Hit {
    let step = vec3<i32>(sign(dir));
    let positive = dir > vec3(0.0);
    let lo = brick * BRICK_SIZE;
    let hi = min(lo + vec3(BRICK_SIZE), window_hi()) - vec3(1);
    var t = t_start;
    var axis = entry_axis;
    var voxel = clamp(vec3<i32>(floor(origin + dir * t)), lo, hi);
    var t_max: vec3<f32>;
    for (var a = 0u; a < 3u; a++) {
        t_max[a] = cross_t(origin[a], dir[a], inv[a], f32(voxel[a] + select(0, 1, positive[a])));
    }
    // At most 22 steps cross an 8^3 brick; the bound guards against a non-finite t.
    for (var i = 0; i < 3 * BRICK_SIZE; i++) {
        trace_steps += 1u;
        trace_loads += 1u;
        let material = pooled_voxel(slot, voxel - lo);
        if material != 0u {
            return Hit(voxel, face_entered(axis, positive[axis]), t, material, true, 0u);
        }
        let a = min_axis(t_max);
        t = t_max[a];
        if t > t_end {
            break;
        }
        axis = a;
        voxel[a] += step[a];
        if voxel[a] < lo[a] || voxel[a] > hi[a] {
            break;
        }
        t_max[a] = cross_t(origin[a], dir[a], inv[a], f32(voxel[a] + select(0, 1, positive[a])));
    }
    return miss();
}

// The plain two-level DDA (traversal=dda): bricks, skipping empty ones, then the voxels of pooled bricks; one
// load per step. Mirrors `trace_counted` in src/world/traversal.rs.
fn trace_dda(origin: vec3<f32>, dir: vec3<f32>, max_distance: f32) -> Hit {
    let entry = box_entry(origin, dir, vec3<f32>(world_info.window_lo), vec3<f32>(window_hi()));
    let t_end = min(entry.y, max_distance);
    var t = max(entry.x, 0.0);
    if !(t <= t_end) || all(dir == vec3(0.0)) {
        return miss();
    }
    let inv = inverse_dir(dir);
    let step = vec3<i32>(sign(dir));
    let positive = dir > vec3(0.0);
    let edge = f32(BRICK_SIZE);
    let first_brick = world_info.window_lo >> vec3(BRICK_SHIFT);
    let last_brick = max((window_hi() - vec3(1)) >> vec3(BRICK_SHIFT), first_brick);
    var axis = u32(entry.z);
    if entry.x < 0.0 {
        let v = floor(origin);
        axis = u32(box_entry(origin, dir, v, v + vec3(1.0)).z);
    }
    var brick = clamp(vec3<i32>(floor((origin + dir * t) / edge)), first_brick, last_brick);
    var brick_t_max: vec3<f32>;
    for (var a = 0u; a < 3u; a++) {
        brick_t_max[a] = cross_t(origin[a], dir[a], inv[a], f32(brick[a] + select(0, 1, positive[a])) * edge);
    }
    let max_steps = world_info.bricks.x + world_info.bricks.y + world_info.bricks.z;
    for (var i = 0; i < max_steps; i++) {
        trace_steps += 1u;
        trace_loads += 1u;
        let cell = brick_cell(brick);
        if cell != 0u {
            if (cell & POOLED_FLAG) == 0u {
                let lo = brick * BRICK_SIZE;
                let voxel = min(clamp(vec3<i32>(floor(origin + dir * t)), lo, lo + vec3(BRICK_SIZE - 1)),
                                window_hi() - vec3(1));
                return Hit(voxel, face_entered(axis, positive[axis]), t, cell, true, 0u);
            }
            let hit = trace_in_brick(origin, dir, inv, brick, cell & ~POOLED_FLAG, t, t_end, axis);
            if hit.found {
                return hit;
            }
        }
        let a = min_axis(brick_t_max);
        t = brick_t_max[a];
        if t > t_end {
            break;
        }
        axis = a;
        brick[a] += step[a];
        if brick[a] < first_brick[a] || brick[a] > last_brick[a] {
            break;
        }
        brick_t_max[a] = cross_t(origin[a], dir[a], inv[a], f32(brick[a] + select(0, 1, positive[a])) * edge);
    }
    return miss();
}

#endif

#ifdef TRAVERSAL_OCCUPANCY
fn has_child(m: vec2<u32>, bit: u32) -> bool {
    let word = select(m.y, m.x, bit < 32u);
    return ((word >> (bit & 31u)) & 1u) != 0u;
}

// The coarsest empty cell below 4^3-child mask m that holds voxel v (children of edge 1 << child_shift), as (low
// corner, edge): the 3^3 children reaching ahead of the ray's child on every axis, else the 2^3 reaching ahead,
// else its aligned 2^3 group, else its child; edge 0 when the child is occupied. A box need not be aligned or a
// power of two: the ray leaves it as any cell, through voxel planes. A box of children at (x, y, z) is a fixed
// pattern of bits moved by x + 4 y + 16 z.
fn empty_child_cell(m: vec2<u32>, v: vec3<i32>, child_shift: u32, positive: vec3<bool>) -> vec4<i32> {
    let c = (v >> vec3(child_shift)) & vec3(3);
    let node = v & vec3(~((4 << child_shift) - 1));
    let ahead3 = select(max(c - vec3(2), vec3(0)), min(c, vec3(1)), positive);
    if !any_bits(m, BOX3, u32(ahead3.x + 4 * ahead3.y + 16 * ahead3.z)) {
        return vec4(node + (ahead3 << vec3(child_shift)), 3 << child_shift);
    }
    let ahead = select(max(c - vec3(1), vec3(0)), min(c, vec3(2)), positive);
    if !any_bits(m, BOX2, u32(ahead.x + 4 * ahead.y + 16 * ahead.z)) {
        return vec4(node + (ahead << vec3(child_shift)), 2 << child_shift);
    }
    // The aligned group, unless it is the box just tested.
    let aligned = c & vec3(2);
    if any(aligned != ahead) && !any_bits(m, BOX2, u32(aligned.x + 4 * aligned.y + 16 * aligned.z)) {
        return vec4(v & vec3(~((2 << child_shift) - 1)), 2 << child_shift);
    }
    if !has_child(m, u32(c.x + 4 * (c.y + 4 * c.z))) {
        return vec4(v & vec3(~((1 << child_shift) - 1)), 1 << child_shift);
    }
    return vec4(v, 0);
}

// No pool slot read yet for the brick the ray is in; no word of its voxel mask held (a quadrant is 0..8).
const NO_SLOT: u32 = 0xffffffffu;
const NO_QUADRANT: u32 = 8u;

// The 2^3 children at (0|1, 0|1, 0|1): bits 0, 1, 4, 5, 16, 17, 20, 21. The 3^3 at (0..3)^3: rows of 0b111 at
// bits 0, 4, 8 of layers 0, 16, 32 (a 64-bit pattern as its low and high words).
const BOX2: vec2<u32> = vec2(0x330033u, 0u);
const BOX3: vec2<u32> = vec2(0x07770777u, 0x0777u);

// Whether any child of m in the box `pattern` moved up by `base` bits (0..=63) is occupied: the 64-bit shift on
// two words (a shift by 32 or more is taken modulo 32 in WGSL, hence the selects).
fn any_bits(m: vec2<u32>, pattern: vec2<u32>, base: u32) -> bool {
    let s = base & 31u;
    let carried = select(pattern.x >> (32u - s), 0u, s == 0u);
    let low = select(pattern.x << s, 0u, base >= 32u);
    let high = select((pattern.y << s) | carried, pattern.x << s, base >= 32u);
    return ((m.x & low) | (m.y & high)) != 0u;
}

// The index of the mask of the level-`shift` cell (bricks, sectors, regions) holding voxel v, in its level's part
// of `occupancy`.
fn mask_index(v: vec3<i32>, dims: vec3<i32>, shift: u32) -> u32 {
    return stored_index(v >> vec3(shift), dims, shift);
}

// traversal=occupancy: one move per step, as `trace_occupancy_counted` in src/world/traversal.rs: the ray is in
// voxel v at t; the step finds the coarsest cell holding v that the masks prove empty (a region, a box of
// sectors, a sector, a box of bricks, a brick, a box of 2^3 cells, a 2^3 cell, a voxel; a box of 3^3 or 2^3
// children reaches ahead of the ray's own child where it can) and leaves it through its nearest face. The masks of
// the region, sector and brick the ray is in, and the word of the brick's voxel mask for its 4^3 quadrant, stay in
// registers and are loaded only when a move enters a new one, so every step does the same few bit tests; past
// the first voxel of a quadrant a material is read only at the hit. (The CPU walks the voxels of an occupied 2^3
// cell in a loop of its own; here they stay steps of the one loop, so lanes keep in step.)
fn trace_occupancy(origin: vec3<f32>, dir: vec3<f32>, max_distance: f32) -> Hit {
    // Nothing solid lies outside the occupied box: a ray starts where it enters it and misses where it leaves.
    let box_lo = world_info.occupied_lo;
    let box_hi = world_info.occupied_hi;
    let entry = box_entry(origin, dir, vec3<f32>(box_lo), vec3<f32>(box_hi));
    let t_end = min(entry.y, max_distance);
    var t = max(entry.x, 0.0);
    if !(t <= t_end) || all(dir == vec3(0.0)) || any(box_hi <= box_lo) {
        return miss();
    }
    let inv = inverse_dir(dir);
    let positive = dir > vec3(0.0);
    let no_dir = dir == vec3(0.0);
    // 1 on the axes whose far face a cell is left through is its high one.
    let far_side = select(vec3(0), vec3(1), positive);
    var axis = u32(entry.z);
    if entry.x < 0.0 {
        let o = floor(origin);
        axis = u32(box_entry(origin, dir, o, o + vec3(1.0)).z);
    }
    let last = window_hi() - vec3(1);
    var v = clamp(vec3<i32>(floor(origin + dir * t)), box_lo, box_hi - vec3(1));
    // The child masks of the region, sector and brick the ray is in, the brick's index and its pool slot once read
    // (NO_SLOT before); `entered`: the coarsest level whose cell the last move changed (a mask of that level or
    // below is stale).
    var region_mask = vec2(0u);
    var sector_mask = vec2(0u);
    var slot = NO_SLOT;
    // The word of the brick's voxel mask the ray holds (its quadrant, NO_QUADRANT before one is read) and the
    // quadrant whose first voxel it read.
    var quadrant = NO_QUADRANT;
    var quadrant_mask = vec2(0u);
    var probed = NO_QUADRANT;
    // A ray that starts in an occupied brick (as one leaving a surface does) reads that brick's mask first: it
    // needs its sector's and region's masks only once it leaves the brick (`*_unread` until then).
    trace_loads += 1u;
    var brick = mask_index(v, world_info.bricks, BRICK_SHIFT);
    var brick_mask = occupancy[brick];
    let starts_in_brick = any(brick_mask != vec2(0u));
    var region_unread = starts_in_brick;
    var sector_unread = starts_in_brick;
    var entered = select(REGION_SHIFT, CELL_BOX_LEVEL, starts_in_brick);
    // Every step crosses at least one voxel boundary; the bound only stops a non-finite t. A constant: lavapipe's
    // primary pass took twice as long with the world's own size here (docs/bench/traversal.md).
    let max_steps = 3 * i32(MAX_WORLD_EDGE) + 8;
    for (var i = 0; i < max_steps; i++) {
        trace_steps += 1u;
        // The level of the coarsest empty cell holding v (edge 0 while every mask says occupied). A mask's tests
        // are skipped while the ray stays in the child it last proved occupied: a move out of a cell of a
        // sector's size or more crosses a sector's face, so `entered` < SECTOR_SHIFT means the last step found the sector
        // occupied; likewise for bricks.
        var cell = vec4(v, 0);
        if entered >= SECTOR_SHIFT {
            if entered >= REGION_SHIFT || region_unread {
                trace_loads += 1u;
                region_mask = occupancy[world_info.region_base + mask_index(v, world_info.regions, REGION_SHIFT)];
                region_unread = false;
            }
            let region_edge = i32(1) << REGION_SHIFT;
            cell = select(empty_child_cell(region_mask, v, SECTOR_SHIFT, positive), vec4(v & vec3(~(region_edge - 1)), region_edge),
                          all(region_mask == vec2(0u)));
            if cell.w == 0 {
                trace_loads += 1u;
                sector_mask = occupancy[world_info.sector_base + mask_index(v, world_info.sectors, SECTOR_SHIFT)];
                sector_unread = false;
            }
        }
        if cell.w == 0 {
            if entered >= BRICK_SHIFT {
                if sector_unread {
                    trace_loads += 1u;
                    sector_mask = occupancy[world_info.sector_base + mask_index(v, world_info.sectors, SECTOR_SHIFT)];
                    sector_unread = false;
                }
                cell = empty_child_cell(sector_mask, v, BRICK_SHIFT, positive);
                if cell.w == 0 {
                    // The brick's mask first: its top cell (homogeneous, or the pool slot) is read only where a
                    // voxel must be.
                    trace_loads += 1u;
                    brick = mask_index(v, world_info.bricks, BRICK_SHIFT);
                    brick_mask = occupancy[brick];
                    slot = NO_SLOT;
                    quadrant = NO_QUADRANT;
                    probed = NO_QUADRANT;
                }
            }
            if cell.w == 0 {
                cell = empty_child_cell(brick_mask, v, CELL_SHIFT, positive);
                if cell.w == 0 {
                    if slot == NO_SLOT {
                        trace_loads += 1u;
                        let top = top_cells[brick];
                        if top != 0u && (top & POOLED_FLAG) == 0u {
                            return Hit(v, face_entered(axis, positive[axis]), t, top, true, 0u);
                        }
                        slot = select(NO_SLOT, top & ~POOLED_FLAG, top != 0u);
                    }
                    if slot == NO_SLOT {
                        // An empty top cell under an occupied mask (never with masks kept current): an empty brick.
                        cell = vec4(v & vec3(~(BRICK_SIZE - 1)), BRICK_SIZE);
                    } else {
                        // The first voxel tested in a 4^3 quadrant of the brick is read (often the hit); past it
                        // the quadrant's word of the voxel mask is loaded, and a material read only at the hit.
                        let local = v & vec3(BRICK_SIZE - 1);
                        let q = local >> vec3(2u);
                        let word = u32(q.x + 2 * (q.y + 2 * q.z));
                        var material = 0u;
                        if word == quadrant || word == probed {
                            if word != quadrant {
                                trace_loads += 1u;
                                quadrant = word;
                                quadrant_mask = occupancy[world_info.voxel_mask_base + slot * VOXEL_MASK_WORDS + word];
                            }
                            let place = local & vec3(3);
                            if has_child(quadrant_mask, u32(place.x + 4 * (place.y + 4 * place.z))) {
                                trace_loads += 1u;
                                material = pooled_voxel(slot, local);
                            }
                        } else {
                            probed = word;
                            trace_loads += 1u;
                            material = pooled_voxel(slot, local);
                        }
                        if material != 0u {
                            return Hit(v, face_entered(axis, positive[axis]), t, material, true, 0u);
                        }
                    }
                }
            }
        }
        // Out of that cell (a voxel where every mask said occupied) through its nearest face (the same planes and
        // products as `cross_t`).
        let edge = max(cell.w, 1);
        let lo = cell.xyz;
        let planes = vec3<f32>(lo + far_side * edge);
        let t_max = select((planes - origin) * inv, vec3(INF), no_dir);
        let a = min_axis(t_max);
        t = t_max[a];
        if t > t_end {
            break;
        }
        axis = a;
        let before = v[a];
        v[a] = select(lo[a] - 1, lo[a] + edge, positive[a]);
        if v[a] < box_lo[a] || v[a] >= box_hi[a] {
            break;
        }
        entered = firstLeadingBit(u32(before ^ v[a]));
        if edge > 1 {
            // v's other axes are the ray's only to the cell's precision: the voxel the ray is in at t, within the
            // cell's extent on every axis but a.
            let moved = v[a];
            v = clamp(vec3<i32>(floor(origin + dir * t)), lo, min(lo + vec3(edge - 1), last));
            v[a] = moved;
        }
    }
    return miss();
}

#endif

// The first solid voxel of object o along the ray, before max_distance: the object's box, then a DDA through its
// voxels (at most MAX_MODEL_EDGE per side, so at most OBJECT_TRACE_STEPS steps).
fn trace_object(o: Object, origin: vec3<f32>, dir: vec3<f32>, max_distance: f32) -> Hit {
    let size = vec3<f32>(o.size);
    let entry = box_entry(origin, dir, o.min, o.min + size);
    let t_end = min(entry.y, max_distance);
    var t = max(entry.x, 0.0);
    if !(t <= t_end) || all(dir == vec3(0.0)) {
        return miss();
    }
    let p = origin - o.min;
    let inv = inverse_dir(dir);
    let step = vec3<i32>(sign(dir));
    let positive = dir > vec3(0.0);
    let hi = vec3<i32>(o.size) - vec3(1);
    // Entered through a box face; a ray starting inside takes the axis it travels most along.
    var axis = u32(entry.z);
    if entry.x < 0.0 {
        let a = abs(dir);
        axis = select(select(2u, 1u, a.y >= a.z), 0u, a.x >= a.y && a.x >= a.z);
    }
    var voxel = clamp(vec3<i32>(floor(p + dir * t)), vec3(0), hi);
    var t_max: vec3<f32>;
    for (var a = 0u; a < 3u; a++) {
        t_max[a] = cross_t(p[a], dir[a], inv[a], f32(voxel[a] + select(0, 1, positive[a])));
    }
    for (var i = 0; i < OBJECT_TRACE_STEPS; i++) {
        let material = object_voxel(o, voxel);
        if material != 0u {
            return Hit(voxel, face_entered(axis, positive[axis]), t, material, true, o.id);
        }
        let a = min_axis(t_max);
        t = t_max[a];
        if t > t_end {
            break;
        }
        axis = a;
        voxel[a] += step[a];
        if voxel[a] < 0 || voxel[a] > hi[a] {
            break;
        }
        t_max[a] = cross_t(p[a], dir[a], inv[a], f32(voxel[a] + select(0, 1, positive[a])));
    }
    return miss();
}

// The nearest moving object's voxel along the ray, before max_distance.
fn trace_objects(origin: vec3<f32>, dir: vec3<f32>, max_distance: f32) -> Hit {
    var best = miss();
    let count = object_count();
    for (var i = 0u; i < count; i++) {
        let hit = trace_object(objects[i], origin, dir, min(best.distance, max_distance));
        if hit.found && hit.distance < best.distance {
            best = hit;
        }
    }
    return best;
}

// The first solid voxel of the static world or of a moving object: what camera, shadow and GI rays see.
fn trace_scene(origin: vec3<f32>, dir: vec3<f32>, max_distance: f32) -> Hit {
    let world = trace(origin, dir, max_distance);
    if object_count() == 0u {
        return world;
    }
    let object = trace_objects(origin, dir, min(world.distance, max_distance));
    if object.found {
        return object;
    }
    return world;
}
