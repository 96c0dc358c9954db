// Voxel ReSTIR pass 2: the visibility ray of the candidate pass 1 chose (initial.wgsl), then temporal reuse of
// last frame's final reservoir at the reprojected pixel. Split from the candidates so that the traversal's
// registers do not lower the occupancy of the candidates' kernel (docs/bench/why.md).

#import glowbrick::traversal::{count_rays}
#import glowbrick::constants::COUNT_RAYS_RESTIR_INITIAL
#import glowbrick::frame::{restir_flag, frame, view, gbuffer, prev_gbuffer, unpack_surface, pixel_index, render_size, previous_pixel}
#import glowbrick::constants::{RESTIR_TEMPORAL, RESTIR_INITIAL_VISIBILITY}
#import glowbrick::world::object_motion
#import glowbrick::random::rng_next
#import glowbrick::restir::common::{reservoirs_temporal, reservoirs_final, empty_reservoir, validated, shading, stream,
    finalize, pair_weight, target_of, reservoir_visible, unbiased, own_sample_rays, pixel_rng}

// Temporal history is capped at this many times M_init (DESIGN.md), so old samples cannot dominate forever.
const HISTORY_CAP: f32 = 20.0;
// The cap where last frame's shading point is not this frame's (a moving camera, or the upscaler's jitter). A
// history of M_p against this frame's M_c can carry a sample's weight forward multiplied by up to M_p / M_c when
// the sample's target was small where it was drawn and is large here (pairwise MIS with confidence weights), and
// a moving point keeps making that happen: frame after frame the factor compounds into fireflies.
const MOVING_HISTORY_CAP: f32 = 4.0;

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    temporal_pixel(id);
    // The candidates' rays: counted as ReSTIR's initial rays, as before the split.
    count_rays(COUNT_RAYS_RESTIR_INITIAL);
}

fn temporal_pixel(id: vec3<u32>) {
    let size = render_size();
    if any(id.xy >= size) {
        return;
    }
    let index = pixel_index(id.xy);
    let surface = unpack_surface(gbuffer[index]);
    if !surface.found {
        return;
    }
    let x = shading(surface);
    var rng = pixel_rng(id.xy, 4u);
    let m_init = f32(frame.candidates);
    var r = reservoirs_temporal[index];

    // Visibility reuse (thesis §4.4): an occluded choice keeps its M but contributes nothing when reused. Without
    // this ray the shading pass's final shadow ray gives the same verdict to next frame's reuse.
    let test_visibility = restir_flag(RESTIR_INITIAL_VISIBILITY);
    if test_visibility && r.big_w > 0.0 && !reservoir_visible(x, r) {
        r.big_w = 0.0;
        r.w_sum = 0.0;
    }

    if restir_flag(RESTIR_TEMPORAL) && frame.prev_camera.w > 0.0 {
        // A moving object's surface has no temporal reuse: the reuse would weigh the old sample at the object's
        // old place against this frame's geometry (the objects buffer holds only where objects are now); both
        // following the object and reusing across its edges brighten a sliding block (the motion bench,
        // docs/bench/denoise.md). Its candidates and spatial reuse remain.
        let moving = any(object_motion(surface.object) != vec3(0.0));
        let prev_pixel = select(previous_pixel(x.point, size), vec3(-1), moving);
        if prev_pixel.z == 1 {
            let prev_index = u32(prev_pixel.x) + size.x * u32(prev_pixel.y);
            let prev_surface = unpack_surface(prev_gbuffer[prev_index]);
            // The same object (or the static world), face orientation (axis and sign) and depth within 10% seen
            // from last frame's camera.
            let depth_now = distance(frame.prev_camera.xyz, x.point);
            let depth_then = distance(frame.prev_camera.xyz, prev_surface.point);
            let same = prev_surface.found && prev_surface.face == surface.face && prev_surface.object == surface.object;
            if same && abs(depth_now - depth_then) <= 0.1 * depth_now {
                let prev_shading = shading(prev_surface);
                // From the same point (a still camera) both inputs see with the same visibility and target.
                let moved = any(prev_shading.point != x.point);
                var prev = validated(reservoirs_final[prev_index]);
                prev.m = min(prev.m, select(HISTORY_CAP, MOVING_HISTORY_CAP, moved) * m_init);
                let current = r;
                // Pairwise MIS with one neighbour is the balance heuristic (see pair_weight); the unbiased
                // variant tests each sample's visibility from the other input (two rays).
                var p_current_at_prev = target_of(x, prev);
                let p_prev_at_prev = target_of(prev_shading, prev);
                var p_prev_at_current = target_of(prev_shading, current);
                // This pixel's target at its own sample, computed above.
                let p_current_at_current = current.target_value;
                // (Each visibility ray below is skipped where the weight it decides multiplies a W of 0.)
                if unbiased() && p_current_at_prev > 0.0 && prev.big_w > 0.0 && !reservoir_visible(x, prev) {
                    p_current_at_prev = 0.0;
                }
                // From the same point both inputs see with the same visibility: no ray.
                if own_sample_rays() && moved && p_prev_at_current > 0.0 && current.big_w > 0.0
                    && !reservoir_visible(prev_shading, current) {
                    p_prev_at_current = 0.0;
                }
                let m_prev = pair_weight(prev.m, p_prev_at_prev, current.m, p_current_at_prev, 1.0);
                let m_current = 1.0 - pair_weight(prev.m, p_prev_at_current, current.m, p_current_at_current, 1.0);
                var merged = empty_reservoir();
                stream(&merged, current, m_current * p_current_at_current * current.big_w, current.m, rng_next(&rng));
                // Resample with the same (visibility-tested, when unbiased) target the weights use.
                stream(&merged, prev, m_prev * p_current_at_prev * prev.big_w, prev.m, rng_next(&rng));
                finalize(&merged, target_of(x, merged));
                r = merged;
            }
        }
    }
    reservoirs_temporal[index] = r;
}
