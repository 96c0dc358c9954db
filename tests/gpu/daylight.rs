//! lighting=full on the GPU (the default of `render` and `play`): the sun's or moon's disk, the sky and every lamp
//! at once, against the CPU reference integrating the same lighting; a lamp placed at night lights the floor in
//! the very frame that places it.
//!
//! Stated bounds: test-room (a closed room lit through an 8 x 8 ceiling window and by a lamp), view `inside`,
//! 96x64, `gi=off` (so the sky arrives by one cosine ray per pixel and the reference's direct light is the whole
//! answer), 256 accumulated frames against a 1024-spp reference over the comparable pixels: |bias| < 3% of the
//! mean luminance and relMSE < 0.05, at noon, dusk and night. The reference's own noise (a 256-spp reference
//! against it) is printed beside each.

use crate::common;

use bevy::math::IVec3;
use glowbrick::colour::luminance;
use glowbrick::image_io::LinearImage;
use glowbrick::lights::daylight::Daylight;
use glowbrick::reference::metrics::compare;
use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::world::events::EditRequest;
use glowbrick::world::recipe::load_scene;
use glowbrick::world::{CameraView, Edit, VoxelWorld};

const W: u32 = 96;
const H: u32 = 64;

fn reference(world: &VoxelWorld, view: &CameraView, hours: f32, spp: u32, seed: u64) -> LinearImage {
    let daylight = Some(Daylight::at(hours, true));
    let options = ReferenceOptions { width: W, height: H, spp, seed, daylight, ..Default::default() };
    render_reference(world, view, &options).unwrap().image
}

pub fn full_lighting_converges_to_the_reference_at_noon_dusk_and_night() {
    let world = load_scene("test-room").unwrap();
    let view = world.view(Some("inside")).unwrap().clone();
    let keep = common::comparable_pixels(&world, &view, W, H);
    for hours in [12.0f32, 17.5, 0.0] {
        let truth = common::masked(&reference(&world, &view, hours, 1024, 5), &keep);
        let noise = compare(&common::masked(&reference(&world, &view, hours, 256, 6), &keep), &truth).unwrap();
        let mean = truth.mean_luminance();
        let time = format!("time={hours}");
        let mut renderer = common::renderer_with(&world, &view, W, H, &["accumulate=on", "radius=8", &time]);
        let image = renderer.render(256).unwrap();
        let m = compare(&common::masked(&image, &keep), &truth).unwrap();
        eprintln!(
            "test-room at {hours} h: {m} (bias {:+.2}% of the mean {mean:.4}); a 256-spp reference: mae {:.5}",
            100.0 * m.bias / mean,
            noise.mae
        );
        assert!(mean > 0.0, "{hours} h: the room is lit");
        assert!(m.bias.abs() < 0.03 * mean, "{hours} h: bias {} of mean {mean}", m.bias);
        assert!(m.relmse < 0.05, "{hours} h: relMSE {}", m.relmse);
    }
}

pub fn a_lamp_placed_at_night_lights_the_floor_in_the_frame_that_places_it() {
    let world = load_scene("test-room").unwrap();
    let lamp = world.palette.id_of("lamp").unwrap();
    let view = world.view(Some("inside")).unwrap().clone();
    // Direct light only: the GI cache's bounce light takes frames to follow by design (its blend).
    let mut renderer = common::renderer_with(&world, &view, W, H, &["time=0", "gi=off"]);
    let before = renderer.render(16).unwrap();
    let at = IVec3::new(16, 1, 16);
    renderer.app_mut().world_mut().write_message(EditRequest::player(Edit::Place { at, material: lamp }));
    // The readback is asked for before the frame that applies the edit, so it copies that frame's image (it
    // arrives while the next frame renders).
    let first = renderer.render_next().unwrap();
    let settled = renderer.render(16).unwrap();
    // Surfaces (not the lamp's own faces, radiance 10) that the new lamp lit by a visible amount.
    let lit = |after: &LinearImage| {
        before
            .pixels
            .iter()
            .zip(&after.pixels)
            .filter(|(b, a)| {
                let (b, a) = (luminance([b[0], b[1], b[2]]), luminance([a[0], a[1], a[2]]));
                a < 1.0 && a > b + 0.01
            })
            .count()
    };
    let (first_lit, settled_lit) = (lit(&first), lit(&settled));
    eprintln!("a lamp placed at night: {first_lit} pixels lit in its first frame, {settled_lit} 16 frames later");
    assert!(settled_lit > 30, "{settled_lit} pixels lit by the new lamp once settled");
    // ReSTIR gives the new light its full weight in its first frame: most of what it will light is lit already
    // (measured 391 of 499; a single frame's noise leaves some pixels under the threshold). With the temporal
    // history kept across the edit it was 41 of 340.
    assert!(first_lit * 10 >= settled_lit * 6, "{first_lit} of {settled_lit} pixels lit in the first frame");
}

pub fn the_clock_moved_in_a_running_game_moves_the_light() {
    let world = load_scene("test-room").unwrap();
    let view = world.view(Some("inside")).unwrap().clone();
    let pairs = ["gi=off", "denoise=on", "accumulate=on", "time=12"];
    let mut running = common::renderer_with(&world, &view, W, H, &pairs);
    running.render(8).unwrap();
    running.app_mut().world_mut().resource_mut::<glowbrick::settings::RenderSettings>().time = 0.0;
    let moved = running.render(64).unwrap();
    let night = common::renderer_with(&world, &view, W, H, &["gi=off", "denoise=on", "accumulate=on", "time=0"])
        .render(64)
        .unwrap();
    let noon = common::renderer_with(&world, &view, W, H, &pairs).render(64).unwrap();
    let (to_night, to_noon) = (compare(&moved, &night).unwrap(), compare(&moved, &noon).unwrap());
    eprintln!("clock moved to night: against night {to_night}, against noon {to_noon}");
    assert!(to_night.mae * 4.0 < to_noon.mae, "the running renderer still shows noon");
}
