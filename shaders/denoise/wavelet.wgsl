// Denoiser passes 2-6 (render::denoise): the edge-aware a-trous wavelet, a 3x3 binomial kernel spread 1, 2, 4, 8
// and 16 pixels apart, ping-ponging between the two halves of `wavelet` (45 taps a pixel, where four 5x5 B3
// iterations took 100 for about the same reach: docs/bench/denoise.md, "A 3x3 kernel"). A tap counts only on the
// pixel's own voxel-face plane (exact geometry edges) and is weighted down by its luminance difference against the
// variance, and by how much farther it lies in the world than its offset in pixels says (a plane seen at a
// grazing angle). The last iteration remodulates, draws the highlight and writes the image.

#import glowbrick::world::{materials, albedo_at}
#import glowbrick::frame::{debug_view, frame, view, gbuffer, history, wavelet, unpack_surface, pixel_index, present, draw_highlight,
    surface_voxel, luminance, pixel_footprint, render_size, upscaling}
#import glowbrick::constants::{DEBUG_VARIANCE, DEBUG_HISTORY}
#import glowbrick::denoise::common::{MAX_HISTORY, ALBEDO_FLOOR, same_plane}

// A tap whose luminance differs by this many standard deviations weighs 1/e as much (SVGF's sigma_l).
const SIGMA_LUMINANCE: f32 = 4.0;

// The binomial weights (1/4, 1/2, 1/4) by offset.
fn kernel(offset: i32) -> f32 {
    return select(0.25, 0.5, offset == 0);
}

fn pixel_count() -> u32 {
    return render_size().x * render_size().y;
}

// One iteration at `pixel`, reading the half of `wavelet` at `source`: filtered colour and its variance.
fn filtered(pixel: vec2<u32>, step: i32, source: u32) -> vec4<f32> {
    let size = vec2<i32>(render_size());
    let index = pixel_index(pixel);
    let centre = wavelet[source + index];
    let s = unpack_surface(gbuffer[index]);
    if !s.found || centre.a < 0.0 {
        return centre;
    }
    let l = luminance(centre.rgb);
    // One over the squared world distance of one step of this iteration at the centre's pixel footprint.
    let per_step = 1.0 / pixel_footprint(s.point) / f32(step);
    let per_step_squared = per_step * per_step;
    var sum = vec3(0.0);
    var variance = 0.0;
    var weights = 0.0;
    for (var dy = -1; dy <= 1; dy++) {
        for (var dx = -1; dx <= 1; dx++) {
            let q = vec2<i32>(pixel) + vec2(dx, dy) * step;
            if any(q < vec2(0)) || any(q >= size) {
                continue;
            }
            let qi = pixel_index(vec2<u32>(q));
            let sq = unpack_surface(gbuffer[qi]);
            if !same_plane(s, sq) {
                continue;
            }
            // Distance in the world in units of this iteration's step at the centre's pixel footprint: its offset
            // in pixels on a plane facing the camera, far more on one seen edge-on (the far ground), where a
            // screen-space kernel mixed light from voxels far apart and left streaks along the rows. Only the
            // excess is weighted down.
            let apart = s.point - sq.point;
            let stretch = max(dot(apart, apart) * per_step_squared - f32(dx * dx + dy * dy), 0.0);
            let tap = wavelet[source + qi];
            // The pair's larger deviation, so a dark pixel with no variance of its own still gathers from a
            // bright neighbour that spreads: with each pixel's own, bright samples lost energy to neighbours that
            // never took it (the image darkened). Tried and not kept (docs/bench/denoise.md): the centre's
            // variance smoothed over 3x3 as in SVGF, and the pair's smaller one (the lamp-lit room kept more noise).
            let sigma = SIGMA_LUMINANCE * sqrt(max(max(centre.a, tap.a), 0.0)) + 1e-4;
            let w = kernel(dx) * kernel(dy) * exp(-abs(luminance(tap.rgb) - l) / sigma - 0.5 * stretch);
            sum += w * tap.rgb;
            variance += w * w * max(tap.a, 0.0);
            weights += w;
        }
    }
    // The centre is always a tap: weights > 0.
    return vec4(sum / weights, variance / (weights * weights));
}

@compute @workgroup_size(8, 8, 1)
fn step_1(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id.xy < render_size()) {
        wavelet[pixel_count() + pixel_index(id.xy)] = filtered(id.xy, 1, 0u);
    }
}

@compute @workgroup_size(8, 8, 1)
fn step_2(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id.xy < render_size()) {
        wavelet[pixel_index(id.xy)] = filtered(id.xy, 2, pixel_count());
    }
}

@compute @workgroup_size(8, 8, 1)
fn step_4(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id.xy < render_size()) {
        wavelet[pixel_count() + pixel_index(id.xy)] = filtered(id.xy, 4, 0u);
    }
}

@compute @workgroup_size(8, 8, 1)
fn step_8(@builtin(global_invocation_id) id: vec3<u32>) {
    if all(id.xy < render_size()) {
        wavelet[pixel_index(id.xy)] = filtered(id.xy, 8, pixel_count());
    }
}

// The last iteration, remodulated (albedo x light + emission), with the highlight, into the image.
@compute @workgroup_size(8, 8, 1)
fn step_16_and_write(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= render_size()) {
        return;
    }
    let f = filtered(id.xy, 16, 0u);
    let index = pixel_index(id.xy);
    if upscaling() {
        // The upscaler remodulates at the output's resolution (render::upscale): the filtered light goes to it.
        wavelet[pixel_count() + index] = f;
        return;
    }
    let s = unpack_surface(gbuffer[index]);
    if !s.found || f.a < 0.0 {
        present(id.xy, vec4(f.rgb, 1.0));
        return;
    }
    let m = materials[s.material];
    var colour = max(albedo_at(s.material, surface_voxel(s), s.object), vec3(ALBEDO_FLOOR)) * f.rgb + m.radiance.rgb * frame.exposure;
    if debug_view() == DEBUG_VARIANCE {
        colour = vec3(sqrt(f.a));
    } else if debug_view() == DEBUG_HISTORY {
        colour = vec3(history[2u * index].a / MAX_HISTORY);
    }
    let depth = distance(view.world_position, s.point);
    present(id.xy, vec4(draw_highlight(colour, surface_voxel(s), s.face, s.point, depth), 1.0));
}
