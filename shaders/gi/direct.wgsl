// Direct light for the GI cache: what a surface reflects of the sun (the sun-only look), of the light pool (one
// next-event-estimation sample), or of both the pool and the sun's or moon's disk (lighting=full), and each entry's own estimate of it, kept once per entry per frame with one
// shadow ray (refresh.wgsl) so a cache ray that hits the entry's face reads it instead of tracing its own.
#define_import_path glowbrick::gi::direct

#import glowbrick::world::{voxel_at, albedo_at}
#import glowbrick::traversal::{trace_scene, face_normal, INF}
#import glowbrick::lights::{lighting_mode, power_pick_on, shadows_on, scene, direct_sample, disk_sample}
#import glowbrick::random::{Rng, pcg, rng_next, r2_point, rotation2}
#import glowbrick::guards::finite3
#import glowbrick::constants::{LIGHTING_SUN, LIGHTING_FULL, RAY_OFFSET, GI_RESTART, GI_RESTART_SAMPLES, GI_QMC, GI_RESERVOIRS}
#import glowbrick::gi::reservoir::reservoir_sample
#import glowbrick::gi::cache::{gi_setting, gi, gi_direct, tangent_axes, slot_seed, cell_of, is_surface, sequence_step, GiEntry}

// The blend of an entry's direct estimate: young entries average evenly, then an exponential blend over about
// 10 frames (faster than the indirect light's alpha: direct light is the bounce's source, so its lag adds up).
const DIRECT_ALPHA: f32 = 0.1;

// Direct light reflected by a surface at `point` (normal n): the sun with a shadow ray in the sun-only look, else
// one next-event-estimation sample of the light pool, plus one of the disk with lighting=full. (The sky is not
// direct light here: the cache's own rays that leave the world bring it, update.wgsl.)
fn direct_at(point: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, Rng>) -> vec3<f32> {
    if lighting_mode() != LIGHTING_SUN {
        var direct = direct_sample(point, n, albedo, scene.light_count, power_pick_on(), rng);
        if lighting_mode() == LIGHTING_FULL {
            direct += disk_sample(point, n, albedo, rng);
        }
        return direct;
    }
    let cos_sun = dot(n, scene.sun.xyz);
    if scene.sun.w > 0.0 && cos_sun > 0.0 && (!shadows_on() || !trace_scene(point + n * RAY_OFFSET, scene.sun.xyz, INF).found) {
        return albedo * scene.sun_radiance.rgb * cos_sun;
    }
    return vec3(0.0);
}

// A point of the entry's cell: `u` in the unit square across the cell picks a column of its voxels along the
// face's normal and the spot on a face (at level 0 the entry's own face): the column's first face of the entry's
// orientation seen from outside, so what a coarse entry's value stands for is its cell's average over what rays
// arriving there meet, whichever face inserted it. Where the column holds none, the same spot on the inserting
// face (so a cell that faces cover only in part still leans, in those columns, toward whichever face inserted it;
// as do the rays of gi_cached_hits=on, which start from the inserting face). The point lies inside its face by a
// hair: one exactly on a neighbour's plane could start a ray in that voxel.
struct CellPoint {
    voxel: vec3<i32>,
    point: vec3<f32>,
}

fn cell_point(e: GiEntry, u: vec2<f32>) -> CellPoint {
    let t = tangent_axes(e.face);
    let size = 1u << e.level;
    let across = u * f32(size);
    var voxel = e.voxel;
    if e.level > 0u {
        // Searched from the side the face looks toward. (The inserting face's own plane made the cell stand for
        // whichever face won the insert, a race between workgroups: docs/bench/gi.md.)
        let axis = e.face / 2u;
        var other = cell_of(e.voxel, e.level) << vec3(e.level);
        other[t.x] += i32(min(u32(across.x), size - 1u));
        other[t.y] += i32(min(u32(across.y), size - 1u));
        let low = other[axis];
        let outward = (e.face & 1u) == 0u;
        for (var k = 0; k < i32(size); k++) {
            other[axis] = select(low + k, low + i32(size) - 1 - k, outward);
            // The first solid voxel ends the search: a face behind it is hidden (only the outermost one can be
            // covered, from beyond the cell).
            if voxel_at(other) != 0u {
                if is_surface(other, e.face) {
                    voxel = other;
                }
                break;
            }
        }
    }
    let spot = fract(across) - vec2(0.5);
    var point = vec3<f32>(voxel) + vec3(0.5) + face_normal(e.face) * 0.5;
    point[t.x] += spot.x * 0.98;
    point[t.y] += spot.y * 0.98;
    return CellPoint(voxel, point);
}

// One direct-light sample at point `u` of the entry's cell (cell_point): the light pool's by the entry's
// reservoir (gi_reservoirs=on, reservoir.wgsl) or by one power-drawn light (direct_at), plus the disk's.
fn face_sample(slot: u32, e: GiEntry, u: vec2<f32>, rng: ptr<function, Rng>) -> vec3<f32> {
    let at = cell_point(e, u);
    let albedo = albedo_at(voxel_at(at.voxel), at.voxel, 0u);
    let n = face_normal(e.face);
    var estimate = vec3(0.0);
    if gi_setting(GI_RESERVOIRS) && lighting_mode() != LIGHTING_SUN {
        estimate = reservoir_sample(slot, cell_point(e, vec2(0.5)).point, at.point, n, albedo, e.level > 0u, rng);
        if lighting_mode() == LIGHTING_FULL {
            estimate += disk_sample(at.point, n, albedo, rng);
        }
    } else {
        estimate = direct_at(at.point, n, albedo, rng);
    }
    return select(vec3(0.0), estimate, finite3(estimate));
}

// Point k of the entry's own R2 sequence (`rotation`), or with gi_qmc=off a random one.
fn cell_sample_point(k: u32, rotation: vec2<u32>, rng: ptr<function, Rng>) -> vec2<f32> {
    if gi_setting(GI_QMC) {
        return r2_point(k, rotation);
    }
    return vec2(rng_next(rng), rng_next(rng));
}

// Blends one direct-light sample into the entry's estimate: over frames the estimate becomes the face's
// average direct light, which is what a ray hitting anywhere on the face reads. After a change of light
// (GI_RESTART) it starts over from GI_RESTART_SAMPLES samples: with one, a whole room swings with the few faces
// the light reaches first, since every entry's bounces read them (docs/bench/why.md).
fn update_direct(slot: u32, e: GiEntry) {
    if voxel_at(e.voxel) == 0u {
        gi_direct[slot].light = vec4(0.0);
        return;
    }
    var rng = Rng(pcg(slot_seed(slot) ^ pcg(gi.frame ^ 0x2545F491u)));
    // Where on the cell: frame k samples point k of the entry's own shifted R2 sequence (gi_qmc), so the last
    // frames' points cover the cell evenly, as a half-lit coarse cell needs.
    let rotation = rotation2(slot_seed(slot) ^ 0x51ED270Bu);
    // After a change of light the points of the frames up to this one (the next frames continue the run), else
    // this frame's. One call site for both: the restart's samples in a loop of their own were inlined nine times,
    // and lavapipe pays for code a dispatch holds whether its lanes run it or not (docs/bench/why.md).
    let restart = (gi.flags & GI_RESTART) != 0u;
    let samples = select(1u, GI_RESTART_SAMPLES, restart);
    let first = select(sequence_step(gi.frame, e), gi.frame, restart);
    var sum = vec3(0.0);
    for (var i = 0u; i < samples; i++) {
        sum += face_sample(slot, e, cell_sample_point(first - i, rotation, &rng), &rng);
    }
    if restart {
        gi_direct[slot].light = vec4(sum / f32(GI_RESTART_SAMPLES), f32(GI_RESTART_SAMPLES));
        return;
    }
    let estimate = sum;
    let old = gi_direct[slot].light;
    let count = old.w;
    let weight = max(DIRECT_ALPHA, 1.0 / (count + 1.0));
    let blended = select(mix(old.rgb, estimate, weight), estimate, count == 0.0);
    gi_direct[slot].light = vec4(blended, min(count + 1.0, 1.0e6));
}
