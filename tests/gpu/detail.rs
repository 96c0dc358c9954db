//! Per-voxel detail (`Material::variation`): the GPU gives every world voxel the CPU's albedo, bit for bit through
//! the same hash, and the lit frame of a room whose every surface varies still converges to the CPU reference.
//!
//! Stated bounds: test-room with variation 0.5 on every non-emissive material (twice the generator's strongest),
//! view `inside`, 96x64. The albedo view: every comparable pixel within the half-float image's rounding (0.1%) of `albedo_at` of the CPU's hit voxel,
//! and at least 20 distinct albedos on the floor (a broken hash gives one). Lighting=full at noon, gi=off, 256
//! accumulated frames (direct light: sun, sky and the room's lamp) against a 1024-spp reference: |bias| < 1% of the
//! mean luminance (the direct-light bound the flat scenes keep; measured +0.00%) and relMSE < 0.05 (the flat
//! room's bound in `daylight`); the reference's own noise (256 spp) printed beside it.

use crate::common;

use bevy::math::{IVec3, UVec2};
use glowbrick::lights::daylight::Daylight;
use glowbrick::reference::metrics::compare;
use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::world::recipe::load_scene;
use glowbrick::world::{VoxelWorld, camera_ray, trace, view_transform, world_from_clip};

const W: u32 = 96;
const H: u32 = 64;

fn varied_room() -> VoxelWorld {
    let mut world = load_scene("test-room").unwrap();
    for m in world.palette.materials.iter_mut().filter(|m| !m.is_emissive()) {
        m.variation = 0.5;
    }
    world
}

pub fn every_voxel_has_the_cpus_albedo_and_the_lit_frame_converges() {
    let world = varied_room();
    let view = world.view(Some("inside")).unwrap().clone();
    let keep = common::comparable_pixels(&world, &view, W, H);

    let transform = view_transform(&view);
    let clip = world_from_clip(&transform, view.fov_deg.to_radians(), W, H);
    // The room as it is, and as a window of the endless world a million voxels out would hold it: the detail
    // is hashed at world coordinates, so the second shades each voxel as the voxel a million voxels out.
    for origin in [IVec3::ZERO, IVec3::new(1_000_000, 0, -777)] {
        let moved = VoxelWorld { detail_origin: origin, ..world.clone() };
        let albedo = common::renderer_with(&moved, &view, W, H, &["debug=albedo", "denoise=off"]).render(1).unwrap();
        let (mut checked, mut distinct, mut moved_shade) = (0, std::collections::BTreeSet::new(), 0);
        for i in (0..W * H).filter(|&i| keep[i as usize]) {
            let ray = camera_ray(clip, transform.translation, UVec2::new(i % W, i / W), W, H);
            let Some(hit) = trace(&world.grid, &ray, f32::INFINITY) else { continue };
            let material = world.palette.get(hit.material).unwrap();
            let expected = moved.voxel_albedo(material, hit.voxel);
            let got = albedo.pixels[i as usize];
            for c in 0..3 {
                // The image is half floats: 11 bits of mantissa.
                assert!(
                    (got[c] - expected[c]).abs() <= 1e-3 * expected[c] + 1e-5,
                    "origin {origin}, pixel {i} voxel {}: GPU {got:?}, CPU {expected:?}",
                    hit.voxel
                );
            }
            checked += 1;
            distinct.insert(expected.map(f32::to_bits));
            moved_shade += usize::from(expected != material.albedo_at(hit.voxel));
        }
        eprintln!(
            "albedo view, detail origin {origin}: {checked} pixels equal the CPU's, {} distinct albedos, {moved_shade} \
             shaded other than at the origin",
            distinct.len()
        );
        assert!(checked * 2 > (W * H) as usize, "only {checked} comparable pixels");
        assert!(distinct.len() >= 20, "{} distinct albedos: the variation is missing", distinct.len());
        if origin != IVec3::ZERO {
            assert!(moved_shade * 2 > checked, "only {moved_shade} of {checked} pixels moved with the origin");
        }
    }

    let reference = |spp: u32, seed: u64| {
        let daylight = Some(Daylight::at(12.0, true));
        let options = ReferenceOptions { width: W, height: H, spp, seed, daylight, ..Default::default() };
        common::masked(&render_reference(&world, &view, &options).unwrap().image, &keep)
    };
    let truth = reference(1024, 5);
    let noise = compare(&reference(256, 6), &truth).unwrap();
    let mean = truth.mean_luminance();
    let mut renderer = common::renderer_with(&world, &view, W, H, &["accumulate=on", "radius=8", "time=12", "gi=off"]);
    let image = common::masked(&renderer.render(256).unwrap(), &keep);
    let m = compare(&image, &truth).unwrap();
    eprintln!(
        "varied test-room at noon: {m} (bias {:+.2}% of the mean {mean:.4}); a 256-spp reference: mae {:.5}, relMSE {:.5}",
        100.0 * m.bias / mean,
        noise.mae,
        noise.relmse
    );
    assert!(m.bias.abs() < 0.01 * mean, "bias {} of mean {mean}", m.bias);
    assert!(m.relmse < 0.05, "relMSE {}", m.relmse);
}
