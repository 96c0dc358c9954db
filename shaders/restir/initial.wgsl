// Voxel ReSTIR pass 1: M_init candidates per pixel by resampled importance sampling. It traces no ray: the chosen
// candidate's visibility and the temporal reuse are the next pass (temporal.wgsl), so this kernel, the frame's
// costliest, holds no traversal code and keeps its registers for the candidates' loads in flight.

#import glowbrick::frame::{gbuffer, unpack_surface, pixel_index, render_size, view, frame}
#import glowbrick::random::rng_next
#import glowbrick::guards::finite
#import glowbrick::restir::common::{reservoirs_temporal, empty_reservoir, shading, local_lights, pixel_tile,
    sample_candidate, draw_point, stream, target_of, pixel_rng}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = render_size();
    if any(id.xy >= size) {
        return;
    }
    let index = pixel_index(id.xy);
    let surface = unpack_surface(gbuffer[index]);
    if !surface.found {
        reservoirs_temporal[index] = empty_reservoir();
        return;
    }
    let x = shading(surface);
    var rng = pixel_rng(id.xy, 1u);

    // Initial candidates (streaming RIS).
    var r = empty_reservoir();
    var local = local_lights(x);
    let tile = pixel_tile(id.xy);
    for (var i = 0u; i < frame.candidates; i++) {
        let c = sample_candidate(x, &local, tile, &rng);
        let weight = select(0.0, c.r.target_value / c.pdf, c.pdf > 0.0);
        stream(&r, c.r, weight, 1.0, rng_next(&rng));
    }
    // W = w_sum / (M x the chosen candidate's target); a near face's candidate was resampled by its face's target
    // times its point's pdf, the point drawn now.
    let pair_target = r.target_value;
    let point_pdf = draw_point(x, &r);
    let own_target = target_of(x, r);
    let denominator = r.m * pair_target * point_pdf;
    r.big_w = select(0.0, r.w_sum / denominator, denominator > 0.0 && own_target > 0.0);
    r.big_w = select(0.0, r.big_w, finite(r.big_w));
    r.target_value = own_target;
    reservoirs_temporal[index] = r;
}
