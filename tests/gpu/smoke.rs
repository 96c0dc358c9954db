//! The GPU half of the smoke test (`cargo test --release --test cpu --test gpu smoke`): one tiny frame of the
//! Cornell box through the whole GPU path (world upload, primary rays, light sampling, accumulation, readback)
//! against the CPU. Primary hits must match the CPU's traversal per pixel, and the lit frame the CPU reference
//! (the same estimator) in its mean and per pixel, at a size that takes seconds on software Vulkan.

use crate::common;

use glowbrick::reference::metrics::compare;
use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::world::recipe::load_scene;

const W: u32 = 48;
const H: u32 = 32;

pub fn a_tiny_frame_matches_the_cpu_reference() {
    let world = load_scene("cornell").unwrap();
    let view = world.view(Some("front")).unwrap().clone();
    let keep = common::comparable_pixels(&world, &view, W, H);
    let kept = keep.iter().filter(|k| **k).count();
    // Only pixels on or beside the light are left out; a broken primary pass would leave out most.
    assert!(kept * 5 >= keep.len() * 4, "{kept} of {} pixels hit the CPU's voxel", keep.len());
    let mut renderer = common::renderer_with(&world, &view, W, H, &["lighting=nee", "accumulate=on"]);
    let gpu = common::masked(&renderer.render(64).unwrap(), &keep);
    // `candidates` 1: the GPU's estimator (one power-drawn light per sample).
    let options =
        ReferenceOptions { width: W, height: H, spp: 256, bounces: 0, seed: 5, candidates: 1, ..Default::default() };
    let cpu = common::masked(&render_reference(&world, &view, &options).unwrap().image, &keep);
    let (g, c) = (gpu.mean_luminance(), cpu.mean_luminance());
    let m = compare(&gpu, &cpu).unwrap();
    let mean_channel =
        cpu.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum::<f64>() / (3 * cpu.pixels.len()) as f64;
    let relative_mae = m.mae / mean_channel;
    eprintln!("smoke: GPU mean {g:.5}, CPU mean {c:.5} ({:+.2}%), relative MAE {relative_mae:.4}", 100.0 * (g - c) / c);
    assert_eq!(gpu.non_finite_pixels(), 0);
    assert!(((g - c) / c).abs() < 0.05, "GPU mean {g} vs CPU {c}");
    assert!(relative_mae < 0.3, "per-pixel relative MAE {relative_mae}");
}
