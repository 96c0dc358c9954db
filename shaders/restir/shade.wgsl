// Voxel ReSTIR pass 3: shading. Emission plus the reservoir's sample: f(y) V(y) W, with a final shadow ray; with
// lighting=full also one sample of the sun's (or moon's) disk and, where no GI cache brings the sky, one of the sky.
// An occluded sample gets W = 0 and keeps its M (visibility reuse): next frame's temporal reuse does not pick it
// again, and its M still says how many candidates found this pixel's light occluded. (Emptying it instead, M = 0,
// forgets that evidence and measurably brightens penumbrae.)

#import glowbrick::traversal::{count_rays}
#import glowbrick::constants::COUNT_RAYS_RESTIR_SHADE
#import glowbrick::world::materials
#import glowbrick::frame::{debug_view, frame, view, output, gbuffer, unpack_surface, surface_voxel, pixel_index, render_size, highlight, write_output,
    primary_ray_dir, pixel_footprint, upscaling}
#import glowbrick::constants::{DEBUG_RESERVOIR, DEBUG_INDIRECT, LIGHTING_FULL}
#import glowbrick::guards::finite
#import glowbrick::restir::common::{reservoirs_final, validated, shading, unshadowed, reservoir_visible, pixel_rng, NO_LIGHT,
    empty_reservoir}
#import glowbrick::lights::{lighting_mode, lights, scene, background, disk_sample, sky_sample, disk_direction, disk_faces,
    disk_visible}
#import glowbrick::gi::cache::{gi_on, gi_incoming, camera_level}

@compute @workgroup_size(8, 8, 1)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    shade_pixel(id);
    count_rays(COUNT_RAYS_RESTIR_SHADE);
}

fn shade_pixel(id: vec3<u32>) {
    let size = render_size();
    if any(id.xy >= size) {
        return;
    }
    let index = pixel_index(id.xy);
    let surface = unpack_surface(gbuffer[index]);
    let full = lighting_mode() == LIGHTING_FULL;
    if !surface.found {
        // A miss sees the sky and the disk with lighting=full, nothing with emitters only (the thesis' protocol).
        // The reservoir view shows a miss as an empty reservoir: an alpha of 1 there reads as "reset for a
        // non-finite field".
        if debug_view() == DEBUG_RESERVOIR {
            write_output(id.xy, vec4(0.0));
            return;
        }
        var sky_seen = vec3(0.0);
        // The sky seen straight on is not the cache's light.
        if full && debug_view() != DEBUG_INDIRECT {
            sky_seen = background(primary_ray_dir(id.xy, vec2<f32>(size))) * frame.exposure;
        }
        write_output(id.xy, vec4(sky_seen, select(0.0, 1.0, full)));
        return;
    }
    let x = shading(surface);
    // Without lights to sample the other passes do not run (restir::samples): emission, the disk, the sky and
    // the GI cache only.
    var raw = empty_reservoir();
    if scene.light_count > 0u {
        raw = reservoirs_final[index];
    }
    var r = validated(raw);
    if debug_view() == DEBUG_RESERVOIR {
        // The stress run's view of the reservoir: raw W, M, w_sum, and whether validation had to reset it for a
        // non-finite field (counted, never shaded).
        let bad = !(finite(raw.w_sum) && finite(raw.m) && finite(raw.big_w) && finite(raw.target_value));
        textureStore(output, vec2<i32>(id.xy), vec4(r.big_w, r.m, r.w_sum, select(0.0, 1.0, bad)));
        return;
    }
    var radiance = materials[surface.material].radiance.rgb;
    if r.slot != NO_LIGHT && r.big_w > 0.0 {
        if reservoir_visible(x, r) {
            radiance += unshadowed(x, lights[r.slot], r.face, unpack2x16unorm(r.uv)) * r.big_w;
        } else {
            r.big_w = 0.0;
            r.w_sum = 0.0;
        }
    }
    if scene.light_count > 0u {
        reservoirs_final[index] = r;
    }
    // Below render scale 1 the disk's light is the upscaler's, at the output's pixels (a sun's shadow edge is as
    // sharp as they are): this pass leaves it out and hands on this sample's visibility in the alpha (-1 where
    // the disk is down or behind the surface).
    var disk_seen = -1.0;
    if full {
        var rng = pixel_rng(id.xy, 3u);
        if upscaling() {
            let dir = disk_direction(&rng);
            if disk_faces(x.normal) {
                disk_seen = disk_visible(x.point, x.normal, dir);
            }
        } else {
            radiance += disk_sample(x.point, x.normal, x.albedo, &rng);
        }
        if !gi_on() {
            radiance += sky_sample(x.point, x.normal, x.albedo, &rng);
        }
    }
    var cached = vec3(0.0);
    if gi_on() {
        cached = x.albedo * gi_incoming(x.point, surface.face, surface.object, camera_level(pixel_footprint(x.point), surface.object));
    }
    radiance += cached;
    if debug_view() == DEBUG_INDIRECT {
        // The cache's share alone; no disk for the upscaler to add (-1).
        write_output(id.xy, vec4(cached * frame.exposure, select(1.0, -1.0, upscaling())));
        return;
    }
    let depth = distance(view.world_position, x.point);
    let alpha = select(1.0, disk_seen, upscaling());
    write_output(id.xy, vec4(highlight(radiance * frame.exposure, surface_voxel(surface), surface.face, x.point, depth), alpha));
}
