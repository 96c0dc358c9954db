//! The game's frame keeps to its ray budget: every per-pixel pass counts the brick-grid rays it traces
//! (`COUNT_RAYS_*`), and a change that adds rays to a pass fails here. This is `glowbrick bench --frame --quick`:
//! the game's frame (full lighting, GI cache, denoiser) at 48x32 on four scenes, a frame after the temporal
//! history and the GI warm-up began.

use glowbrick::bench::frame::{FrameConfig, QUICK_HIT_PIXEL_BUDGET, RAY_BUDGET, run_quick};
use glowbrick::render::gpu_types::GpuCounter;

pub fn the_game_frame_keeps_to_its_rays_per_pixel() {
    let rows = run_quick().unwrap_or_else(|over| panic!("over the frame's ray budget: {over}"));
    assert_eq!(rows.len(), FrameConfig::quick().cases.len());
    for row in &rows {
        for (counter, pass, budget) in RAY_BUDGET {
            eprintln!("{}: {pass}: {:.3} rays per pixel (budget {budget})", row.case, row.rays_per_pixel(counter));
        }
        let (steps, loads) = row.steps_per_ray();
        eprintln!(
            "{}: direct light: {:.3} rays per pixel, {:.3} per hit pixel (budget {QUICK_HIT_PIXEL_BUDGET}), \
             {steps:.1} steps and {loads:.1} loads per ray",
            row.case,
            row.direct_rays() / row.pixels(),
            row.rays_per_hit_pixel()
        );
        // Every pixel's primary ray walks the grid once, and the counters are live: ReSTIR's passes trace too.
        let count = |c: GpuCounter| row.counters[c as usize];
        assert_eq!(count(GpuCounter::RaysPrimary) as f64, row.pixels(), "{}", row.case);
        assert!(count(GpuCounter::RaysRestirInitial) > 0 && count(GpuCounter::RaysRestirShade) > 0, "{}", row.case);
        // Every view sees some voxels and some pixels see through to the sky or the world's edge, or all hit.
        let hits = count(GpuCounter::PrimaryHits);
        assert!(hits > 0 && hits as f64 <= row.pixels(), "{}: {hits} hit pixels", row.case);
        // Every ray visits at least the region it starts in and loads its mask (the rays that start outside the
        // world's box and miss it take none, and none of these views has them); the GPU walks the CPU's hierarchy,
        // whose loads per ray on such scenes are a few to a few tens.
        assert!(steps >= 1.0 && loads >= 1.0, "{}: {steps} steps and {loads} loads per ray", row.case);
        assert!(loads <= 2.0 * steps && loads < 100.0, "{}: {steps} steps and {loads} loads per ray", row.case);
    }
}
