//! Helpers shared by the GPU tests: adapter policy and the per-pixel hit comparison against the CPU traversal.
#![allow(dead_code)]

use bevy::math::{IVec3, UVec2};
use glowbrick::headless::{HeadlessOptions, HeadlessRenderer};
use glowbrick::image_io::LinearImage;
use glowbrick::render::camera::{camera_ray, view_transform, world_from_clip};
use glowbrick::world::{CameraView, VoxelWorld, trace};

/// With `GLOWBRICK_REQUIRE_GPU=1` (CI) a missing adapter is a failure, otherwise a skip.
pub fn require_gpu() -> bool {
    std::env::var("GLOWBRICK_REQUIRE_GPU").is_ok_and(|v| v == "1")
}

/// A headless renderer, or `None` (with a message) when no adapter exists and the GPU is not required.
pub fn renderer(world: VoxelWorld, view: &CameraView, options: &HeadlessOptions) -> Option<HeadlessRenderer> {
    match std::panic::catch_unwind(|| HeadlessRenderer::new(world, view, options)) {
        Ok(result) => Some(result.expect("headless renderer")),
        Err(_) if !require_gpu() => {
            eprintln!("skipping GPU test: no adapter (set GLOWBRICK_REQUIRE_GPU=1 to make this a failure)");
            None
        }
        Err(panic) => std::panic::resume_unwind(panic),
    }
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
