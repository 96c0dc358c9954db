// Primary rays: one per pixel through the brick grid; albedo lit by a sun (with a shadow ray) and sky light,
// plus emission, written into the camera's HDR target. Debug views show the pass's inputs.

#import bevy_render::view::View
#import glowbrick::world::materials
#import glowbrick::traversal::{trace, face_normal, INF}
#import glowbrick::lights::{Rng, pcg, direct_sample}

struct FrameParams {
    // xyz: unit direction towards the sun; w: 1 when the sun is on.
    sun: vec4<f32>,
    sun_radiance: vec4<f32>,
    sky_zenith: vec4<f32>,
    sky_horizon: vec4<f32>,
    // Index of settings::DebugView.
    debug_view: u32,
    shadows: u32,
    exposure: f32,
    frame: u32,
    // Targeted voxel (xyz) and face + 1 (w; 0 = none).
    highlight_target: vec4<i32>,
    // Box selection, inclusive corners; selection_min.w is 1 when shown.
    selection_min: vec4<i32>,
    selection_max: vec4<i32>,
    // 0: sun and sky; 1: next-event estimation over the light pool (emitters only, no sky).
    lighting: u32,
    power_pick: u32,
    light_count: u32,
    // Frames averaged including this one; 1 restarts the average.
    accumulated: u32,
}

@group(1) @binding(0) var output: texture_storage_2d<rgba16float, write>;
@group(1) @binding(1) var<uniform> view: View;
@group(1) @binding(2) var<uniform> frame: FrameParams;
// Running sum of accumulated frames per pixel (rgb; a unused).
@group(1) @binding(3) var<storage, read_write> accumulation: array<vec4<f32>>;

const DEBUG_NONE: u32 = 0u;
const DEBUG_ALBEDO: u32 = 1u;
const DEBUG_NORMAL: u32 = 2u;
const DEBUG_HIT: u32 = 3u;
const DEBUG_DEPTH: u32 = 4u;

// The camera ray through the centre of `pixel`; render::camera::camera_ray computes the same on the CPU.
fn primary_ray_dir(pixel: vec2<u32>, size: vec2<f32>) -> vec3<f32> {
    let uv = (vec2<f32>(pixel) + 0.5) / size;
    let ndc = vec2(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    // Reverse-Z infinite projection: depth 1 is the near plane.
    let p = view.world_from_clip * vec4(ndc, 1.0, 1.0);
    return normalize(p.xyz / p.w - view.world_position);
}

fn sky(dir: vec3<f32>) -> vec3<f32> {
    let up = clamp(dir.y * 0.5 + 0.5, 0.0, 1.0);
    return mix(frame.sky_horizon.rgb, frame.sky_zenith.rgb, up);
}

// Outlines the targeted voxel's edges, brightens its targeted face, and tints voxels in the box selection.
fn highlight(colour: vec3<f32>, hit_voxel: vec3<i32>, face: u32, point: vec3<f32>, distance: f32) -> vec3<f32> {
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

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    let size = vec2<u32>(view.viewport.zw);
    if any(id.xy >= size) {
        return;
    }
    let origin = view.world_position;
    let dir = primary_ray_dir(id.xy, vec2<f32>(size));
    let hit = trace(origin, dir, INF);
    let nee = frame.lighting == 1u;
    var colour = vec4(0.0);
    if !hit.found {
        if frame.debug_view == DEBUG_NONE && !nee {
            colour = vec4(sky(dir) * frame.exposure, 1.0);
        }
    } else {
        let normal = face_normal(hit.face);
        let material = materials[hit.material];
        switch frame.debug_view {
            case DEBUG_ALBEDO: {
                colour = vec4(material.albedo.rgb, 1.0);
            }
            case DEBUG_NORMAL: {
                colour = vec4(normal * 0.5 + 0.5, 1.0);
            }
            case DEBUG_HIT: {
                colour = vec4(vec3<f32>(hit.voxel), f32(hit.face + 1u));
            }
            case DEBUG_DEPTH: {
                colour = vec4(vec3(hit.distance), 1.0);
            }
            default: {
                if nee {
                    let point = origin + dir * hit.distance;
                    var rng = Rng(pcg(id.x + size.x * id.y) ^ pcg(frame.frame * 0x9E3779B9u + 1u));
                    let radiance = material.radiance.rgb
                        + direct_sample(point, normal, material.albedo.rgb, frame.light_count, frame.power_pick == 1u, &rng);
                    colour = vec4(highlight(radiance * frame.exposure, hit.voxel, hit.face, point, hit.distance), 1.0);
                    break;
                }
                let sun_dir = frame.sun.xyz;
                var sun = 0.0;
                let cos_sun = dot(normal, sun_dir);
                if frame.sun.w > 0.0 && cos_sun > 0.0 {
                    sun = cos_sun;
                    if frame.shadows != 0u {
                        // Start just off the face so the shadow ray does not hit its own voxel.
                        let p = origin + dir * hit.distance + normal * 1e-3;
                        if trace(p, sun_dir, INF).found {
                            sun = 0.0;
                        }
                    }
                }
                // Sky light seen by the face: the sky colour in the normal's direction, a crude ambient term.
                let lit = frame.sun_radiance.rgb * sun + sky(normal) * 0.3;
                let shaded = (material.albedo.rgb * lit + material.radiance.rgb) * frame.exposure;
                let point = origin + dir * hit.distance;
                colour = vec4(highlight(shaded, hit.voxel, hit.face, point, hit.distance), 1.0);
            }
        }
    }
    // Progressive accumulation: the running mean of the frames since anything changed.
    let index = id.x + size.x * id.y;
    var sum = colour.rgb;
    if frame.accumulated > 1u {
        sum += accumulation[index].rgb;
    }
    accumulation[index] = vec4(sum, 1.0);
    textureStore(output, vec2<i32>(id.xy), vec4(sum / f32(max(frame.accumulated, 1u)), colour.a));
}
