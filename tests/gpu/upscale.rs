//! Render scale and the upscaler on the GPU: below scale 1 the lighting passes trace fewer rays per output pixel,
//! a frame stays about as close to the converged reference as a native one, the mean is kept, and the pixels that
//! see the sky are the native frame's exactly (the upscaler traces nothing: it reads the output's own G-buffer).
//!
//! Stated bounds (test-room `inside` at noon, lighting=full, gi=off so the CPU's direct light is the whole answer;
//! 1024-spp reference over the comparable pixels; 160x96 output, 80x48 at scale 0.5): one denoised frame after 16
//! at scale 0.5 has at most 1.5x native's relMSE; accumulated over 64 raw frames the means differ by at most 2%;
//! the lighting passes (ReSTIR's and the GI cache's) trace at most 0.8 brick-grid rays per output pixel on the
//! game's frame at 320x180 on window-room and cornell.

use crate::common;

use glowbrick::bench::frame::{CASES, FrameConfig, LIGHTINGS, measure};
use glowbrick::image_io::LinearImage;
use glowbrick::lights::daylight::Daylight;
use glowbrick::reference::metrics::compare;
use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::world::recipe::load_scene;
use glowbrick::world::{CameraView, VoxelWorld};

const W: u32 = 160;
const H: u32 = 96;

fn room() -> (VoxelWorld, CameraView) {
    let world = load_scene("test-room").unwrap();
    let view = world.view(Some("inside")).unwrap().clone();
    (world, view)
}

fn frame(world: &VoxelWorld, view: &CameraView, frames: u32, pairs: &[&str]) -> LinearImage {
    let mut all = vec!["time=12", "gi=off"];
    all.extend_from_slice(pairs);
    common::renderer_with(world, view, W, H, &all).render(frames).unwrap()
}

pub fn at_half_scale_a_frame_is_about_as_close_to_the_reference_and_keeps_the_mean() {
    let (world, view) = room();
    let keep = common::comparable_pixels(&world, &view, W, H);
    let options =
        ReferenceOptions { width: W, height: H, spp: 1024, daylight: Some(Daylight::at(12.0, true)), ..Default::default() };
    let truth = common::masked(&render_reference(&world, &view, &options).unwrap().image, &keep);
    let one = |scale: &str| {
        let image = frame(&world, &view, 16, &["denoise=on", &format!("render_scale={scale}")]);
        compare(&common::masked(&image, &keep), &truth).unwrap()
    };
    let (native, half) = (one("1"), one("0.5"));
    eprintln!("one denoised frame: native {native}; scale 0.5 {half}; relMSE {:.2}x", half.relmse / native.relmse);
    assert!(half.relmse <= 1.5 * native.relmse, "relMSE native {} at 0.5 {}", native.relmse, half.relmse);
    let accumulated = |scale: &str| {
        let image = frame(&world, &view, 64, &["accumulate=on", &format!("render_scale={scale}")]);
        common::masked(&image, &keep).mean_luminance()
    };
    let (native, half) = (accumulated("1"), accumulated("0.5"));
    eprintln!("64 raw frames: mean native {native:.5}, at 0.5 {half:.5} ({:+.2}%)", 100.0 * (half / native - 1.0));
    assert!((half / native - 1.0).abs() <= 0.02, "mean native {native} at 0.5 {half}");
}

pub fn the_sky_of_an_upscaled_frame_is_the_native_frames() {
    let world = load_scene("apartments").unwrap();
    let view = world.view(Some("street")).unwrap().clone();
    let native = frame(&world, &view, 2, &[]);
    let half = frame(&world, &view, 2, &["render_scale=0.5"]);
    let hits = common::renderer_with(&world, &view, W, H, &["debug=hit"]).render(1).unwrap();
    let sky: Vec<usize> = (0..hits.pixels.len()).filter(|&i| hits.pixels[i][3] == 0.0).collect();
    assert!(sky.len() > 100, "the view sees the sky at {} pixels", sky.len());
    let different = sky.iter().filter(|&&i| native.pixels[i] != half.pixels[i]).count();
    assert_eq!(different, 0, "{different} of {} sky pixels differ", sky.len());
}

pub fn at_half_scale_the_lighting_passes_trace_under_a_ray_per_output_pixel() {
    let config = FrameConfig {
        sizes: vec![(320, 180)],
        cases: CASES.iter().filter(|c| ["window-room", "cornell"].contains(&c.label)).copied().collect(),
        lightings: vec![LIGHTINGS[0]],
        warm_frames: 4,
        timed_frames: 1,
        extra: Vec::new(),
    };
    for case in &config.cases {
        let at = |scale: &str| {
            let config = FrameConfig { extra: vec![format!("render_scale={scale}")], ..config.clone() };
            measure(case, config.lightings[0], config.sizes[0], &config).unwrap()
        };
        let (native, half) = (at("1"), at("0.5"));
        eprintln!(
            "{}: lighting rays per output pixel {:.3} native, {:.3} at 0.5 (ReSTIR per render pixel {:.2} and {:.2})",
            case.label,
            native.lighting_rays_per_output_pixel(),
            half.lighting_rays_per_output_pixel(),
            native.restir_rays_per_render_pixel(),
            half.restir_rays_per_render_pixel()
        );
        assert!(half.lighting_rays_per_output_pixel() <= 0.8, "{}", case.label);
        assert!(half.lighting_rays_per_output_pixel() < 0.5 * native.lighting_rays_per_output_pixel(), "{}", case.label);
    }
}
