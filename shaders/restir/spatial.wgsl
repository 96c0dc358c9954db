// Voxel ReSTIR pass 2: spatial reuse. Each pixel merges its reservoir with k neighbours' in a disk of radius r
// pixels that share its face orientation and depth (within 10%). With spatial reuse off, it copies.

#import glowbrick::traversal::{count_rays}
#import glowbrick::constants::COUNT_RAYS_RESTIR_SPATIAL
#import glowbrick::frame::{restir_flag, frame, view, gbuffer, unpack_surface, pixel_index, render_size}
#import glowbrick::constants::{RESTIR_SPATIAL, MAX_TAPS, PI}
#import glowbrick::random::{Rng, rng_next}
#import glowbrick::restir::common::{Reservoir, Shading, reservoirs_temporal, reservoirs_final, empty_reservoir, validated,
    shading, stream, finalize, pair_weight, target_of, reservoir_visible, unbiased, own_sample_rays, pixel_rng}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    spatial_pixel(id);
    count_rays(COUNT_RAYS_RESTIR_SPATIAL);
}

fn spatial_pixel(id: vec3<u32>) {
    let size = render_size();
    if any(id.xy >= size) {
        return;
    }
    let index = pixel_index(id.xy);
    let own = validated(reservoirs_temporal[index]);
    let surface = unpack_surface(gbuffer[index]);
    if !surface.found || !restir_flag(RESTIR_SPATIAL) || frame.taps == 0u {
        reservoirs_final[index] = own;
        return;
    }
    let x = shading(surface);
    let depth = distance(view.world_position, x.point);
    var rng = pixel_rng(id.xy, 2u);

    // Gather the neighbours first: pairwise MIS needs their count k.
    var taps: array<u32, MAX_TAPS>;
    var tap_reservoirs: array<Reservoir, MAX_TAPS>;
    var used = 0u;
    var m_total = own.m;
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
        taps[used] = tap_index;
        tap_reservoirs[used] = validated(reservoirs_temporal[tap_index]);
        m_total += tap_reservoirs[used].m;
        used++;
    }

    // Pairwise MIS (pair_weight): each neighbour against this pixel's reservoir, the canonical input.
    var merged = empty_reservoir();
    let k = f32(max(used, 1u));
    let m_share = own.m / k;
    // The temporal pass stored this pixel's target at its own sample.
    let p_own_at_own = own.target_value;
    var m_own = 1.0;
    for (var j = 0u; j < used; j++) {
        let tap = tap_reservoirs[j];
        let neighbour = shading(unpack_surface(gbuffer[taps[j]]));
        let share = select(0.0, (tap.m + m_share) / m_total, m_total > 0.0);
        // The neighbour's sample, weighed at both pixels. The unbiased variant resamples with this pixel's
        // visibility-tested target, as its MIS weights use it: with an unshadowed target, a sample this pixel
        // cannot see would get the neighbour's full weight with nothing to damp its W, and inflate w_sum.
        var p_own_at_tap = target_of(x, tap);
        // (Each visibility ray below is skipped where the weight it decides multiplies a W of 0.)
        if unbiased() && p_own_at_tap > 0.0 && tap.big_w > 0.0 && !reservoir_visible(x, tap) {
            p_own_at_tap = 0.0;
        }
        let m_tap = pair_weight(tap.m, target_of(neighbour, tap), m_share, p_own_at_tap, share);
        stream(&merged, tap, m_tap * p_own_at_tap * tap.big_w, tap.m, rng_next(&rng));
        // This pixel's sample, seen from the neighbour.
        var p_tap_at_own = target_of(neighbour, own);
        if own_sample_rays() && p_tap_at_own > 0.0 && own.big_w > 0.0 && !reservoir_visible(neighbour, own) {
            p_tap_at_own = 0.0;
        }
        m_own -= pair_weight(tap.m, p_tap_at_own, m_share, p_own_at_own, share);
    }
    stream(&merged, own, max(m_own, 0.0) * p_own_at_own * own.big_w, own.m, rng_next(&rng));
    finalize(&merged, target_of(x, merged));
    reservoirs_final[index] = merged;
}
