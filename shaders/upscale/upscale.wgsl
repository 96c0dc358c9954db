// The upscaler (render::upscale), while the lighting passes run below the output's resolution. Two passes:
//
// - `pick` (render pixels, after the primary pass): each render pixel takes the G-buffer texel of one output
//   pixel of its footprint (`render_pixel_source`, jittered on raw frames), so the lighting passes light exact
//   hit points of the output's own rays, and touches the GI cache's entry there (the primary pass does not).
// - `main` (output pixels, last): the render pixels' demodulated light (the denoiser's filtered light, or the
//   noisy frame over its albedo) gathered from those on the output pixel's own voxel-face plane (voxel faces are
//   flat: an exact edge stop; a face with none nearby, narrower than a render pixel, takes the GI cache's entry
//   of its own voxel face), on raw frames accumulated into the output's history reprojected from last frame
//   (under the denoiser, whose light has a history of its own, not); plus the sun's (or moon's) disk at the
//   output pixel itself: its visibility where the render pixels around it on its plane agree, one shadow ray of
//   its own where they do not (a shadow edge); then remodulated by the output pixel's own albedo and emission,
//   with the highlight, into the image.

#import glowbrick::world::{materials, object_motion, albedo_at}
#import glowbrick::frame::{frame, view, gbuffer, prev_gbuffer, noisy, wavelet, unpack_surface, surface_voxel, pixel_index,
    output_texel, upscaled_texel, disk_texel, render_size, output_size, render_pixel_source, previous_pixel,
    primary_ray_dir, present, draw_highlight, denoising, pixel_footprint, Surface}
#import glowbrick::lights::{lighting_mode, background, disk_direction, disk_faces, disk_visible, disk_irradiance}
#import glowbrick::random::{Rng, pcg}
#import glowbrick::traversal::{count_rays, face_normal}
#import glowbrick::constants::COUNT_RAYS_UPSCALE
#import glowbrick::gi::cache::{gi_on, gi_touch_surface, gi_incoming, camera_level}
#import glowbrick::constants::{LIGHTING_FULL, UPSCALE_HISTORY}
#import glowbrick::denoise::common::{ALBEDO_FLOOR, same_plane}

// The history's weight is capped at this many exact samples' (a new exact sample blends at 1 / (1 + this)).
const MAX_HISTORY_WEIGHT: f32 = 8.0;
// The weight of the plane's spatial estimate beside this frame's nearest sample: a prior where the history is
// new, soon outweighed by the samples that land on the pixel itself as the jitter moves.
const PRIOR_WEIGHT: f32 = 0.1;
// A render sample's weight falls to 0 this many render pixels from the output pixel.
const TENT_RADIUS: f32 = 1.0;

@compute @workgroup_size(8, 8, 1)
fn pick(@builtin(global_invocation_id) id: vec3<u32>) {
    if any(id.xy >= render_size()) {
        return;
    }
    let texel = gbuffer[output_texel(render_pixel_source(id.xy))];
    gbuffer[pixel_index(id.xy)] = texel;
    // The GI cache's entries are touched where the lighting passes read them: at the render pixels.
    let s = unpack_surface(texel);
    if gi_on() && s.found {
        gi_touch_surface(s.point, s.face, s.object, camera_level(pixel_footprint(s.point), s.object));
    }
}

// A render pixel's light over its albedo, emission set aside.
fn render_light(index: u32, s: Surface) -> vec3<f32> {
    if denoising() {
        return wavelet[render_size().x * render_size().y + index].rgb;
    }
    let lighting = max(noisy[index].rgb - materials[s.material].radiance.rgb * frame.exposure, vec3(0.0));
    return lighting / max(albedo_at(s.material, surface_voxel(s), s.object), vec3(ALBEDO_FLOOR));
}

// What the render pixels around an output pixel say of its light: their weighted mean (the spatial estimate)
// and the one on its plane whose point lies nearest (and how far, in output pixels). Where none of the 5x5 lies
// on its plane (a face narrower than a render pixel: the thin strip of a cube's underside or side seen past its
// edge), the GI cache's light at its own voxel face instead of other faces' light.
struct Gathered {
    light: vec3<f32>,
    weight: f32,
    nearest: vec3<f32>,
    nearest_distance: f32,
    // The disk's visibility at the render pixels on the plane (their shading pass's sample): its least and most.
    disk_least: f32,
    disk_most: f32,
}

// The render pixels of the 3x3 around `pixel`'s footprint on its plane `s`, each by a tent on its distance in
// render pixels; where none is on the plane, the 5x5's, and failing that the nearest faces seen at all.
fn gather(pixel: vec2<u32>, s: Surface) -> Gathered {
    let ratio = vec2<f32>(render_size()) / vec2<f32>(output_size());
    let centre = vec2<i32>(floor((vec2<f32>(pixel) + 0.5) * ratio));
    var sum = vec3(0.0);
    var weights = 0.0;
    var count = 0.0;
    var nearest = vec3(0.0);
    var nearest_distance = 1e9;
    var disk_least = 1.0;
    var disk_most = 0.0;
    var on_plane = 0.0;
    for (var cell = 0; cell < 9; cell++) {
        let r = centre + vec2(cell % 3 - 1, cell / 3 - 1);
        if any(r < vec2(0)) || any(r >= vec2<i32>(render_size())) {
            continue;
        }
        let ri = pixel_index(vec2<u32>(r));
        let sr = unpack_surface(gbuffer[ri]);
        if !same_plane(s, sr) {
            continue;
        }
        let light = render_light(ri, sr);
        disk_least = min(disk_least, noisy[ri].a);
        disk_most = max(disk_most, noisy[ri].a);
        let offset = vec2<f32>(render_pixel_source(vec2<u32>(r))) - vec2<f32>(pixel);
        if length(offset) < nearest_distance {
            nearest_distance = length(offset);
            nearest = light;
        }
        let apart = abs(offset) * ratio;
        let tent = max(vec2(1.0) - apart / TENT_RADIUS, vec2(0.0));
        let w = tent.x * tent.y + 1e-3;
        on_plane += w;
        sum += w * light;
        weights += w;
        count += 1.0;
    }
    // No render pixel of the 3x3 on this plane (a face smaller than a render pixel): a wider look, on the plane
    // first, then the same facing, then anything seen. A loop of length 0 elsewhere.
    let cells = select(0, 25, count == 0.0);
    for (var cell = 0; cell < cells; cell++) {
        let r = centre + vec2(cell % 5 - 2, cell / 5 - 2);
        if any(r < vec2(0)) || any(r >= vec2<i32>(render_size())) {
            continue;
        }
        let ri = pixel_index(vec2<u32>(r));
        let sr = unpack_surface(gbuffer[ri]);
        if !sr.found {
            continue;
        }
        let apart = (vec2<f32>(render_pixel_source(vec2<u32>(r))) - vec2<f32>(pixel)) * ratio;
        let likeness = select(select(1e-6, 1e-3, sr.face == s.face && sr.object == s.object), 1.0, same_plane(s, sr));
        let w = likeness / (1.0 + dot(apart, apart));
        on_plane += select(0.0, w, same_plane(s, sr));
        let light = render_light(ri, sr);
        sum += w * light;
        weights += w;
        count += 1.0;
    }
    var light = sum / max(weights, 1e-20);
    if on_plane == 0.0 && gi_on() {
        // Touched here, the entry is made and kept by the cache as the render pixels' are.
        let level = camera_level(pixel_footprint(s.point), s.object);
        gi_touch_surface(s.point, s.face, s.object, level);
        light = gi_incoming(s.point, s.face, s.object, level) * frame.exposure;
        // An estimate, where the render pixels around may all have seen the sky.
        weights = max(weights, 1.0);
    }
    return Gathered(light, weights, nearest, nearest_distance, disk_least, disk_most);
}

// The disk's visibility history blends a new sample at 1 / (1 + its samples), up to this many (a penumbra's
// shade settles within a few frames; a moving shadow's edge re-traces until the history reaches the render
// pixels' verdict).
const MAX_DISK_SAMPLES: f32 = 16.0;
// Where the render pixels agree and the history does not yet, it weighs at most this many samples: a shadow that
// moved away fades in a few frames rather than 16's dozens, at a little more noise in penumbrae.
const AGREEING_DISK_SAMPLES: f32 = 4.0;

// The disk's light at an output pixel's surface, over its albedo (exposed), and its visibility history. Where the
// render pixels on its plane around it all saw the disk, or all did not, theirs, once its history has settled on
// it; otherwise (a shadow edge or a penumbra passes, or no render pixel lies on the plane) one shadow ray of its
// own toward a point of the disk, blended into its history reprojected from last frame.
fn disk_light(pixel: vec2<u32>, s: Surface, g: Gathered, previous: vec3<i32>) -> vec3<f32> {
    let n = face_normal(s.face);
    if lighting_mode() != LIGHTING_FULL || !disk_faces(n) {
        gbuffer[disk_texel(pixel)] = vec4(0.0);
        return vec3(0.0);
    }
    var seen = g.disk_least;
    var samples = 0.0;
    var history = vec2(0.0);
    if previous.z == 1 {
        history = prev_gbuffer[disk_texel(vec2<u32>(previous.xy))].xy;
    }
    // In a penumbra the render pixels' single samples often agree by chance: a history that has not settled on
    // their verdict keeps tracing (dropping it there restarted the pixel from one 0-or-1 sample).
    let agree = g.disk_least == g.disk_most && g.disk_least >= 0.0;
    let settled = history.y == 0.0 || abs(history.x - g.disk_least) < 1.0 / MAX_DISK_SAMPLES;
    if !agree || !settled {
        var rng = Rng(pcg(pixel.x + output_size().x * pixel.y) ^ pcg(frame.frame * 0x9E3779B9u + 11u));
        seen = disk_visible(s.point, n, disk_direction(&rng));
        samples = min(select(history.y, min(history.y, AGREEING_DISK_SAMPLES - 1.0), agree) + 1.0, MAX_DISK_SAMPLES);
        seen = mix(history.x, seen, 1.0 / samples);
    }
    gbuffer[disk_texel(pixel)] = vec4(seen, samples, 0.0, 0.0);
    return disk_irradiance(n) * seen * frame.exposure;
}

// The pixel of last frame's output where the same surface was seen (same face, object, depth within 10%, as the
// denoiser's reprojection), z = 1; z = 0 where there is none or the history restarted.
fn previous_output_pixel(s: Surface) -> vec3<i32> {
    if (frame.upscale & UPSCALE_HISTORY) == 0u {
        return vec3(0);
    }
    let then = s.point - object_motion(s.object);
    let p = previous_pixel(then, output_size());
    if p.z != 1 {
        return vec3(0);
    }
    let ps = unpack_surface(prev_gbuffer[output_texel(vec2<u32>(p.xy))]);
    let depth_now = distance(frame.prev_camera.xyz, then);
    let depth_then = distance(frame.prev_camera.xyz, ps.point);
    if !ps.found || ps.face != s.face || ps.object != s.object || abs(depth_now - depth_then) > 0.1 * depth_now {
        return vec3(0);
    }
    return p;
}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    upscale_pixel(id);
    count_rays(COUNT_RAYS_UPSCALE);
}

fn upscale_pixel(id: vec3<u32>) {
    if any(id.xy >= output_size()) {
        return;
    }
    let s = unpack_surface(gbuffer[output_texel(id.xy)]);
    if !s.found {
        // The sky, at the output's own rays: the background with lighting=full, nothing with emitters only.
        let full = lighting_mode() == LIGHTING_FULL;
        var sky = vec3(0.0);
        if full {
            sky = background(primary_ray_dir(id.xy, vec2<f32>(output_size()))) * frame.exposure;
        }
        gbuffer[upscaled_texel(id.xy)] = vec4(0.0);
        present(id.xy, vec4(sky, select(0.0, 1.0, full)));
        return;
    }
    let g = gather(id.xy, s);
    let previous = previous_output_pixel(s);
    // Under the denoiser the render pixels do not move (no jitter) and their light has a history of its own:
    // accumulating it again here would only add lag (a ghost behind a moving block), so the plane's spatial
    // estimate is the pixel's light and last frame's upscaled light is not read.
    var light = g.light;
    var total = 0.0;
    if !(denoising() && g.weight > 0.0) {
        // No neighbourhood clamp: raw frames' light is heavy-tailed (a few bright samples among dark ones), and
        // a clamp to this frame's neighbourhood cut the accumulated mean by 9% (docs/bench/upscale.md). The
        // reprojection's surface test still drops a history that saw another surface.
        var history = vec4(0.0);
        if previous.z == 1 {
            history = prev_gbuffer[upscaled_texel(vec2<u32>(previous.xy))];
        }
        // This frame's samples, each by its weight (TAAU's rule): the render pixel on the plane whose point is
        // nearest, by a Gaussian of its distance (1 on the pixel, 0.14 a pixel away), and the spatial estimate
        // as a weak prior. A still view thus converges to the samples that fell on each pixel itself: shadow
        // edges stay as sharp as the output's pixels, not the render pixels'.
        let near = select(0.0, exp(-2.0 * g.nearest_distance * g.nearest_distance), g.nearest_distance < 1e8);
        let prior = select(0.0, PRIOR_WEIGHT, g.weight > 0.0);
        total = history.a + near + prior;
        light = history.rgb;
        if total > 0.0 {
            light = (history.rgb * history.a + g.nearest * near + g.light * prior) / total;
        }
    }
    gbuffer[upscaled_texel(id.xy)] = vec4(light, min(total, MAX_HISTORY_WEIGHT));
    light += disk_light(id.xy, s, g, previous);
    let albedo = max(albedo_at(s.material, surface_voxel(s), s.object), vec3(ALBEDO_FLOOR));
    let colour = albedo * light + materials[s.material].radiance.rgb * frame.exposure;
    let depth = distance(view.world_position, s.point);
    present(id.xy, vec4(draw_highlight(colour, surface_voxel(s), s.face, s.point, depth), 1.0));
}
