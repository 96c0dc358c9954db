// Denoiser pass 1 (render::denoise): demodulate this frame's noisy light, blend it into the history reprojected
// from last frame, and estimate its luminance variance for the wavelet passes.

#import glowbrick::world::{materials, object_motion, albedo_at}
#import glowbrick::frame::{frame, view, gbuffer, prev_gbuffer, noisy, history, prev_history, wavelet, unpack_surface, surface_voxel,
    pixel_index, render_size, previous_pixel, previous_render_pixel, upscaling, luminance, Surface}
#import glowbrick::constants::DENOISE_HISTORY
#import glowbrick::denoise::common::{MAX_HISTORY, ALBEDO_FLOOR, same_plane}

// Light at a pixel over its albedo, emission set aside: what the filter smooths (textures stay sharp).
fn demodulated(index: u32, s: Surface) -> vec3<f32> {
    let m = materials[s.material];
    let lighting = max(noisy[index].rgb - m.radiance.rgb * frame.exposure, vec3(0.0));
    return lighting / max(albedo_at(s.material, surface_voxel(s), s.object), vec3(ALBEDO_FLOOR));
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = render_size();
    if any(id.xy >= size) {
        return;
    }
    let index = pixel_index(id.xy);
    let s = unpack_surface(gbuffer[index]);
    if !s.found {
        // The sky: nothing to filter (variance -1 says so to the wavelet passes).
        history[2u * index] = vec4(0.0);
        history[2u * index + 1u] = vec4(0.0);
        wavelet[index] = vec4(noisy[index].rgb, -1.0);
        return;
    }
    // No firefly clamp: clipping a sample to 10x its brightest neighbour darkened the test room's mean and did
    // not lower the error (docs/bench/denoise.md); the wavelet's luminance weights already keep a lone
    // bright sample from smearing.
    let c = demodulated(index, s);
    // Last frame's history where the same surface was seen: same face axis and sign, same object, depth within
    // 10% (as ReSTIR's temporal reuse). A moving object's point is where it was last frame (its motion vector).
    var length = 0.0;
    var previous = vec3(0.0);
    var moments = vec2(0.0);
    if (frame.denoise & DENOISE_HISTORY) != 0u {
        let then = s.point - object_motion(s.object);
        // Below scale 1 the render pixel whose sample lay nearest (a render pixel samples one output pixel of its
        // footprint); at scale 1 the pixel that saw the point, as before.
        var p: vec3<i32>;
        if upscaling() {
            p = previous_render_pixel(then);
        } else {
            p = previous_pixel(then, size);
        }
        if p.z == 1 {
            let pi = u32(p.x) + size.x * u32(p.y);
            let ps = unpack_surface(prev_gbuffer[pi]);
            let depth_now = distance(frame.prev_camera.xyz, then);
            let depth_then = distance(frame.prev_camera.xyz, ps.point);
            if ps.found && ps.face == s.face && ps.object == s.object && abs(depth_now - depth_then) <= 0.1 * depth_now {
                let h = prev_history[2u * pi];
                previous = h.rgb;
                length = h.a;
                moments = prev_history[2u * pi + 1u].xy;
            }
        }
    }
    length = min(length + 1.0, MAX_HISTORY);
    // While the history is short, this frame's 3x3 neighbourhood on the same plane: its spread stands in for the
    // variance. One loop of length 0 once the history is long enough: software Vulkan runs a loop's body under a
    // mask for as long as any lane needs it, so the nine lookups cost a settled pixel nothing but the first.
    var sum = 0.0;
    var sum_squares = 0.0;
    var count = 0.0;
    let cells = select(0, 9, length < 4.0);
    for (var cell = 0; cell < cells; cell++) {
        let q = vec2<i32>(id.xy) + vec2(cell % 3 - 1, cell / 3 - 1);
        if any(q < vec2(0)) || any(q >= vec2<i32>(size)) {
            continue;
        }
        let qi = pixel_index(vec2<u32>(q));
        let sq = unpack_surface(gbuffer[qi]);
        if !same_plane(s, sq) {
            continue;
        }
        let l = luminance(demodulated(qi, sq));
        sum += l;
        sum_squares += l * l;
        count += 1.0;
    }
    let alpha = 1.0 / length;
    let colour = mix(previous, c, alpha);
    let lc = luminance(c);
    moments = mix(moments, vec2(lc, lc * lc), alpha);
    var variance = max(moments.y - moments.x * moments.x, 0.0);
    if length < 4.0 && count > 0.0 {
        // Too few frames for the moments: the neighbourhood's spread stands in.
        let mean = sum / count;
        variance = max(sum_squares / count - mean * mean, 0.0);
    }
    history[2u * index] = vec4(colour, length);
    history[2u * index + 1u] = vec4(moments, 0.0, 0.0);
    wavelet[index] = vec4(colour, variance);
}
