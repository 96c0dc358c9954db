// Voxel ReSTIR pass 2: spatial reuse. Each pixel merges its reservoir with k neighbours' in a disk of radius r
// pixels that share its face orientation and depth (within 10%). With spatial reuse off, it copies.

#import glowbrick::frame::{frame, view, gbuffer, unpack_surface, pixel_index, RESTIR_SPATIAL}
#import glowbrick::lights::{Rng, rng_next, PI}
#import glowbrick::restir::{Reservoir, Shading, reservoirs_temporal, reservoirs_final, empty_reservoir, validated,
    shading, stream, finalize, target_of, reservoir_visible, unbiased, pixel_rng}

// Settings clamp taps to this (src/settings.rs).
const MAX_TAPS: u32 = 16u;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(view.viewport.zw);
    if any(id.xy >= size) {
        return;
    }
    let index = pixel_index(id.xy);
    let own = validated(reservoirs_temporal[index]);
    let surface = unpack_surface(gbuffer[index]);
    if !surface.found || (frame.restir_flags & RESTIR_SPATIAL) == 0u || frame.taps == 0u {
        reservoirs_final[index] = own;
        return;
    }
    let x = shading(surface);
    let depth = distance(view.world_position, x.point);
    var rng = pixel_rng(id.xy, 2u);

    var merged = empty_reservoir();
    stream(&merged, own, target_of(x, own) * own.big_w * own.m, own.m, rng_next(&rng));
    // Which input the merged sample came from: -1 this pixel, else the tap number.
    var source = -1;
    var taps: array<u32, MAX_TAPS>;
    var tap_m: array<f32, MAX_TAPS>;
    var used = 0u;
    for (var i = 0u; i < min(frame.taps, MAX_TAPS); i++) {
        let angle = 2.0 * PI * rng_next(&rng);
        let radius = frame.radius * sqrt(rng_next(&rng));
        let offset = vec2<i32>(round(vec2(cos(angle), sin(angle)) * radius));
        let pixel = vec2<i32>(id.xy) + offset;
        if all(offset == vec2(0)) || any(pixel < vec2(0)) || any(pixel >= vec2<i32>(size)) {
            continue;
        }
        let tap_index = pixel_index(vec2<u32>(pixel));
        let tap_surface = unpack_surface(gbuffer[tap_index]);
        if !tap_surface.found || tap_surface.face != surface.face
            || abs(distance(view.world_position, tap_surface.point) - depth) > 0.1 * depth {
            continue;
        }
        let tap = validated(reservoirs_temporal[tap_index]);
        if stream(&merged, tap, target_of(x, tap) * tap.big_w * tap.m, tap.m, rng_next(&rng)) {
            source = i32(used);
        }
        taps[used] = tap_index;
        tap_m[used] = tap.m;
        used++;
    }
    let target_value = target_of(x, merged);
    // The balance heuristic for the chosen sample (see finalize): every input's target at it. The unbiased
    // variant tests visibility from each input that is not the sample's source (one ray per input); the biased
    // one skips those rays and darkens a little where inputs see the sample differently.
    var p_own = target_value;
    if unbiased() && source != -1 && p_own > 0.0 && !reservoir_visible(x, merged) {
        p_own = 0.0;
    }
    var sum = own.m * p_own;
    var p_source = p_own;
    for (var j = 0u; j < used; j++) {
        let neighbour = shading(unpack_surface(gbuffer[taps[j]]));
        var p = target_of(neighbour, merged);
        if unbiased() && source != i32(j) && p > 0.0 && !reservoir_visible(neighbour, merged) {
            p = 0.0;
        }
        if source == i32(j) {
            p_source = p;
        }
        sum += tap_m[j] * p;
    }
    let mis = select(0.0, p_source / sum, sum > 0.0 && merged.slot != 0xffffffffu);
    finalize(&merged, target_value, mis);
    reservoirs_final[index] = merged;
}
