// GI cache refresh, one thread per static entry due this frame (listed by compact.wgsl), before the update: brings a due entry's K cached static hits up
// to date. A new entry traces all K; after an edit, only the rays whose segments cross an edited brick are traced
// again, and entries whose rays cannot reach any edit keep every hit (counted: COUNT_GI_RETRACED, COUNT_GI_RAYS_TRACED).
// Without the static visibility cache (gi_cached_hits=off, the default) nothing is kept: an entry an edit may reach
// (inside the box of the segments update.wgsl traced for it) restarts its blend. Then, either way, the entry's
// own direct light.

#import glowbrick::traversal::{trace, box_entry, INF, count_rays_only}
#import glowbrick::gi::cache::{gi_setting, gi, gi_entries, gi_rays, gi_edits, gi_direct, GiEntry, listed_slot, ray_direction,
    ray_origin, slot_seed, world_exit, encode_hit, hit_face, hit_distance, is_surface, forget_value, NEVER_TRACED, LOST_FACE, MISS_FACE, NOT_FOUND,
    WORK_STATIC}
#import glowbrick::gi::direct::update_direct
#import glowbrick::counters::counters
#import glowbrick::constants::{GI_CACHE, COUNT_GI_RETRACED, COUNT_GI_RAYS_TRACED, COUNT_RAYS_GI}

// Whether an edit since the entry's trace may have reached its rays at all: an edited brick overlaps the box
// around its ray segments. Cheap; the rays themselves are tested only when it says yes.
fn maybe_stale(e: GiEntry) -> bool {
    for (var i = 0u; i < gi.edit_count; i++) {
        if edit_reaches(e, i) {
            return true;
        }
    }
    return false;
}

fn edit_reaches(e: GiEntry, i: u32) -> bool {
    let lo = gi_edits[2u * i];
    if u32(lo.w) <= e.traced_epoch {
        return false;
    }
    let hi = vec3<f32>(gi_edits[2u * i + 1u].xyz);
    return all(e.lo <= hi) && all(e.hi >= vec3<f32>(lo.xyz));
}

// Whether the segment from `origin` along `dir` for `length` passes through edit i's bricks. The margin covers
// the cached distance's rounding (1/256 voxel, always short of the face).
fn segment_crosses_edit(origin: vec3<f32>, dir: vec3<f32>, length: f32, i: u32) -> bool {
    let margin = vec3(0.05);
    let lo = vec3<f32>(gi_edits[2u * i].xyz) - margin;
    let hi = vec3<f32>(gi_edits[2u * i + 1u].xyz) + margin;
    let t = box_entry(origin, dir, lo, hi);
    return t.x <= t.y && t.y >= 0.0 && t.x <= length;
}

// Where ray i's static segment ends: its cached hit, or where it leaves the world.
fn segment_length(origin: vec3<f32>, dir: vec3<f32>, code: u32) -> f32 {
    if hit_face(code) != MISS_FACE {
        return hit_distance(code);
    }
    return world_exit(origin, dir);
}

// Brings an entry's K cached static hits up to date: all of them when it was never traced (or edits it cannot
// check were forgotten), else only the rays whose segments cross a brick edited since. Returns the rays traced.
fn refresh(slot: u32, e: GiEntry, origin: vec3<f32>) -> u32 {
    let everything = e.traced_epoch == NEVER_TRACED || e.traced_epoch < gi.lost_epoch;
    if !everything && (e.traced_epoch == gi.epoch || !maybe_stale(e)) {
        if e.traced_epoch != gi.epoch {
            gi_entries[slot].traced_epoch = gi.epoch;
        }
        return 0u;
    }
    var lo = origin;
    var hi = origin;
    var traced = 0u;
    for (var i = 0u; i < gi.rays; i++) {
        let dir = ray_direction(e.face, i, gi.rays, slot_seed(slot));
        var code = gi_rays[slot * gi.rays + i];
        var stale = everything;
        if !stale {
            let length = segment_length(origin, dir, code);
            for (var k = 0u; k < gi.edit_count && !stale; k++) {
                stale = edit_reaches(e, k) && segment_crosses_edit(origin, dir, length, k);
            }
        }
        if stale {
            let hit = trace(origin, dir, INF);
            code = encode_hit(hit.found, hit.face, hit.distance);
            gi_rays[slot * gi.rays + i] = code;
            traced++;
        }
        let end = origin + dir * segment_length(origin, dir, code);
        lo = min(lo, end);
        hi = max(hi, end);
    }
    gi_entries[slot].lo = lo - vec3(1.0);
    gi_entries[slot].hi = hi + vec3(1.0);
    gi_entries[slot].traced_epoch = gi.epoch;
    // An edit reached it without changing its hits: the light at them may have changed all the same. One sample
    // keeps its value for readers and marks it for the edit restart (update.wgsl, GI_EDIT_RESTART).
    if traced == 0u && e.samples > 1u {
        gi_entries[slot].samples = 1u;
    }
    if traced > 0u {
        atomicAdd(&counters[COUNT_GI_RETRACED], 1u);
        atomicAdd(&counters[COUNT_GI_RAYS_TRACED], traced);
    }
    return traced;
}

// Per due static entry: its cached hits brought up to date (with the static cache on), then its own direct
// light, one shadow ray (direct.wgsl), which the update pass reads wherever a cache ray hits this face.
@compute @workgroup_size(64, 1, 1)
fn refresh_static(@builtin(global_invocation_id) id: vec3<u32>) {
    refresh_static_entry(id);
    count_rays_only(COUNT_RAYS_GI);
}

fn refresh_static_entry(id: vec3<u32>) {
    let slot = listed_slot(WORK_STATIC, id.x);
    if slot == NOT_FOUND {
        return;
    }
    let e = gi_entries[slot];
    // A coarse entry stays in use while any face of its cell is hit, but it is kept by the face that inserted it
    // (the fallback when a face drawn across its cell is not a surface, and with cached hits its rays' origin):
    // once an edit removes that face, mark it for the next compaction to free (the next hit inserts
    // it again from a face that exists; until then it keeps its value). A fine entry whose face went is simply
    // no longer touched.
    if e.level > 0u && !is_surface(e.voxel, e.face) {
        gi_entries[slot].traced_epoch = LOST_FACE;
        return;
    }
    if gi_setting(GI_CACHE) {
        if refresh(slot, e, ray_origin(e.voxel, e.face, vec3(0.0))) > 0u {
            // What it blended so far saw the old world: start over, its direct light too (an edit reached it).
            forget_value(slot);
            gi_direct[slot].light = vec4(0.0);
        }
    } else if e.traced_epoch != gi.epoch {
        // Fresh directions (nothing cached): an edit inside the bounds of the segments traced so far restarts the
        // blend as a retraced hit does (one sample marks it for update.wgsl's GI_EDIT_RESTART), counted as
        // retraced. The blend restarts fully rather than part way: a partial restart leaves every bounce lagging
        // the one before it, so an opened doorway's far side takes tens of frames to reach its new light
        // (docs/bench/why.md).
        let forgotten = e.traced_epoch < gi.lost_epoch;
        if e.samples > 1u && e.traced_epoch != NEVER_TRACED && (forgotten || maybe_stale(e)) {
            gi_entries[slot].samples = 1u;
            atomicAdd(&counters[COUNT_GI_RETRACED], 1u);
        }
        gi_entries[slot].traced_epoch = gi.epoch;
    }
    update_direct(slot, e);
}
