// What every per-view pass shares: the frame parameters, the view's buffers (group 1), the G-buffer encoding,
// reprojection, the selection highlight and the final write with progressive accumulation (through the
// denoiser when it is on).
#define_import_path glowbrick::frame

#import bevy_render::view::View
#import glowbrick::traversal::face_normal
#import glowbrick::guards::finite3
#import glowbrick::constants::{KEY_GENERIC, KEY_DEBUG_VIEW, KEY_RESTIR_FLAGS, GBUFFER_FACE_SHIFT, GBUFFER_MATERIAL_SHIFT, GBUFFER_MATERIAL_MASK, GBUFFER_OBJECT_SHIFT,
    DENOISE_ON, UPSCALE_ON, DEBUG_NONE, DEBUG_VARIANCE, DEBUG_HISTORY, DEBUG_INDIRECT}

// FrameParams in src/render/gpu_types.rs: one view's parameters this frame (the scene's lighting, the same for
// every view, is SceneLighting in glowbrick::lights).
struct FrameParams {
    // Last frame's clip_from_world, for temporal reprojection.
    prev_clip_from_world: mat4x4<f32>,
    // Last frame's camera position (xyz); w is 1 when last frame's G-buffer and reservoirs may be reused.
    prev_camera: vec4<f32>,
    // DEBUG_*.
    debug_view: u32,
    exposure: f32,
    frame: u32,
    // Frames averaged including this one; 1 restarts the average.
    accumulated: u32,
    // Targeted voxel (xyz) and face + 1 (w; 0 = none).
    highlight_target: vec4<i32>,
    // Box selection, inclusive corners; selection_min.w is 1 when shown.
    selection_min: vec4<i32>,
    selection_max: vec4<i32>,
    // ReSTIR: candidates per pixel, spatial taps, spatial radius in pixels, RESTIR_* flags.
    candidates: u32,
    taps: u32,
    radius: f32,
    restir_flags: u32,
    // DENOISE_* flags.
    denoise: u32,
    // UPSCALE_* flags.
    upscale: u32,
    // The lighting passes' pixels (the output's at render scale 1).
    render_size: vec2<u32>,
    // Where in its footprint each render pixel takes its output pixel this frame, [0, 1) per axis.
    jitter: vec2<f32>,
    // Padding to 16 bytes (FrameParams::_pad).
    _pad_a: u32,
    _pad_b: u32,
}

@group(1) @binding(0) var output: texture_storage_2d<rgba16float, write>;
@group(1) @binding(1) var<uniform> view: View;
@group(1) @binding(2) var<uniform> frame: FrameParams;
// Running sum of accumulated frames per pixel (rgb; a unused).
@group(1) @binding(3) var<storage, read_write> accumulation: array<vec4<f32>>;
// Per pixel: hit point (xyz) and the packed hit (w, see pack_surface); this frame's and last frame's. Each holds
// GBUFFER_REGIONS regions of the output's pixels: the lighting passes' G-buffer (at their render size), then below
// render scale 1 the output's own G-buffer and the upscaler's two histories (render::upscale; in these buffers because
// a stage may bind no more storage buffers than lavapipe's 32, and they swap every frame as the G-buffer does).
@group(1) @binding(4) var<storage, read_write> gbuffer: array<vec4<f32>>;
@group(1) @binding(5) var<storage, read_write> prev_gbuffer: array<vec4<f32>>;
// Voxel ReSTIR's part follows (restir/common.wgsl), then the denoiser's (render::denoise): the shading passes'
// noisy frame; per pixel two texels of history (demodulated colour and length, luminance moments), this frame's
// and last frame's; the wavelet's two halves (colour and variance). The numbers follow src/render/view.rs's
// parts in order (tests/cpu/shaders_validate.rs checks them).
@group(1) @binding(9) var<storage, read_write> noisy: array<vec4<f32>>;
@group(1) @binding(10) var<storage, read_write> history: array<vec4<f32>>;
@group(1) @binding(11) var<storage, read_write> prev_history: array<vec4<f32>>;
@group(1) @binding(12) var<storage, read_write> wavelet: array<vec4<f32>>;

fn luminance(c: vec3<f32>) -> f32 {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// Whether the view shows the lit image (or the denoiser's view of it), as DebugView::is_lit.
fn lit_view() -> bool {
    let shown = debug_view();
    return shown == DEBUG_NONE || shown == DEBUG_VARIANCE || shown == DEBUG_HISTORY || shown == DEBUG_INDIRECT;
}

// The view's settings: the pipeline's own (constants.wgsl, KEY_*) or the uniform's in a generic build.
fn debug_view() -> u32 {
    if KEY_DEBUG_VIEW == KEY_GENERIC {
        return frame.debug_view;
    }
    return KEY_DEBUG_VIEW;
}

// Whether any of the ReSTIR setting bits `bits` (RESTIR_*) is on.
fn restir_flag(bits: u32) -> bool {
    if KEY_RESTIR_FLAGS == KEY_GENERIC {
        return (frame.restir_flags & bits) != 0u;
    }
    return (KEY_RESTIR_FLAGS & bits) != 0u;
}

fn denoising() -> bool {
    return (frame.denoise & DENOISE_ON) != 0u;
}

// Whether the lighting passes run below the output's resolution and the upscaler writes the image.
fn upscaling() -> bool {
    return (frame.upscale & UPSCALE_ON) != 0u;
}

// The lighting passes' pixels: the output's at render scale 1.
fn render_size() -> vec2<u32> {
    return frame.render_size;
}

// The output's pixels (the primary pass, the upscaler and the image).
fn output_size() -> vec2<u32> {
    return vec2<u32>(view.viewport.zw);
}

// The G-buffer's w: bit 0 hit, then the face (3 bits), the material and the moving object's id (0: the static
// world), at the GBUFFER_* shifts. Zero (a cleared buffer) reads as a miss.
fn pack_surface(face: u32, material: u32, object: u32) -> f32 {
    return bitcast<f32>(1u | (face << GBUFFER_FACE_SHIFT) | ((material & GBUFFER_MATERIAL_MASK) << GBUFFER_MATERIAL_SHIFT)
        | (object << GBUFFER_OBJECT_SHIFT));
}

struct Surface {
    found: bool,
    point: vec3<f32>,
    face: u32,
    material: u32,
    object: u32,
}

fn unpack_surface(texel: vec4<f32>) -> Surface {
    let bits = bitcast<u32>(texel.w);
    return Surface((bits & 1u) == 1u, texel.xyz, (bits >> GBUFFER_FACE_SHIFT) & 7u,
        (bits >> GBUFFER_MATERIAL_SHIFT) & GBUFFER_MATERIAL_MASK, bits >> GBUFFER_OBJECT_SHIFT);
}

// The camera ray through the centre of `pixel`; world::camera::camera_ray computes the same on the CPU.
fn primary_ray_dir(pixel: vec2<u32>, size: vec2<f32>) -> vec3<f32> {
    let uv = (vec2<f32>(pixel) + 0.5) / size;
    let ndc = vec2(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    // Reverse-Z infinite projection: depth 0 is the point at infinity, whose homogeneous w is 0, so the product
    // is the direction itself. (Not the near-plane point minus the camera's position: far from the origin, as in
    // the thesis' scenes, that difference cancels digits and the GPU's rays drift from the CPU's;
    // docs/bench/why.md.)
    return normalize((view.world_from_clip * vec4(ndc, 0.0, 1.0)).xyz);
}

// Voxels across one pixel at `point` (at the view's centre; the GI cache picks its level of detail from it).
fn pixel_footprint(point: vec3<f32>) -> f32 {
    // clip_from_view[1][1] is 1 / tan(half the vertical field of view).
    return distance(point, view.world_position) * 2.0 / (view.clip_from_view[1][1] * f32(frame.render_size.y));
}

// A render pixel's index in the lighting passes' buffers.
fn pixel_index(pixel: vec2<u32>) -> u32 {
    return pixel.x + frame.render_size.x * pixel.y;
}

// An output pixel's index in the output's buffers (the image's accumulation, the upscaler's).
fn output_index(pixel: vec2<u32>) -> u32 {
    return pixel.x + u32(view.viewport.z) * pixel.y;
}

// Where an output pixel's G-buffer texel lies in `gbuffer` and `prev_gbuffer` below render scale 1.
fn output_texel(pixel: vec2<u32>) -> u32 {
    return u32(view.viewport.z) * u32(view.viewport.w) + output_index(pixel);
}

// Where an output pixel's upscaled history (demodulated light, length) lies in `gbuffer` and `prev_gbuffer`.
fn upscaled_texel(pixel: vec2<u32>) -> u32 {
    return 2u * u32(view.viewport.z) * u32(view.viewport.w) + output_index(pixel);
}

// Where an output pixel's history of the disk's visibility (mean, samples) lies in `gbuffer` and `prev_gbuffer`.
fn disk_texel(pixel: vec2<u32>) -> u32 {
    return 3u * u32(view.viewport.z) * u32(view.viewport.w) + output_index(pixel);
}

// The output pixel whose G-buffer texel render pixel `pixel` lights this frame: a point of its footprint that
// moves with the jitter, so that over frames every output pixel is lit by a render pixel of its own.
fn render_pixel_source(pixel: vec2<u32>) -> vec2<u32> {
    let output = output_size();
    let at = (vec2<f32>(pixel) + frame.jitter) * vec2<f32>(output) / vec2<f32>(frame.render_size);
    return min(vec2<u32>(floor(at)), output - 1u);
}

// Where `point` was seen last frame: its position in last frame's image as a fraction of it (xy), z = -1 when it
// was behind the camera.
fn previous_uv(point: vec3<f32>) -> vec3<f32> {
    let clip = frame.prev_clip_from_world * vec4(point, 1.0);
    if clip.w <= 0.0 {
        return vec3(-1.0);
    }
    let ndc = clip.xy / clip.w;
    return vec3(ndc.x * 0.5 + 0.5, 0.5 - ndc.y * 0.5, 1.0);
}

// Last frame's pixel that saw `point` (xy, z = 1), or z = -1 when it was off screen.
fn previous_pixel(point: vec3<f32>, size: vec2<u32>) -> vec3<i32> {
    let uv = previous_uv(point);
    if uv.z < 0.0 {
        return vec3(-1);
    }
    let pixel = vec2<i32>(floor(uv.xy * vec2<f32>(size)));
    if any(pixel < vec2(0)) || any(pixel >= vec2<i32>(size)) {
        return vec3(-1);
    }
    return vec3(pixel, 1);
}

// Below render scale 1: last frame's render pixel whose sample (the output pixel it took, `render_pixel_source`)
// lay nearest to where `point` was seen (xy, z = 1), or z = -1 off screen. `previous_pixel` at the render size
// takes the render pixel whose footprint holds the point, but a render pixel samples one output pixel of its
// footprint, not its centre: once the view moves by more than about half a render pixel a frame (a turning
// player), the nearest sample often lies in the next footprint, and a history read from further away blurs.
// Assumes last frame's samples sat where this frame's do (the denoiser's fixed footprint centre).
fn previous_render_pixel(point: vec3<f32>) -> vec3<i32> {
    let uv = previous_uv(point);
    let output = vec2<f32>(output_size());
    let at = uv.xy * output;
    if uv.z < 0.0 || any(at < vec2(0.0)) || any(at >= output) {
        return vec3(-1);
    }
    let size = vec2<i32>(frame.render_size);
    let per_render = output / vec2<f32>(frame.render_size);
    let base = vec2<i32>(floor(at / per_render));
    var best = base;
    var best_distance = vec2(1e9);
    // Per axis, the footprint holding the point and its two neighbours: the nearest sample is among them.
    for (var d = -1; d <= 1; d++) {
        let r = clamp(base + vec2(d), vec2(0), size - 1);
        let taken = floor((vec2<f32>(r) + frame.jitter) * per_render) + 0.5;
        let apart = abs(taken - at);
        if apart.x < best_distance.x {
            best_distance.x = apart.x;
            best.x = r.x;
        }
        if apart.y < best_distance.y {
            best_distance.y = apart.y;
            best.y = r.y;
        }
    }
    return vec3(best, 1);
}

// The highlight, where the shading passes write the image; the denoiser draws it after filtering instead (an
// outline filtered along with the light would smear across its face).
fn highlight(colour: vec3<f32>, hit_voxel: vec3<i32>, face: u32, point: vec3<f32>, distance: f32) -> vec3<f32> {
    if denoising() || upscaling() {
        return colour;
    }
    return draw_highlight(colour, hit_voxel, face, point, distance);
}

// Outlines the targeted voxel's edges, brightens its targeted face, and tints voxels in the box selection.
fn draw_highlight(colour: vec3<f32>, hit_voxel: vec3<i32>, face: u32, point: vec3<f32>, distance: f32) -> vec3<f32> {
    var c = colour;
    if frame.selection_min.w == 1 && all(hit_voxel >= frame.selection_min.xyz) && all(hit_voxel <= frame.selection_max.xyz) {
        c = mix(c, vec3(0.25, 0.6, 1.0), 0.35);
    }
    if frame.highlight_target.w == 0 || any(hit_voxel != frame.highlight_target.xyz) {
        return c;
    }
    // Position on the hit face in [0, 1]^2: the two axes other than the face's.
    let local = point - vec3<f32>(hit_voxel);
    let axis = face / 2u;
    let uv = vec2(local[(axis + 1u) % 3u], local[(axis + 2u) % 3u]);
    let edge = min(min(uv.x, 1.0 - uv.x), min(uv.y, 1.0 - uv.y));
    // About two pixels wide at typical fields of view, whatever the distance.
    let width = clamp(0.003 * distance, 0.006, 0.2);
    if edge < width {
        return vec3(0.02);
    }
    if u32(frame.highlight_target.w) == face + 1u {
        c = c * 1.2 + vec3(0.04);
    }
    return c;
}

// A voxel coordinate no highlight or selection contains.
const NOT_A_VOXEL: i32 = -1073741824;

// The world voxel a surface point lies on: step back from the face it was entered through. NOT_A_VOXEL on a
// moving object (its voxels are not world voxels).
fn surface_voxel(s: Surface) -> vec3<i32> {
    if s.object != 0u {
        return vec3(NOT_A_VOXEL);
    }
    return vec3<i32>(floor(s.point - face_normal(s.face) * 0.5));
}

// A shading pass's result: the image, or the noisy input of the denoiser (render::denoise) or the upscaler.
fn write_output(pixel: vec2<u32>, colour: vec4<f32>) {
    if denoising() || upscaling() {
        noisy[pixel_index(pixel)] = colour;
        return;
    }
    present(pixel, colour);
}

// Progressive accumulation (the running mean of the frames since anything changed), then the HDR target.
fn present(pixel: vec2<u32>, colour: vec4<f32>) {
    let index = output_index(pixel);
    // A non-finite value would poison the running sum until the next restart: write black instead.
    let c = select(vec3(0.0), colour.rgb, finite3(colour.rgb));
    var sum = c;
    if frame.accumulated > 1u {
        sum += accumulation[index].rgb;
    }
    accumulation[index] = vec4(sum, 1.0);
    textureStore(output, vec2<i32>(pixel), vec4(sum / f32(max(frame.accumulated, 1u)), colour.a));
}
