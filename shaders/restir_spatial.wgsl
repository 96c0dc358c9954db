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
    var z = merged.m;
    if unbiased() && merged.slot != 0xffffffffu {
        // 1/Z normalisation (Bitterli et al. 2020, Alg. 6): count the inputs whose own (visibility-tested)
        // target is non-zero at the chosen sample, one visibility ray per neighbour.
        z = select(0.0, own.m, target_value > 0.0);
        for (var j = 0u; j < used; j++) {
            let neighbour = shading(unpack_surface(gbuffer[taps[j]]));
            if target_of(neighbour, merged) > 0.0 && (source == i32(j) || reservoir_visible(neighbour, merged)) {
                z += tap_m[j];
            }
        }
    }
    finalize(&merged, target_value, z);
    reservoirs_final[index] = merged;
}
