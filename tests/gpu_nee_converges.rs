//! The GPU next-event-estimation baseline, averaged over many frames, converges to the CPU direct-light
//! reference: GPU and CPU agree on geometry, materials, lights and units.
//!
//! Compared pixels: those whose camera ray hits the same voxel on GPU and CPU (float rounding at voxel edges may
//! differ) and whose hit voxel does not touch an emitter. Where a surface meets a light at an edge, area-light
//! sampling has infinite variance (cos * cos / d^2 near d = 0): neither side converges there in any number of
//! samples, and one firefly decides the number. The scene's other pixels are the fair comparison.
//!
//! Stated bounds, per scene at 96x64, over the compared pixels: after 256 accumulated frames the GPU's mean
//! luminance is within 1% of a 4096-spp reference's, its MSE is within a factor 1.6 of the MSE of a 256-spp CPU
//! image (same estimator, same sample count: only noise may differ, no systematic error), and its relMSE is
//! below 0.05.

mod common;

use bevy::math::UVec2;
use glowbrick::headless::HeadlessOptions;
use glowbrick::image_io::LinearImage;
use glowbrick::reference::metrics::compare;
use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::render::camera::{camera_ray, view_transform, world_from_clip};
use glowbrick::settings::RenderSettings;
use glowbrick::world::scene::load_scene;
use glowbrick::world::{CameraView, VoxelWorld, trace};

const W: u32 = 96;
const H: u32 = 64;

fn cpu(world: &VoxelWorld, view: &CameraView, spp: u32, seed: u64) -> LinearImage {
    render_reference(world, view, &ReferenceOptions { width: W, height: H, spp, bounces: 0, seed, time_budget: None })
        .unwrap()
        .image
}

/// Keeps only pixels whose primary hit the GPU agrees on (those where the `debug=hit` image equals the CPU).
fn masked(image: &LinearImage, keep: &[bool]) -> LinearImage {
    let pixels = image.pixels.iter().zip(keep).filter(|(_, k)| **k).map(|(p, _)| *p).collect::<Vec<_>>();
    LinearImage { width: pixels.len() as u32, height: 1, pixels }
}

fn check_scene(name: &str, view_name: &str) {
    let world = load_scene(name).unwrap();
    let view = world.view(Some(view_name)).unwrap().clone();
    let pairs = ["lighting=nee", "accumulate=on"].map(String::from);
    let settings = RenderSettings::default().with_pairs(&pairs).unwrap();
    let options = HeadlessOptions { width: W, height: H, settings, ..Default::default() };
    let Some(mut renderer) = common::renderer(world.clone(), &view, &options) else { return };
    let gpu = renderer.render(256).unwrap();
    let truth = cpu(&world, &view, 4096, 77);
    let cpu_256 = cpu(&world, &view, 256, 78);

    let transform = view_transform(&view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), W, H);
    let hit_settings = RenderSettings::default().with_pairs(&["debug=hit".to_string()]).unwrap();
    let hit_options = HeadlessOptions { width: W, height: H, settings: hit_settings, ..Default::default() };
    let Some(mut hit_renderer) = common::renderer(world.clone(), &view, &hit_options) else { return };
    let hits = hit_renderer.render(1).unwrap();
    let keep: Vec<bool> = (0..W * H)
        .map(|i| {
            let ray = camera_ray(m, transform.translation, UVec2::new(i % W, i / W), W, H);
            let p = hits.pixels[i as usize];
            match trace(&world.grid, &ray, f32::INFINITY) {
                Some(h) => {
                    let same = p[3] > 0.0 && [p[0], p[1], p[2]] == h.voxel.as_vec3().to_array();
                    same && !touches_emitter(&world, h.voxel)
                }
                None => p[3] == 0.0,
            }
        })
        .collect();
    let dropped = keep.iter().filter(|k| !**k).count();
    // The cornell box sees its 128 x 128 light head on: those pixels are emitters and are left out.
    assert!(dropped * 5 <= keep.len(), "{name}: {dropped} of {} pixels left out", keep.len());
    let (gpu, truth, cpu_256) = (masked(&gpu, &keep), masked(&truth, &keep), masked(&cpu_256, &keep));
    let g = compare(&gpu, &truth).unwrap();
    let c = compare(&cpu_256, &truth).unwrap();
    let mean =
        compare(&truth, &LinearImage { pixels: vec![[0.0; 4]; truth.pixels.len()], ..truth.clone() }).unwrap().bias;
    eprintln!("{name}: {dropped} pixels left out\n{name}: gpu {g}\n{name}: cpu {c}\n{name}: mean luminance {mean:.4}");
    assert!(g.bias.abs() < 0.01 * mean, "{name}: GPU bias {} against mean {mean}", g.bias);
    let ratio = g.mse / c.mse;
    assert!((1.0 / 1.6..1.6).contains(&ratio), "{name}: GPU MSE {} vs CPU MSE {} at equal samples", g.mse, c.mse);
    assert!(g.relmse < 0.05, "{name}: relMSE {}", g.relmse);
}

/// Whether an emissive voxel lies within one voxel (26-neighbourhood) of `v`, or is `v`.
fn touches_emitter(world: &VoxelWorld, v: bevy::math::IVec3) -> bool {
    (-1..=1).any(|z| {
        (-1..=1)
            .any(|y| (-1..=1).any(|x| world.palette.is_emissive(world.grid.get(v + bevy::math::IVec3::new(x, y, z)))))
    })
}

#[test]
fn gpu_nee_converges_to_the_cpu_reference_on_the_cornell_box() {
    check_scene("cornell", "front");
}

#[test]
fn gpu_nee_converges_to_the_cpu_reference_on_the_letters() {
    check_scene("letters", "front");
}
