// GI cache update, one thread per entry due this frame (listed by compact.wgsl): re-shade `update_rays` of an entry's K
// directions from its cached static hits (brought up to date by refresh.wgsl) or, for a moving object's
// entry, from rays traced now; light at a hit is the hit face's direct light (its entry's estimate, kept once a
// frame by refresh.wgsl; traced here only when the face has none yet) plus its face's cached indirect light from
// last frame (and emission where the shading passes do not already count it); blend. Rays that leave the world
// bring the sky (lighting=full and the sun-only look).

#import glowbrick::world::{materials, voxel_at, objects, object_index, object_count, albedo_at}
#import glowbrick::traversal::{Hit, trace, trace_objects, trace_scene, face_normal, INF, count_rays_only}
#import glowbrick::lights::{lighting_mode, scene, sky}
#import glowbrick::random::{Rng, pcg, rng_next, r4_point, rotation2, rotation4}
#import glowbrick::guards::finite3
#import glowbrick::counters::counters
#import glowbrick::constants::{RAY_OFFSET, LIGHTING_SUN, LIGHTING_FULL, GI_BOUNCES, GI_CACHE, GI_RESTART, GI_EDIT_RESTART, GI_QMC, GI_GUIDING, COUNT_GI_BORROWED, COUNT_RAYS_GI,
    COUNT_GI_RESETS, COUNT_GI_DIRECT_TRACED}
#import glowbrick::gi::cache::{gi_setting, gi, gi_entries, gi_irradiance, gi_filtered, gi_rays, gi_direct, gi_probe,
    GiEntry, has_filtered_value, listed_slot, hit_level, used_within, settled_samples, sequence_step, slot_seed, world_exit, ray_direction, ray_square_point, cosine_direction, hit_face, hit_distance, ray_origin, NOT_FOUND, MISS_FACE,
    WORK_STATIC, WORK_DYNAMIC}
#import glowbrick::gi::direct::{direct_at, cell_point}
#import glowbrick::gi::guide::{load_guide, guided_point, guide_bin, guide_record, store_guide}

// The indirect light a hit face's entry holds (its last filtered value), or `fallback` (the shooting entry's
// own) where it has none yet or no room in a full table: counted as borrowed. (Told by its colour, which this pass
// does not write: see cache.wgsl's forget_value.)
// In the first iteration after a change of light there is none: the start from zero (GI_RESTART).
fn incoming_at(slot: u32, fallback: vec3<f32>) -> vec3<f32> {
    if (gi.flags & GI_RESTART) != 0u && gi.iteration == 0u {
        return vec3(0.0);
    }
    if slot != NOT_FOUND && has_filtered_value(slot) {
        return gi_filtered[slot].rgb;
    }
    borrowed++;
    return fallback;
}

// The face a ray brings light from: the static world's (voxel, face) or a moving object's, where the ray met it.
struct RayHit {
    point: vec3<f32>,
    voxel: vec3<i32>,
    face: u32,
    // 0: the static world.
    object: u32,
    material: u32,
    // The level of the hit face's entry: the static world's from the hit's distance, an object's 0.
    level: u32,
}

// Light arriving along a ray that hit `hit`: the hit face's direct light, with bounces on its cached indirect
// light (last frame's filtered value: stable while this pass writes), and emission where the shading passes do
// not already count it.
//
// The static world's hit face: its direct light is its entry's estimate (the face's or cell's average,
// refresh.wgsl), traced here only where it has none; emission only in sun-and-sky mode (with emitter lighting
// the shading passes' light sampling already brings every emitter's direct light to the pixel, and counting it
// again here would double it).
//
// A moving object's face: its emission always (objects' emitters are not in the light pool, so this is the only
// way their light reaches other surfaces), its direct light traced, and with bounces on, the indirect light of
// its entry in the moving objects' table (a lantern's frame, lit by its own core, passes that light on), touched
// by entries the camera sees as static hits are. Static entries read it and never cache it: their cached hits
// stay static (the split).
//
// One body for both, with one call of each costly step (the entry's lookup, the traced direct light): software
// Vulkan runs both sides of every branch, so two bodies cost every ray both.
fn hit_radiance(hit: RayHit, seen: bool, fallback: vec3<f32>, rng: ptr<function, Rng>) -> vec3<f32> {
    let on_object = hit.object != 0u;
    var id = hit.material;
    if !on_object {
        id = voxel_at(hit.voxel);
        if id == 0u {
            // Removed this frame, before the edit reached the cache.
            return vec3(0.0);
        }
    }
    let m = materials[id];
    let albedo = albedo_at(id, hit.voxel, hit.object);
    let bounces = gi_setting(GI_BOUNCES);
    // Entries the camera sees bring the entries their rays hit into the cache (with bounces on); others only look
    // up.
    let slot = gi_probe(hit.voxel, hit.face, hit.object, hit.level, seen && bounces, false);
    var radiance = vec3(0.0);
    if !on_object && slot != NOT_FOUND && gi_direct[slot].light.w > 0.0 {
        radiance = gi_direct[slot].light.rgb;
    } else {
        // No estimate yet (new, or not in the cache), or a moving face: this ray's own sample, unbiased (counted
        // for the static world's faces).
        if !on_object {
            direct_traced++;
        }
        radiance = direct_at(hit.point, face_normal(hit.face), albedo, rng);
    }
    if on_object || lighting_mode() == LIGHTING_SUN {
        radiance += m.radiance.rgb;
    }
    if bounces {
        // A hit face without a value yet (or no room for it in a full table) borrows the shooting entry's own
        // indirect light: nearby surfaces of a room see similar indirect light, and leaving it out would
        // darken every later bounce.
        radiance += albedo * incoming_at(slot, fallback);
    }
    return radiance;
}

// A ray that leaves the world sees the sky (not the disk: hits sample that as direct light) where there is one.
fn miss_radiance(dir: vec3<f32>) -> vec3<f32> {
    return select(vec3(0.0), sky(dir), lighting_mode() == LIGHTING_SUN || lighting_mode() == LIGHTING_FULL);
}

// One of an entry's rays this frame: where it starts, where it goes, and the static world's hit (if any); with
// guided rays, the guide's bin it was drawn in and its weight (the cosine lobe's density over the mixture's; 1
// for unguided rays).
struct EntryRay {
    start: vec3<f32>,
    dir: vec3<f32>,
    found: bool,
    face: u32,
    distance: f32,
    bin: u32,
    weight: f32,
}

// The ray generators' inputs for one entry this frame.
struct RayPlan {
    // The face's centre, where cached hits and a moving object's rays start.
    origin: vec3<f32>,
    seed: u32,
    frame_seed: u32,
    // Cached hits: the first of the K fixed directions re-shaded this frame.
    first: u32,
    // Fresh rays: where this frame's run continues the entry's low-discrepancy sequence, and its rotation.
    run: u32,
    rotation: vec4<u32>,
    // Fresh rays of a static entry start from a point of its cell.
    spread: bool,
    // Fresh rays drawn from the entry's guide (gi_guiding; guide.wgsl), loaded for this thread, and this
    // frame's shift of their points of the square.
    guided: bool,
    shift: vec2<f32>,
}

// With cached hits, each frame re-shades the next `update_rays` of the entry's K fixed directions; a frame's
// further iterations (after a change of light) start 3 groups further on each, other directions at the game's
// K and update rays.
fn cached_ray(e: GiEntry, slot: u32, plan: RayPlan, j: u32) -> EntryRay {
    let i = (plan.first + j) % gi.rays;
    let code = gi_rays[slot * gi.rays + i];
    let face = hit_face(code);
    return EntryRay(plan.origin, ray_direction(e.face, i, gi.rays, plan.seed), face != MISS_FACE, face, hit_distance(code), 0u, 1.0);
}

// Without cached hits each frame draws `update_rays` fresh directions (a fixed set leaves each entry a quadrature
// error of its own that no blend averages: docs/bench/gi.md, "Fresh directions"). With gi_qmc (the default) the
// directions and start points are the entry's own shifted 4D Kronecker sequence (random.wgsl), continued frame
// after frame and iteration after iteration, so the blend of the last frames' rays covers the hemisphere and the
// cell evenly (docs/bench/gi.md, "Low-discrepancy rays"). Without, this frame's directions are stratified (a
// Hammersley set turned by a seed of the frame's, not the rng's stream, which the hits' direct light draws from)
// and the start points random. Guided, the direction's point of the square is warped to the entry's guide.
fn fresh_ray(e: GiEntry, plan: RayPlan, j: u32, rng: ptr<function, Rng>) -> EntryRay {
    // The direction's point of the unit square (cosine_direction's), and the start point's place on the cell.
    var square: vec2<f32>;
    var across: vec2<f32>;
    if gi_setting(GI_QMC) {
        let u = r4_point(plan.run + j, plan.rotation);
        square = u.xy;
        across = u.zw;
    } else {
        square = ray_square_point(j, gi.update_rays, pcg(plan.seed ^ plan.frame_seed ^ 0x68BC21EBu));
        across = vec2(rng_next(rng), rng_next(rng));
    }
    var bin = 0u;
    var weight = 1.0;
    if plan.guided {
        // The guide is learnt from the entry's earlier rays, and a sequence continued across frames is a
        // function of those same rays: warped by the guide it is no longer spread evenly (the window room's
        // bounce light came out 17% bright). A random shift of this frame's own keeps its rays stratified
        // among themselves and independent of the guide.
        let guided = guided_point(fract(square + plan.shift));
        square = guided.u;
        bin = guided.bin;
        weight = 1.0 / guided.density;
    }
    let dir = cosine_direction(e.face, square);
    // A static entry's value is then its cell's average, as its direct light is, whichever face inserted it (a
    // cache that lived through an edit settles where a fresh one does).
    var start = plan.origin;
    if plan.spread {
        start = cell_point(e, across).point + face_normal(e.face) * RAY_OFFSET;
    }
    let hit = trace(start, dir, INF);
    return EntryRay(start, dir, hit.found, hit.face, hit.distance, bin, weight);
}

// The light a ray brings: a moving object in front of the static hit replaces it for this frame.
fn ray_radiance(ray: EntryRay, level: u32, seen: bool, own: vec3<f32>, rng: ptr<function, Rng>) -> vec3<f32> {
    let object = trace_objects(ray.start, ray.dir, select(INF, ray.distance, ray.found));
    if !object.found && !ray.found {
        return miss_radiance(ray.dir);
    }
    var hit: RayHit;
    if object.found {
        object_hit = true;
        hit = RayHit(ray.start + ray.dir * object.distance, object.voxel, object.face, object.object, object.material, 0u);
    } else {
        let point = ray.start + ray.dir * ray.distance;
        let voxel = vec3<i32>(floor(point - face_normal(ray.face) * 0.5));
        hit = RayHit(point, voxel, ray.face, 0u, 0u, hit_level(ray.distance, level));
    }
    return hit_radiance(hit, seen, own, rng);
}

// Blends this frame's estimate into the entry. Young entries average with weights growing linearly with age
// (frame j weighs j + 1): their first estimates come before the light has travelled the bounces (their hits are
// young too), and an even average keeps that shortfall for 1 / alpha frames (docs/bench/gi.md). After about
// 2 / alpha frames it is an exponential blend.
//
// A settled entry whose light is still rising (the bounces of a large scene arrive over hundreds of frames, or the
// light changed) lags behind it by about 1 / alpha frames. So each entry also keeps a fast luminance average (at
// FAST_BLEND times alpha, in the blended radiance's w) and the variance of its estimates about it (in the
// filtered radiance's w): while the fast and the slow average differ by more than DRIFT_SIGMAS times the noise of
// their difference, the entry blends at the fast weight. A still, converged entry's averages differ by noise
// alone, so it keeps alpha and its noise (docs/bench/frame.md, "A noise-aware fast blend").
const FAST_BLEND: f32 = 4.0;
const DRIFT_SIGMAS: f32 = 3.0;
const LUMINANCE: vec3<f32> = vec3(0.2126, 0.7152, 0.0722);

fn blend_estimate(slot: u32, age: u32, estimate: vec3<f32>) -> bool {
    let old = gi_irradiance[slot];
    let young = 2.0 / f32(age + 2u);
    let fast_alpha = min(FAST_BLEND * gi.alpha, 1.0);
    let luminance = dot(estimate, LUMINANCE);
    var fast = luminance;
    var variance = 0.0;
    var weight = 1.0;
    var drifting = false;
    if age > 0u {
        let fast_weight = max(fast_alpha, young);
        fast = mix(old.a, luminance, fast_weight);
        let deviation = luminance - old.a;
        variance = mix(gi_filtered[slot].a, deviation * deviation, fast_weight);
        // Variance of an exponential average at weight a: a / (2 - a) times the estimates' variance.
        let noise = sqrt(variance * (fast_alpha / (2.0 - fast_alpha) + gi.alpha / (2.0 - gi.alpha)));
        drifting = age > 8u && abs(fast - dot(old.rgb, LUMINANCE)) > DRIFT_SIGMAS * noise;
        weight = max(select(gi.alpha, fast_alpha, drifting), young);
    }
    gi_irradiance[slot] = vec4(mix(old.rgb, estimate, weight), fast);
    gi_filtered[slot].a = variance;
    return drifting;
}

// The ray generators' inputs for the entry `e` in `slot`.
fn ray_plan(e: GiEntry, slot: u32, cached: bool, dynamic: bool) -> RayPlan {
    // Only a moving object's entry looks its object up (a scan of the object list; compact.wgsl freed the
    // entries of objects that are gone).
    var base = vec3(0.0);
    if dynamic {
        base = objects[object_index(e.object)].min;
    }
    let seed = slot_seed(slot);
    let frame_seed = pcg(gi.frame ^ (gi.iteration << 28u));
    var first = 0u;
    if cached {
        first = pcg(seed ^ 0x5bd1e995u) + (sequence_step(gi.frame, e) + gi.iteration * 3u) * gi.update_rays;
    }
    return RayPlan(
        ray_origin(e.voxel, e.face, base),
        seed,
        frame_seed,
        first,
        sequence_step(gi.update_run + gi.iteration, e) * gi.update_rays,
        rotation4(seed ^ 0x68BC21EBu),
        !cached && !dynamic,
        !cached && gi_setting(GI_GUIDING),
        vec2<f32>(rotation2(seed ^ frame_seed) >> vec2(8u)) * (1.0 / 16777216.0),
    );
}

// Ages and re-shades the entry in `slot`. Static entries read their cached static hits and test only
// the moving objects per frame; a moving object's entries trace everything every frame (nothing of theirs stays
// put).
// `dynamic`: the slot lies in the moving objects' table (its entry's object is not 0). A constant of each entry
// point, so each compiles only its own table's paths.
fn update_entry(slot: u32, dynamic: bool) {
    let e = gi_entries[slot];
    // The refresh pass (refresh.wgsl) has brought the cached hits up to date this frame.
    let cached = gi_setting(GI_CACHE) && !dynamic;
    let plan = ray_plan(e, slot, cached, dynamic);
    let samples = e.samples;
    // After a change of light the blend starts over from this frame's estimate (the samples count stays for
    // the readers: the entry still has a value).
    // After an edit, the entries it reached (marked with one sample by refresh.wgsl, as are new ones) do the same
    // for a few frames, while the new light travels the bounces.
    let edit_restart = (gi.flags & GI_EDIT_RESTART) != 0u && samples <= 1u;
    let age = select(samples, 0u, (gi.flags & GI_RESTART) != 0u || edit_restart);
    let seen = used_within(e.last_seen, 1u) && !dynamic;
    let own = select(vec3(0.0), gi_filtered[slot].rgb, samples > 0u);
    var rng = Rng(pcg(plan.seed ^ plan.frame_seed));
    var lo = select(plan.origin, e.lo, samples > 0u);
    var hi = select(plan.origin, e.hi, samples > 0u);
    if plan.guided {
        load_guide(slot);
    }
    var sum = vec3(0.0);
    for (var j = 0u; j < gi.update_rays; j++) {
        var ray: EntryRay;
        if cached {
            ray = cached_ray(e, slot, plan, j);
        } else {
            ray = fresh_ray(e, plan, j, &rng);
        }
        if plan.spread {
            // The bounds of every segment traced so far: an edit inside them restarts the blend (refresh.wgsl),
            // as a retraced cached hit does.
            let end = ray.start + ray.dir * select(world_exit(ray.start, ray.dir), ray.distance, ray.found);
            lo = min(lo, min(ray.start, end));
            hi = max(hi, max(ray.start, end));
        }
        let radiance = ray_radiance(ray, e.level, seen, own, &rng) * ray.weight;
        if plan.guided {
            guide_record(ray.bin, dot(radiance, LUMINANCE));
        }
        sum += radiance;
    }
    var estimate = sum / f32(gi.update_rays);
    if !finite3(estimate) {
        atomicAdd(&counters[COUNT_GI_RESETS], 1u);
        estimate = vec3(0.0);
    }
    let drifting = blend_estimate(slot, age, estimate);
    if plan.guided {
        store_guide(slot, age);
    }
    if plan.spread {
        gi_entries[slot].lo = lo;
        gi_entries[slot].hi = hi;
    }
    // While settled entries skip frames, an entry whose rays met a moving object, or whose light is drifting,
    // goes back a quarter of the way to settled: it updates every frame (compact.wgsl) for that many frames after
    // the object was last among its hits or the drift ended, at a blend weight at most a third above alpha (a
    // drifting one at the fast weight). (At a period of 1 every entry updates every frame anyway, and its blend
    // stays as it was.)
    let unsettle = (object_hit || drifting) && gi.period > 1u;
    let most = select(1u << 20u, max(settled_samples() - settled_samples() / 4u, 2u), unsettle);
    gi_entries[slot].samples = min(age + 1u, most);
}

// This thread's hits that borrowed their value or traced their own direct light, summed per workgroup and
// added to the counters once per workgroup (a global atomic per ray serialises the lanes).
var<private> borrowed: u32;
var<private> direct_traced: u32;
// Whether one of this thread's rays hit a moving object (ray_radiance).
var<private> object_hit: bool;
var<workgroup> borrowed_in_group: atomic<u32>;
var<workgroup> direct_traced_in_group: atomic<u32>;

fn update_listed(work: u32, i: u32, local: u32) {
    // Workgroup memory starts undefined (pipelines do not ask for it zeroed).
    if local == 0u {
        atomicStore(&borrowed_in_group, 0u);
        atomicStore(&direct_traced_in_group, 0u);
    }
    workgroupBarrier();
    let slot = listed_slot(work, i);
    if slot != NOT_FOUND {
        update_entry(slot, work == WORK_DYNAMIC);
    }
    if borrowed > 0u {
        atomicAdd(&borrowed_in_group, borrowed);
    }
    if direct_traced > 0u {
        atomicAdd(&direct_traced_in_group, direct_traced);
    }
    workgroupBarrier();
    if local == 0u {
        atomicAdd(&counters[COUNT_GI_BORROWED], atomicLoad(&borrowed_in_group));
        atomicAdd(&counters[COUNT_GI_DIRECT_TRACED], atomicLoad(&direct_traced_in_group));
    }
}

@compute @workgroup_size(64, 1, 1)
fn update_static(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    update_listed(WORK_STATIC, id.x, local);
    count_rays_only(COUNT_RAYS_GI);
}

// The moving objects' table, dispatched only while objects exist.
@compute @workgroup_size(64, 1, 1)
fn update_dynamic(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    update_listed(WORK_DYNAMIC, id.x, local);
    count_rays_only(COUNT_RAYS_GI);
}
