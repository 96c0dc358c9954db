//! Helpers shared by the GPU tests: adapter policy, renderers and the per-pixel hit comparison against the CPU
//! traversal.

use bevy::math::{IVec3, UVec2};
use glowbrick::headless::{HeadlessOptions, HeadlessRenderer};
use glowbrick::image_io::LinearImage;
use glowbrick::world::{CameraView, VoxelWorld, trace};
use glowbrick::world::{camera_ray, view_transform, world_from_clip};

/// With `GLOWBRICK_REQUIRE_GPU=1` (CI) a missing adapter is a failure, otherwise a skip (decided in `main`).
pub fn require_gpu() -> bool {
    std::env::var("GLOWBRICK_REQUIRE_GPU").is_ok_and(|v| v == "1")
}

/// A headless renderer (the harness runs GPU tests only when an adapter exists).
pub fn renderer(world: VoxelWorld, view: &CameraView, options: &HeadlessOptions) -> HeadlessRenderer {
    HeadlessRenderer::new(world, view, options).expect("headless renderer")
}

/// Panics unless `renderer` recorded GPU time for its primary pass, which runs every frame. A test that asserts
/// some pass recorded no time proves nothing on an adapter without timestamp queries, where no pass records any:
/// calling this first makes such an adapter fail the test instead of passing it.
pub fn assert_passes_are_timed(renderer: &HeadlessRenderer) {
    let primary = glowbrick::render::primary::PRIMARY_PASS_NAME;
    assert!(
        renderer.gpu_pass_ms(primary).is_some(),
        "the {primary} pass recorded no GPU time: this adapter has no timestamp queries, so a test that a pass \
         did not run cannot tell"
    );
}

/// Render settings from `--set` pairs (panics on a bad pair: a test's own typo).
pub fn settings(pairs: &[&str]) -> glowbrick::settings::RenderSettings {
    let pairs: Vec<String> = pairs.iter().map(|p| p.to_string()).collect();
    glowbrick::settings::RenderSettings::default().with_pairs(&pairs).unwrap()
}

/// A `w` x `h` headless renderer with `pairs`.
pub fn renderer_with(world: &VoxelWorld, view: &CameraView, w: u32, h: u32, pairs: &[&str]) -> HeadlessRenderer {
    let options = HeadlessOptions { width: w, height: h, settings: settings(pairs), ..Default::default() };
    renderer(world.clone(), view, &options)
}

/// Pixel counts of a GPU `debug=hit` image against the CPU traversal of the same camera rays.
#[derive(Debug)]
pub struct HitComparison {
    pub pixels: usize,
    pub hits: usize,
    pub mismatches: usize,
}

/// Compares per pixel. A mismatch where both hit must be between neighbouring voxels (a ray through an edge or
/// corner, where float rounding decides); anything else fails at once.
pub fn compare_hits(world: &VoxelWorld, view: &CameraView, gpu: &LinearImage) -> HitComparison {
    let (w, h) = (gpu.width, gpu.height);
    let transform = view_transform(view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), w, h);
    let mut c = HitComparison { pixels: (w * h) as usize, hits: 0, mismatches: 0 };
    for y in 0..h {
        for x in 0..w {
            let ray = camera_ray(m, transform.translation, UVec2::new(x, y), w, h);
            let cpu = trace(&world.grid, &ray, f32::INFINITY);
            let p = gpu.pixel(x, y);
            let gpu_hit = (p[3] > 0.0).then(|| (IVec3::new(p[0] as i32, p[1] as i32, p[2] as i32), p[3] as u8 - 1));
            match (cpu, gpu_hit) {
                (None, None) => {}
                (Some(cpu), Some((voxel, face))) => {
                    c.hits += 1;
                    if cpu.voxel != voxel || cpu.face.0 != face {
                        c.mismatches += 1;
                        let apart = (cpu.voxel - voxel).abs().max_element();
                        assert!(apart <= 1, "pixel ({x}, {y}): cpu {cpu:?}, gpu voxel {voxel} face {face}");
                    }
                }
                (cpu, gpu) => {
                    c.mismatches += 1;
                    eprintln!("pixel ({x}, {y}): cpu {cpu:?} gpu {gpu:?} (silhouette)");
                }
            }
        }
    }
    c
}

/// Pixels fit for comparing lighting with the CPU: the GPU's primary hit (a `debug=hit` render) is the CPU's, and
/// the hit voxel does not touch an emitter (where a surface meets a light, area sampling has unbounded variance:
/// neither side converges there and one firefly decides the number).
pub fn comparable_pixels(world: &VoxelWorld, view: &CameraView, w: u32, h: u32) -> Vec<bool> {
    let transform = view_transform(view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), w, h);
    let settings = glowbrick::settings::RenderSettings::default().with_pairs(&["debug=hit".to_string()]).unwrap();
    let options = HeadlessOptions { width: w, height: h, settings, ..Default::default() };
    let hits = renderer(world.clone(), view, &options).render(1).unwrap();
    (0..w * h)
        .map(|i| {
            let ray = camera_ray(m, transform.translation, UVec2::new(i % w, i / w), w, h);
            let p = hits.pixels[i as usize];
            match trace(&world.grid, &ray, f32::INFINITY) {
                Some(hit) => {
                    let same = p[3] > 0.0 && [p[0], p[1], p[2]] == hit.voxel.as_vec3().to_array();
                    same && !touches_emitter(world, hit.voxel)
                }
                None => p[3] == 0.0,
            }
        })
        .collect()
}

/// Whether an emissive voxel lies within one voxel (26-neighbourhood) of `v`, or is `v`.
pub fn touches_emitter(world: &VoxelWorld, v: IVec3) -> bool {
    (-1..=1)
        .any(|z| (-1..=1).any(|y| (-1..=1).any(|x| world.palette.is_emissive(world.grid.get(v + IVec3::new(x, y, z))))))
}

/// The pixels of `image` where `keep` is true, as a one-row image (the bench's own mask).
pub use glowbrick::bench::same_hit::kept as masked;
