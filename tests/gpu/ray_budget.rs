//! The game's frame keeps to its ray budget: every per-pixel pass counts the brick-grid rays it traces
//! (`COUNT_RAYS_*`), and a change that adds rays to a pass fails here. Cornell box, `RenderSettings::game()`'s
//! frame (full lighting, GI cache, denoiser), a frame after the temporal history and the GI warm-up began.

use crate::common;

use glowbrick::render::gpu_types::GpuCounter;
use glowbrick::world::recipe::load_scene;

const W: u32 = 48;
const H: u32 = 32;

/// Rays per pixel each pass may trace at most: the primary ray; the chosen candidate's visibility; one per
/// spatial tap (`taps`, 5 by default, with `reuse=one-ray`); the final shadow ray and the sun's disk.
const BUDGET: [(GpuCounter, &str, f64); 4] = [
    (GpuCounter::RaysPrimary, "primary", 1.0),
    (GpuCounter::RaysRestirInitial, "ReSTIR initial", 1.0),
    (GpuCounter::RaysRestirSpatial, "ReSTIR spatial", 5.0),
    (GpuCounter::RaysRestirShade, "ReSTIR shade", 2.0),
];

/// Rays per pixel of the whole direct light (primary included) at the test's size, in every scene below.
const TOTAL_AT_TEST_SIZE: f64 = 3.5;

pub fn the_game_frame_keeps_to_its_rays_per_pixel() {
    for (scene, view) in [("cornell", "front"), ("window-room", "inside"), ("apartments", "street"), ("letters", "")] {
        let world = load_scene(scene).unwrap();
        let view = world.view((!view.is_empty()).then_some(view)).unwrap().clone();
        let mut renderer = common::renderer_with(&world, &view, W, H, &["gi=on", "denoise=on"]);
        renderer.render(4).unwrap();
        let counters = renderer.counters().unwrap();
        let pixels = (W * H) as f64;
        let mut total = 0.0;
        for (counter, pass, budget) in BUDGET {
            let per_pixel = counters[counter as usize] as f64 / pixels;
            eprintln!("{scene}: {pass}: {per_pixel:.3} rays per pixel (budget {budget})");
            assert!(per_pixel <= budget, "{scene}: {pass} traces {per_pixel:.3} rays per pixel, over {budget}");
            total += per_pixel;
        }
        eprintln!("{scene}: direct light: {total:.3} rays per pixel");
        // At this size the four scenes trace 2.2-2.8 rays a pixel (primary included): a pass that adds one ray
        // for a large share of the pixels crosses this line. (At 320x180 the spatial taps land inside the image
        // more often: 2.6-4.2, docs/bench/rays.md.)
        assert!(total <= TOTAL_AT_TEST_SIZE, "{scene}: {total:.3} rays per pixel, over {TOTAL_AT_TEST_SIZE}");
        // Every pixel's primary ray walks the grid once, and the counters are live: ReSTIR's passes trace too.
        assert_eq!(counters[GpuCounter::RaysPrimary as usize], W * H);
        assert!(
            counters[GpuCounter::RaysRestirInitial as usize] > 0 && counters[GpuCounter::RaysRestirShade as usize] > 0
        );
    }
}
