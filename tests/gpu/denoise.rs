//! The denoiser on the GPU: a single denoised frame is much closer to the converged reference than a raw one,
//! the filter adds little bias, a lamp switched off shows within a frame, and with the denoiser off none of its
//! passes runs.
//!
//! Stated bounds (96x64, test-room `inside` at noon, lighting=full, gi=off so the reference's direct light is the
//! whole answer; 1024-spp reference over the comparable pixels): one frame after 16, relMSE denoised at most a
//! third of raw; accumulated over 128 frames, the denoised image's bias differs from the raw image's by at most
//! 2% of the mean; after a lamp is removed at night, with and without the GI cache, the mean of the pixels it
//! lit is within 10% of the step to its new converged value by the 4th frame and within 3.5% by the 8th.

use crate::common;

use bevy::math::IVec3;
use glowbrick::image_io::LinearImage;
use glowbrick::lights::daylight::Daylight;
use glowbrick::reference::metrics::compare;
use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::render::denoise::DENOISE_PASS_NAMES;
use glowbrick::world::events::EditRequest;
use glowbrick::world::scene::load_scene;
use glowbrick::world::{CameraView, Edit, VoxelWorld};

const W: u32 = 96;
const H: u32 = 64;

fn room() -> (VoxelWorld, CameraView) {
    let world = load_scene("test-room").unwrap();
    let view = world.view(Some("inside")).unwrap().clone();
    (world, view)
}

pub fn a_denoised_frame_is_closer_to_the_reference_and_adds_little_bias() {
    let (world, view) = room();
    let keep = common::comparable_pixels(&world, &view, W, H);
    let options = ReferenceOptions {
        width: W,
        height: H,
        spp: 1024,
        daylight: Some(Daylight::at(12.0, true)),
        ..Default::default()
    };
    let truth = common::masked(&render_reference(&world, &view, &options).unwrap().image, &keep);
    let mean = truth.mean_luminance();
    let frame = |pairs: &[&str]| -> LinearImage {
        let mut all = vec!["time=12", "gi=off"];
        all.extend_from_slice(pairs);
        common::masked(&common::renderer_with(&world, &view, W, H, &all).render(16).unwrap(), &keep)
    };
    let raw = compare(&frame(&["denoise=off"]), &truth).unwrap();
    let denoised = compare(&frame(&["denoise=on"]), &truth).unwrap();
    eprintln!("one frame: raw {raw}; denoised {denoised}; relMSE {:.1}x lower", raw.relmse / denoised.relmse);
    assert!(denoised.relmse * 3.0 <= raw.relmse, "relMSE raw {} denoised {}", raw.relmse, denoised.relmse);
    let accumulated = |on: &str| {
        let image = common::renderer_with(&world, &view, W, H, &["time=12", "gi=off", "accumulate=on", on])
            .render(128)
            .unwrap();
        compare(&common::masked(&image, &keep), &truth).unwrap()
    };
    let (raw, denoised) = (accumulated("denoise=off"), accumulated("denoise=on"));
    let added = (denoised.bias - raw.bias) / mean;
    eprintln!("128 frames: raw {raw}; denoised {denoised}; bias added {:+.2}% of the mean {mean:.4}", 100.0 * added);
    assert!(added.abs() <= 0.02, "the filter moved the mean by {:+.2}%", 100.0 * added);
}

pub fn a_lamp_switched_off_leaves_no_ghost() {
    // Without and with the GI cache (the game's frame): the cache restarts its blends when the light changes.
    for gi in ["gi=off", "gi=on"] {
        let frames = frames_for_a_lamp_to_go(gi);
        assert!(frames <= 4, "{gi}: {frames} frames for the light to go");
    }
}

/// Frames after the test room's lamp is removed at night until the mean of the pixels it lit is within 10% of
/// the step to its converged unlit value (that value is near 0 at night: 10% of it would be inside one frame's
/// noise). Panics when 8 frames are not enough.
fn frames_for_a_lamp_to_go(gi: &str) -> u32 {
    let (world, view) = room();
    // The room's lamp: a column of two voxels at (24, 1..3, 24).
    let off = Edit::FillBox { min: IVec3::new(24, 1, 24), max: IVec3::new(24, 2, 24), material: 0 };
    let mut dark = world.clone();
    dark.apply(off.clone()).unwrap();
    let converged = common::renderer_with(&dark, &view, W, H, &["time=0", gi, "accumulate=on"]).render(64).unwrap();
    let mut renderer = common::renderer_with(&world, &view, W, H, &["time=0", gi, "denoise=on"]);
    let lit = renderer.render(32).unwrap();
    // The pixels the lamp lit: now at least twice as bright as without it.
    let affected: Vec<usize> = (0..lit.pixels.len())
        .filter(|&i| {
            let (a, b) = (lit.pixels[i][1], converged.pixels[i][1]);
            a > 2.0 * b + 0.005
        })
        .collect();
    assert!(affected.len() > 300, "{gi}: {} pixels lit by the lamp", affected.len());
    let mean =
        |image: &LinearImage| affected.iter().map(|&i| image.pixels[i][1] as f64).sum::<f64>() / affected.len() as f64;
    let target = mean(&converged);
    renderer.app_mut().world_mut().write_message(EditRequest::player(off));
    let step = (mean(&lit) - target).abs();
    let mut first = None;
    let mut left = 1.0;
    for frame in 1..=8 {
        let now = mean(&renderer.render_next().unwrap());
        left = (now - target).abs() / step;
        eprintln!(
            "{gi}: lamp off, frame {frame}: mean {now:.5} against {target:.5} converged ({:.1}% of the step left)",
            100.0 * left
        );
        if first.is_none() && left <= 0.1 {
            first = Some(frame);
        }
    }
    // Measured with the GI cache: 2.2% left at frame 8 (4.6% before the cache restarted its blends on a change
    // of light); 10% of the step is reached at frame 3 either way.
    assert!(left <= 0.035, "{gi}: {:.1}% of the lamp's light left 8 frames after it went out", 100.0 * left);
    first.unwrap_or_else(|| panic!("{gi}: the lamp's light was still there 8 frames after it went out"))
}

pub fn with_the_denoiser_off_none_of_its_passes_runs() {
    let (world, view) = room();
    let mut renderer = common::renderer_with(&world, &view, W, H, &["gi=off"]);
    renderer.render(4).unwrap();
    let primary = renderer.gpu_pass_ms(glowbrick::render::primary::PRIMARY_PASS_NAME);
    assert!(primary.is_some() || !common::require_gpu(), "the primary pass records its GPU time");
    for name in DENOISE_PASS_NAMES {
        assert_eq!(renderer.gpu_pass_ms(name), None, "{name} ran with denoise=off");
    }
    renderer.app_mut().world_mut().resource_mut::<glowbrick::settings::RenderSettings>().denoise = true;
    renderer.render(4).unwrap();
    if primary.is_some() {
        for name in DENOISE_PASS_NAMES {
            assert!(renderer.gpu_pass_ms(name).is_some(), "{name} did not run with denoise=on");
        }
    }
}
