//! Scenes at the edges of the numbers: emission strengths over eight decades in one scene, a light one voxel
//! above a floor, lights embedded in the surface the camera sees, 10^5 lights, a room in the far corner of the
//! largest world, and a single light seen through a one-voxel hole. Each renders with unbiased Voxel ReSTIR
//! (128 frames accumulated at 64x48) with no non-finite pixel, and its mean luminance is within a stated bound of
//! a 512-spp CPU reference of the same view: 5%, or 10% where the camera sees surfaces touching a light
//! (unbounded variance there: cos cos / d^2 at d -> 0).
//!
//! A right mean can hide a wrong image, so each is also compared per pixel: its MAE relative to the reference's
//! mean (1 for a black image) stays within a bound per scene, about 1.5x what lavapipe measures, the rest of the
//! margin left for another adapter's different noise. The reference is two independent halves, whose difference
//! prints its own noise, and the test checks its bound rejects the reference shifted by two pixels.

use crate::common;

use bevy::math::{IVec3, UVec3};
use glowbrick::headless::HeadlessOptions;
use glowbrick::image_io::LinearImage;
use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::settings::RenderSettings;
use glowbrick::world::palette::{Material, Palette};
use glowbrick::world::{CameraView, VoxelWorld};

const W: u32 = 64;
const H: u32 = 48;

fn view(origin: [f32; 3], direction: [f32; 3]) -> CameraView {
    CameraView { name: "shot".into(), origin, direction, fov_deg: 60.0 }
}

/// Renders `world` from `view` with ReSTIR and with the CPU, and checks finiteness, the mean (within `bound`)
/// and the per-pixel error (relative MAE within `pixel_bound`).
fn check(name: &str, world: VoxelWorld, view: &CameraView, bound: f64, pixel_bound: f64) {
    check_with(name, world, view, bound, pixel_bound, &[]);
}

fn check_with(name: &str, world: VoxelWorld, view: &CameraView, bound: f64, pixel_bound: f64, extra: &[&str]) {
    let mut pairs = ["lighting=restir", "reuse=unbiased", "accumulate=on", "radius=5"].map(String::from).to_vec();
    pairs.extend(extra.iter().map(|p| p.to_string()));
    let settings = RenderSettings::default().with_pairs(&pairs).unwrap();
    let options = HeadlessOptions { width: W, height: H, settings, ..Default::default() };
    let mut renderer = common::renderer(world.clone(), view, &options);
    let gpu = renderer.render(128).unwrap();
    drop(renderer);
    let bad = gpu.non_finite_pixels();
    assert_eq!(bad, 0, "{name}: non-finite pixels");
    // A million lights make the CPU estimate noisy too (512 spp: 1.5% from a 4096-spp one): more samples there.
    let spp = if name.contains("10^6") { 2048 } else { 512 };
    // The reference is two independent halves: their mean is the reference, their difference its own noise.
    let half = |seed| {
        let options = ReferenceOptions { width: W, height: H, spp: spp / 2, bounces: 0, seed, ..Default::default() };
        render_reference(&world, view, &options).unwrap().image
    };
    let halves = [half(3), half(4)];
    let cpu = LinearImage::mean_of(&halves);
    assert_eq!(cpu.non_finite_pixels(), 0, "{name}: non-finite CPU pixels");
    let (g, c) = (gpu.mean_luminance(), cpu.mean_luminance());
    // The reference's own per-pixel noise: the halves' difference is twice as noisy as their mean.
    let noise = 0.5 * relative_mae(&halves[0], &halves[1]);
    let error = relative_mae(&gpu, &cpu);
    // What a render of the wrong place would score (a black image scores 1).
    let shifted = relative_mae(&shift(&cpu, SHIFT, SHIFT), &cpu);
    eprintln!(
        "{name}: GPU mean {g:.6}, CPU mean {c:.6} ({:+.2}%); per-pixel relative MAE {error:.4} (bound \
         {pixel_bound}), the reference's noise {noise:.4}, the reference shifted {SHIFT} px both ways {shifted:.4}",
        100.0 * (g - c) / c
    );
    assert!(c > 0.0, "{name}: the reference sees light");
    assert!(((g - c) / c).abs() < bound, "{name}: GPU mean {g} vs CPU {c}");
    assert!(error < pixel_bound, "{name}: per-pixel relative MAE {error} against the CPU (bound {pixel_bound})");
    // The bound must fail an image that is right on average but wrong per pixel. Not with a million lights: their
    // view is a field of near-equal small lamps with no structure a shift changes by more than the noise (6 px
    // scores barely above a 2-px shift); there the bound catches a black or wrongly lit image only.
    assert!(
        name.contains("10^6") || shifted > pixel_bound,
        "{name}: a {SHIFT}-pixel shift ({shifted}) passes the bound {pixel_bound}"
    );
}

/// Pixels a render of the wrong place is shifted by, across and down (the bounds must reject it).
const SHIFT: i32 = 2;

/// Mean absolute error per pixel and channel relative to the reference's mean channel value: 0 for the
/// reference itself, 1 for a black image, whatever the scene's brightness.
fn relative_mae(image: &LinearImage, reference: &LinearImage) -> f64 {
    let mae = glowbrick::reference::metrics::compare(image, reference).unwrap().mae;
    let sum: f64 = reference.pixels.iter().map(|p| (p[0] + p[1] + p[2]) as f64).sum();
    mae / (sum / (3 * reference.pixels.len()) as f64)
}

/// `image` moved by (`dx`, `dy`) pixels, its edge repeated into the gap.
fn shift(image: &LinearImage, dx: i32, dy: i32) -> LinearImage {
    let (w, h) = (image.width as i32, image.height as i32);
    let pixels = (0..h)
        .flat_map(|y| (0..w).map(move |x| ((x - dx).clamp(0, w - 1), (y - dy).clamp(0, h - 1))))
        .map(|(x, y)| image.pixel(x as u32, y as u32))
        .collect();
    LinearImage { pixels, ..*image }
}

fn palette_with(lamps: &[(&str, f32)]) -> (Palette, u16, Vec<u16>) {
    let mut palette = Palette::new(vec![]);
    let white = palette.push(Material::solid("white", [0.8, 0.8, 0.8]));
    let ids = lamps.iter().map(|(n, s)| palette.push(Material::emissive(n, [0.9; 3], [1.0, 0.9, 0.8], *s))).collect();
    (palette, white, ids)
}

pub fn emission_over_eight_decades_in_one_scene() {
    let strengths = [("e-4", 1e-4), ("e-2", 1e-2), ("e0", 1.0), ("e2", 1e2), ("e4", 1e4)];
    let (palette, white, lamps) = palette_with(&strengths);
    let mut world = VoxelWorld::new(UVec3::new(48, 16, 16), palette);
    world.grid.fill_box(IVec3::ZERO, IVec3::new(48, 1, 16), white).unwrap();
    for (i, lamp) in lamps.iter().enumerate() {
        world.grid.set(IVec3::new(4 + 10 * i as i32, 3, 8), *lamp).unwrap();
    }
    check("eight decades", world, &view([24.0, 12.0, -8.0], [0.0, -0.5, 1.0]), 0.05, 0.055);
}

pub fn a_light_one_voxel_above_the_floor() {
    let (palette, white, lamps) = palette_with(&[("lamp", 4.0)]);
    let mut world = VoxelWorld::new(UVec3::splat(24), palette);
    world.grid.fill_box(IVec3::ZERO, IVec3::new(24, 1, 24), white).unwrap();
    // Floor top at y = 1, lamp at y = 2: one voxel of air between; grazing light across the floor.
    world.grid.set(IVec3::new(12, 2, 12), lamps[0]).unwrap();
    check("one voxel above", world, &view([12.0, 6.0, 2.0], [0.0, -0.45, 1.0]), 0.05, 0.03);
}

pub fn lights_embedded_in_the_surface_the_camera_sees() {
    let (palette, white, lamps) = palette_with(&[("lamp", 4.0)]);
    let mut world = VoxelWorld::new(UVec3::splat(24), palette);
    world.grid.fill_box(IVec3::ZERO, IVec3::new(24, 1, 24), white).unwrap();
    for x in [6, 12, 18] {
        world.grid.set(IVec3::new(x, 0, 12), lamps[0]).unwrap();
    }
    check("touching", world, &view([12.0, 8.0, 2.0], [0.0, -0.6, 1.0]), 0.10, 0.01);
}

pub fn a_hundred_thousand_lights() {
    let (palette, white, lamps) = palette_with(&[("lamp", 0.5)]);
    let mut world = VoxelWorld::new(UVec3::new(448, 16, 448), palette);
    world.grid.fill_box(IVec3::ZERO, IVec3::new(448, 1, 448), white).unwrap();
    // A checkerboard layer of 100,352 one-voxel lights four voxels above the floor.
    for z in 0..448 {
        for x in (z % 2..448).step_by(2) {
            world.grid.set(IVec3::new(x, 5, z), lamps[0]).unwrap();
        }
    }
    // With temporal reuse: until reservoirs that hold no light kept their M (`validated` in
    // shaders/restir/common.wgsl) it brightened this view by +88% (docs/bench/restir.md); now +1.3%.
    check_with("10^5 lights", world, &view([224.0, 3.0, 200.0], [0.0, -0.2, 1.0]), 0.05, 0.16, &[]);
}

pub fn a_million_lights() {
    let (palette, white, lamps) = palette_with(&[("lamp", 0.5)]);
    let edge = 1416;
    let mut world = VoxelWorld::new(UVec3::new(edge, 16, edge), palette);
    world.grid.fill_box(IVec3::ZERO, IVec3::new(edge as i32, 1, edge as i32), white).unwrap();
    // A checkerboard layer of 1,002,528 one-voxel lights four voxels above the floor.
    for z in 0..edge as i32 {
        for x in (z % 2..edge as i32).step_by(2) {
            world.grid.set(IVec3::new(x, 5, z), lamps[0]).unwrap();
        }
    }
    let lights = glowbrick::lights::LightPool::from_world(&world).len();
    assert!(lights > 1_000_000, "{lights} lights");
    // With temporal reuse, as the 10^5 case. Bound 8%, not 5%: without temporal reuse it measured -3.5%, -4.7%
    // and -4.9% against 4096-, 2048- and 512-spp references (the references differ by 1.5% among themselves:
    // with a million lights the few nearest dominate and both sides sample them rarely); a systematic few-%
    // darkening here is not ruled out and is listed in docs/bench/stress.md.
    let c = edge as f32 / 2.0;
    check_with("10^6 lights", world, &view([c, 3.0, c - 24.0], [0.0, -0.2, 1.0]), 0.08, 0.3, &[]);
}

pub fn a_room_in_the_far_corner_of_the_largest_world() {
    let (palette, white, lamps) = palette_with(&[("lamp", 6.0)]);
    let edge = glowbrick::world::grid::MAX_WORLD_EDGE;
    let mut world = VoxelWorld::new(UVec3::new(edge, 16, edge), palette);
    let far = edge as i32;
    world.grid.fill_box(IVec3::new(far - 32, 0, far - 32), IVec3::new(far, 1, far), white).unwrap();
    world.grid.fill_box(IVec3::new(far - 1, 1, far - 32), IVec3::new(far, 16, far), white).unwrap();
    world.grid.set(IVec3::new(far - 8, 6, far - 8), lamps[0]).unwrap();
    let o = far as f32;
    check("far corner", world, &view([o - 24.0, 10.0, o - 24.0], [1.0, -0.4, 1.0]), 0.05, 0.032);
}

/// A world whose brick pool is past what software Vulkan binds in one buffer (128 MiB) renders through the pool's
/// parts (`render::scene::world::POOL_PARTS`), every hit where the CPU finds it. 512 x 256 x 528 voxels: one voxel
/// in every brick of the first 512 voxels of z (131,072 stored bricks, the first part on lavapipe), then two layers
/// of bricks in the next part, the last of them a wall of 8 x 8 x 2 voxels per brick at a depth that changes from
/// brick to brick, which nearly every camera ray meets: a slot read from the wrong part, or not at all, moves the
/// hit. The pool with the upload's headroom is 198 MiB. Tolerance: the primary test's (0.5% of pixels may differ,
/// by a neighbouring voxel or at a silhouette).
pub fn a_world_past_one_gpu_binding_renders_through_pool_parts() {
    let (palette, white, _) = palette_with(&[]);
    let mut world = VoxelWorld::new(UVec3::new(512, 256, 528), palette);
    let brick_dependent = |b: IVec3| IVec3::new(b.x % 8, (b.y + b.z) % 8, (b.x + 2 * b.y) % 8);
    for z in (0..512).step_by(8) {
        for y in (0..256).step_by(8) {
            for x in (0..512).step_by(8) {
                let corner = IVec3::new(x, y, z);
                world.grid.set(corner + brick_dependent(corner / 8), white).unwrap();
            }
        }
    }
    for y in (0..256).step_by(8) {
        for x in (0..512).step_by(8) {
            let corner = IVec3::new(x, y, 512);
            world.grid.set(corner + brick_dependent(corner / 8), white).unwrap();
            let depth = brick_dependent(IVec3::new(x, y, 520) / 8).z % 7;
            world.grid.fill_box(IVec3::new(x, y, 520 + depth), IVec3::new(x + 8, y + 8, 522 + depth), white).unwrap();
        }
    }
    let slots = world.grid.pool_capacity();
    assert!(slots > 1 << 17, "{slots} stored bricks: some must lie past the first part on lavapipe");
    let (name, part) = glowbrick::render::scene::world::required_binding(&world);
    let limit = glowbrick::render::adapter::probe_adapter().expect("a GPU").max_binding;
    assert!(part <= limit, "the {name} needs {part} bytes per binding, the GPU binds {limit}");
    let settings = RenderSettings::default().with_pairs(&["debug=hit".to_string()]).unwrap();
    let options = HeadlessOptions { width: 32, height: 16, frames: 1, settings, ..Default::default() };
    // Off the voxel grid's planes, so no camera ray runs along a plate's edge (where the two sides round apart).
    let view = view([256.37, 128.61, 600.29], [0.013, -0.021, -1.0]);
    let mut renderer = glowbrick::headless::HeadlessRenderer::new(world.clone(), &view, &options)
        .expect("a pool in parts fits the GPU");
    let image = renderer.render(1).expect("render");
    let c = common::compare_hits(&world, &view, &image);
    eprintln!("pool in parts: {} pixels, {} hits, {} mismatches", c.pixels, c.hits, c.mismatches);
    // The hits in the wall's layer are reads of the second part on lavapipe.
    let in_wall = (0..options.width * options.height)
        .filter(|i| image.pixel(i % options.width, i / options.width)[2] >= 520.0)
        .count();
    assert!(in_wall * 10 >= c.pixels * 9, "{in_wall} of {} pixels see the wall", c.pixels);
    assert!(c.mismatches * 200 <= c.pixels, "{} of {} pixels differ from the CPU", c.mismatches, c.pixels);
}

pub fn a_single_light_behind_a_one_voxel_hole() {
    let (palette, white, lamps) = palette_with(&[("lamp", 50.0)]);
    let mut world = VoxelWorld::new(UVec3::splat(24), palette);
    // A closed box split by a wall at x = 12 with one hole; the lamp on the far side.
    world.grid.fill_box(IVec3::ZERO, IVec3::splat(24), white).unwrap();
    world.grid.fill_box(IVec3::ONE, IVec3::new(12, 23, 23), 0).unwrap();
    world.grid.fill_box(IVec3::new(13, 1, 1), IVec3::splat(23), 0).unwrap();
    world.grid.set(IVec3::new(12, 12, 12), 0).unwrap();
    world.grid.set(IVec3::new(18, 12, 12), lamps[0]).unwrap();
    check("one-voxel hole", world, &view([2.0, 12.0, 3.0], [0.6, -0.2, 0.6]), 0.05, 0.02);
}

/// A third of a floor's voxels are lamps lying on it (the `lights-100k` layout at test size): every floor pixel
/// beside a lamp sees its side face at a distance near 0, where a uniform point on the face weighs cos cos / d^2
/// (unbounded) and temporal reuse kept such a sample for its whole history (the bench's lights-100k frame had 23
/// fireflies, lights-1m 189). Near faces are sampled by solid angle, and a quarter of the candidates come from the
/// lights beside the face (`local_lights`): the power pick alone finds the lamp lying next to a pixel once in N.
/// The default reuse, frame 32 of a still camera: no pixel above 100x its reference plus 1 (the rule),
/// none above 2x the reference's brightest and relMSE under 0.05 (area sampling: 6.5x and 0.189; solid angle:
/// 2.3x and 0.126; with local lights: 1.25x and 0.028), at least 3x below the same frame without local lights;
/// 128 frames accumulated: the mean within 3%.
pub fn lamps_lying_on_a_floor() {
    let (palette, white, lamps) = palette_with(&[("lamp", 2.0)]);
    let mut world = VoxelWorld::new(UVec3::new(96, 16, 96), palette);
    world.grid.fill_box(IVec3::ZERO, IVec3::new(96, 1, 96), white).unwrap();
    let mut rng = glowbrick::reference::sampling::Pcg::new(17, 0);
    for z in 0..96 {
        for x in 0..96 {
            if rng.next_f32() < 0.33 {
                world.grid.set(IVec3::new(x, 1, z), lamps[0]).unwrap();
            }
        }
    }
    let view = view([48.0, 4.0, 4.0], [0.0, -0.25, 1.0]);
    let frame_32 = |pairs: &[&str]| {
        let pairs: Vec<String> = pairs.iter().map(|p| p.to_string()).collect();
        let settings = RenderSettings::default().with_pairs(&pairs).unwrap();
        let options = HeadlessOptions { width: W, height: H, settings, ..Default::default() };
        let mut renderer = common::renderer(world.clone(), &view, &options);
        let frame = renderer.render(32).unwrap();
        (renderer, frame)
    };
    let (mut renderer, frame) = frame_32(&["lighting=restir"]);
    renderer.app_mut().world_mut().resource_mut::<RenderSettings>().accumulate = true;
    let accumulated = renderer.render(128).unwrap();
    drop(renderer);
    let (_, without_local) = frame_32(&["lighting=restir", "local_lights=off"]);
    let options = ReferenceOptions { width: W, height: H, spp: 512, bounces: 0, seed: 3, ..Default::default() };
    let cpu = render_reference(&world, &view, &options).unwrap().image;
    let luminance = |p: &[f32; 4]| 0.2126 * p[0] as f64 + 0.7152 * p[1] as f64 + 0.0722 * p[2] as f64;
    let fireflies =
        frame.pixels.iter().zip(&cpu.pixels).filter(|(g, c)| luminance(g) > 100.0 * luminance(c) + 1.0).count();
    let brightest = frame.pixels.iter().map(luminance).fold(0.0, f64::max);
    let reference_brightest = cpu.pixels.iter().map(luminance).fold(0.0, f64::max);
    let (g, c) = (accumulated.mean_luminance(), cpu.mean_luminance());
    let one_frame = glowbrick::reference::metrics::compare(&frame, &cpu).unwrap();
    let no_local = glowbrick::reference::metrics::compare(&without_local, &cpu).unwrap();
    eprintln!(
        "lamps on a floor: frame 32 fireflies {fireflies}, brightest {brightest:.2} (reference {reference_brightest:.2}), \
         relMSE {:.4} (local_lights=off: {:.4}); accumulated mean {g:.5} vs CPU {c:.5} ({:+.2}%)",
        one_frame.relmse,
        no_local.relmse,
        100.0 * (g - c) / c
    );
    assert_eq!(frame.non_finite_pixels() + accumulated.non_finite_pixels(), 0);
    assert_eq!(fireflies, 0, "pixels above 100x their reference + 1 at frame 32");
    assert!(brightest < 2.0 * reference_brightest, "brightest pixel {brightest} (reference {reference_brightest})");
    assert!(one_frame.relmse < 0.05, "one frame's relMSE {}", one_frame.relmse);
    assert!(3.0 * one_frame.relmse < no_local.relmse, "local lights {} vs none {}", one_frame.relmse, no_local.relmse);
    assert!(((g - c) / c).abs() < 0.03, "accumulated mean {g} vs CPU {c}");
}
