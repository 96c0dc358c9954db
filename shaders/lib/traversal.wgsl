// Ray traversal of the brick grid: DDA over bricks (skipping empty ones), then over voxels of pooled bricks.
// Mirrors src/world/traversal.rs step for step (same boundary formulas and tie rules) so GPU and CPU agree.
#define_import_path glowbrick::traversal

#import glowbrick::world::{world_info, brick_cell, pooled_voxel, objects, object_count, object_voxel, Object}
#import glowbrick::constants::{POOLED_FLAG, BRICK_SIZE, BRICK_SHIFT, COUNT_BRICK_STEPS, COUNT_VOXEL_STEPS}
#import glowbrick::counters::counters

const INF: f32 = 3.0e38;

// Brick-grid rays (calls of `trace`) this invocation traced, added to a pass's per-frame counter once per
// invocation by a pass whose entry point ends with `count_rays` (same-address atomics from a SIMD group are
// combined by the compiler on GPUs; a workgroup sum with two barriers cost more on software Vulkan).
var<private> rays_traced: u32;
// Their steps at each level of the grid, each step one memory load: of the top grid (a brick), of the brick pool (a
// voxel). Added to the frame's totals by the same call.
var<private> brick_steps: u32;
var<private> voxel_steps: u32;

// For the GI cache's passes: their rays only (their steps are not the per-pixel passes' totals).
fn count_rays_only(counter: u32) {
    if rays_traced > 0u {
        atomicAdd(&counters[counter], rays_traced);
    }
}

fn count_rays(counter: u32) {
    if rays_traced > 0u {
        atomicAdd(&counters[counter], rays_traced);
        atomicAdd(&counters[COUNT_BRICK_STEPS], brick_steps);
        if voxel_steps > 0u {
            atomicAdd(&counters[COUNT_VOXEL_STEPS], voxel_steps);
        }
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

// Voxel DDA inside the pooled brick `brick` (pool slot `slot`), entered at parameter t through `entry_axis`.
fn trace_in_brick(origin: vec3<f32>, dir: vec3<f32>, inv: vec3<f32>, brick: vec3<i32>, slot: u32, t_start: f32,
                  t_end: f32, entry_axis: u32) -> Hit {
    let step = vec3<i32>(sign(dir));
    let positive = dir > vec3(0.0);
    let lo = brick * BRICK_SIZE;
    let hi = min(lo + vec3(BRICK_SIZE), world_info.size) - vec3(1);
    var t = t_start;
    var axis = entry_axis;
    var voxel = clamp(vec3<i32>(floor(origin + dir * t)), lo, hi);
    var t_max: vec3<f32>;
    for (var a = 0u; a < 3u; a++) {
        t_max[a] = cross_t(origin[a], dir[a], inv[a], f32(voxel[a] + select(0, 1, positive[a])));
    }
    // At most 22 steps cross an 8^3 brick; the bound guards against a non-finite t.
    for (var i = 0; i < 3 * BRICK_SIZE; i++) {
        voxel_steps += 1u;
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

// The first solid voxel along the ray (unit `dir`) within max_distance.
fn trace(origin: vec3<f32>, dir: vec3<f32>, max_distance: f32) -> Hit {
    rays_traced += 1u;
    let size = vec3<f32>(world_info.size);
    let entry = box_entry(origin, dir, vec3(0.0), size);
    let t_end = min(entry.y, max_distance);
    var t = max(entry.x, 0.0);
    if !(t <= t_end) || all(dir == vec3(0.0)) {
        return miss();
    }
    let inv = inverse_dir(dir);
    let step = vec3<i32>(sign(dir));
    let positive = dir > vec3(0.0);
    let edge = f32(BRICK_SIZE);
    let last_brick = max((world_info.size - vec3(1)) >> vec3(BRICK_SHIFT), vec3(0));
    var axis = u32(entry.z);
    if entry.x < 0.0 {
        let v = floor(origin);
        axis = u32(box_entry(origin, dir, v, v + vec3(1.0)).z);
    }
    var brick = clamp(vec3<i32>(floor((origin + dir * t) / edge)), vec3(0), last_brick);
    var brick_t_max: vec3<f32>;
    for (var a = 0u; a < 3u; a++) {
        brick_t_max[a] = cross_t(origin[a], dir[a], inv[a], f32(brick[a] + select(0, 1, positive[a])) * edge);
    }
    let max_steps = last_brick.x + last_brick.y + last_brick.z + 3;
    for (var i = 0; i < max_steps; i++) {
        brick_steps += 1u;
        let cell = brick_cell(brick);
        if cell != 0u {
            if (cell & POOLED_FLAG) == 0u {
                let lo = brick * BRICK_SIZE;
                let voxel = min(clamp(vec3<i32>(floor(origin + dir * t)), lo, lo + vec3(BRICK_SIZE - 1)),
                                world_info.size - vec3(1));
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
        if brick[a] < 0 || brick[a] > last_brick[a] {
            break;
        }
        brick_t_max[a] = cross_t(origin[a], dir[a], inv[a], f32(brick[a] + select(0, 1, positive[a])) * edge);
    }
    return miss();
}

// The first solid voxel of object o along the ray, before max_distance: the object's box, then a DDA through its
// voxels (at most 16 per side, so at most 48 steps).
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
    for (var i = 0; i < 48; i++) {
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
