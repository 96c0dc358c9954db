// Primary rays: one per pixel through the brick grid, into the G-buffer. Where Voxel ReSTIR shades
// (lighting=full or emitters) that is all; otherwise this pass shades too: next-event estimation, or the
// sun-only debug look. Debug views show the pass's inputs.

#import glowbrick::world::{materials, Material, albedo_at}
#import glowbrick::frame::{debug_view, frame, view, gbuffer, upscaling, pack_surface, pixel_index, output_texel, highlight, write_output, primary_ray_dir, lit_view,
    pixel_footprint, NOT_A_VOXEL}
#import glowbrick::gi::cache::{gi_on, gi_touch_surface, gi_incoming, camera_level}
#import glowbrick::traversal::{Hit, trace_scene, face_normal, INF, count_rays}
#import glowbrick::lights::{lighting_mode, power_pick_on, shadows_on, scene, sky, background, direct_sample, disk_sample, sky_sample}
#import glowbrick::random::{Rng, pcg}
#import glowbrick::counters::counters
#import glowbrick::constants::{COUNT_RAYS_PRIMARY, COUNT_PRIMARY_HITS, LIGHTING_NEE, LIGHTING_EMITTERS, LIGHTING_FULL, DEBUG_ALBEDO, DEBUG_NORMAL, DEBUG_HIT, DEBUG_DEPTH,
    DEBUG_RESERVOIR, DEBUG_INDIRECT, RAY_OFFSET}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    primary_pixel(id);
    count_rays(COUNT_RAYS_PRIMARY);
    if pixel_hit {
        atomicAdd(&counters[COUNT_PRIMARY_HITS], 1u);
    }
}

// Whether this invocation's primary ray hit a voxel (the bench's rays per hit pixel).
var<private> pixel_hit: bool;

fn primary_pixel(id: vec3<u32>) {
    let size = vec2<u32>(view.viewport.zw);
    if any(id.xy >= size) {
        return;
    }
    let origin = view.world_position;
    let dir = primary_ray_dir(id.xy, vec2<f32>(size));
    let hit = trace_scene(origin, dir, INF);
    pixel_hit = hit.found;
    let point = origin + dir * hit.distance;
    let texel = select(vec4(0.0), vec4(point, pack_surface(hit.face, hit.material, hit.object)), hit.found);
    // Below the output's resolution the lighting passes' G-buffer takes its texels from this one
    // (upscale.wgsl's `pick`).
    if upscaling() {
        gbuffer[output_texel(id.xy)] = texel;
    } else {
        gbuffer[pixel_index(id.xy)] = texel;
    }
    // The GI cache keeps the entries the camera sees (and their interpolation neighbours) alive and updated:
    // those the lighting passes read, so below render scale 1 the render pixels' (upscale.wgsl's `pick`).
    if gi_on() && hit.found && !upscaling() {
        gi_touch_surface(point, hit.face, hit.object, camera_level(pixel_footprint(point), hit.object));
    }
    // Voxel ReSTIR's shading pass shades its lit views (and its reservoir view), with or without lights to
    // sample (restir::shades). Both are the pass key's constants, so that pipeline holds none of the code below.
    let full = lighting_mode() == LIGHTING_FULL;
    let restir = lighting_mode() == LIGHTING_EMITTERS || full;
    if restir && (lit_view() || debug_view() == DEBUG_RESERVOIR) {
        return;
    }
    if debug_view() == DEBUG_RESERVOIR {
        // No ReSTIR pass ran (another mode): every reservoir is empty, W = M = w_sum = 0, none reset.
        // (The shaded colour's alpha of 1 here would read as "reset for a non-finite field" to the soak.)
        write_output(id.xy, vec4(0.0));
        return;
    }
    // (The uniform, not the setting's constant: with `nee` folded to false, Mesa 22.3's lavapipe crashed at this
    // shader's first dispatch; lighting=sun, the debug look, keeps a runtime test.)
    let nee = scene.mode == LIGHTING_NEE || restir;
    var colour = vec4(0.0);
    if !hit.found {
        colour = miss_colour(dir, full, nee);
    } else {
        colour = hit_colour(id.xy, size, point, hit, full, nee);
    }
    write_output(id.xy, colour);
}

// A ray that left the world: the sky (or, without emitters under lighting=full, the sky and the disk).
fn miss_colour(dir: vec3<f32>, full: bool, nee: bool) -> vec4<f32> {
    if debug_view() == DEBUG_INDIRECT {
        return vec4(0.0, 0.0, 0.0, 1.0);
    }
    if lit_view() && full {
        return vec4(background(dir) * frame.exposure, 1.0);
    } else if lit_view() && !nee {
        return vec4(sky(dir) * frame.exposure, 1.0);
    }
    return vec4(0.0);
}

// A hit: a debug view of it, or its light (NEE or the sun-only look) with the highlight drawn over.
fn hit_colour(pixel: vec2<u32>, size: vec2<u32>, point: vec3<f32>, hit: Hit, full: bool, nee: bool) -> vec4<f32> {
    let normal = face_normal(hit.face);
    // The material with this voxel's own albedo (per-voxel variation), for every use below.
    var material = materials[hit.material];
    material.albedo = vec4(albedo_at(hit.material, hit.voxel, hit.object), 0.0);
    switch debug_view() {
        case DEBUG_ALBEDO: {
            return vec4(material.albedo.rgb, 1.0);
        }
        case DEBUG_NORMAL: {
            return vec4(normal * 0.5 + 0.5, 1.0);
        }
        case DEBUG_HIT: {
            return vec4(vec3<f32>(hit.voxel), f32(hit.face + 1u));
        }
        case DEBUG_DEPTH: {
            return vec4(vec3(hit.distance), 1.0);
        }
        case DEBUG_INDIRECT: {
            var cached = vec3(0.0);
            if gi_on() {
                cached = material.albedo.rgb * gi_incoming(point, hit.face, hit.object, camera_level(pixel_footprint(point), hit.object));
            }
            return vec4(cached * frame.exposure, 1.0);
        }
        default: {}
    }
    var shaded: vec3<f32>;
    if nee {
        var rng = Rng(pcg(pixel.x + size.x * pixel.y) ^ pcg(frame.frame * 0x9E3779B9u + 1u));
        shaded = nee_radiance(point, hit, normal, material, full, &rng) * frame.exposure;
    } else {
        shaded = sun_look(point, hit, normal, material);
    }
    // Moving objects' voxels are in their own coordinates: never outlined or selected.
    let world_voxel = select(hit.voxel, vec3(NOT_A_VOXEL), hit.object != 0u);
    return vec4(highlight(shaded, world_voxel, hit.face, point, hit.distance), 1.0);
}

// Emission plus one next-event-estimation sample of the light pool (and under lighting=full, with no emitters
// to sample, the disk and the sky), plus the GI cache's indirect light when it is on.
fn nee_radiance(point: vec3<f32>, hit: Hit, normal: vec3<f32>, material: Material, full: bool, rng: ptr<function, Rng>) -> vec3<f32> {
    var radiance = material.radiance.rgb
        + direct_sample(point, normal, material.albedo.rgb, scene.light_count, power_pick_on(), rng);
    if full {
        radiance += disk_sample(point, normal, material.albedo.rgb, rng);
        if !gi_on() {
            radiance += sky_sample(point, normal, material.albedo.rgb, rng);
        }
    }
    if gi_on() {
        radiance += material.albedo.rgb * gi_incoming(point, hit.face, hit.object, camera_level(pixel_footprint(point), hit.object));
    }
    return radiance;
}

// The sun-only debug look: a sun without a disk, shadowed, and a crude sky ambient (or the GI cache's light).
fn sun_look(point: vec3<f32>, hit: Hit, normal: vec3<f32>, material: Material) -> vec3<f32> {
    let sun_dir = scene.sun.xyz;
    var sun = 0.0;
    let cos_sun = dot(normal, sun_dir);
    if scene.sun.w > 0.0 && cos_sun > 0.0 {
        sun = cos_sun;
        if shadows_on() {
            // Start just off the face so the shadow ray does not hit its own voxel.
            if trace_scene(point + normal * RAY_OFFSET, sun_dir, INF).found {
                sun = 0.0;
            }
        }
    }
    // Indirect light: the GI cache's (which sees the sky through its rays), else the sky colour in the normal's
    // direction.
    var ambient = sky(normal) * 0.3;
    if gi_on() {
        ambient = gi_incoming(point, hit.face, hit.object, camera_level(pixel_footprint(point), hit.object));
    }
    let lit = scene.sun_radiance.rgb * sun + ambient;
    return (material.albedo.rgb * lit + material.radiance.rgb) * frame.exposure;
}
