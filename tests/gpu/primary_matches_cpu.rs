//! The GPU primary-ray pass against the CPU traversal, per pixel, on any adapter (lavapipe in CI).
//!
//! The pass runs with `debug=hit`, which writes `(voxel.x, voxel.y, voxel.z, face + 1)` (exact in f16), and the
//! CPU traces the same camera rays. Tolerance: at most 0.5% of pixels may differ, and only where the two disagree
//! about a ray through a voxel edge or corner (the hit voxels are neighbours) or grazing a silhouette.
//! With `GLOWBRICK_REQUIRE_GPU=1` a missing adapter fails the test; otherwise it is reported ignored (main.rs).

use crate::common;

use bevy::math::{IVec2, IVec3, UVec2, UVec3};
use common::compare_hits;
use glowbrick::colour::luminance;
use glowbrick::headless::HeadlessOptions;
use glowbrick::image_io::LinearImage;
use glowbrick::reference::metrics::compare;
use glowbrick::render::gpu_types::GpuCounter;
use glowbrick::settings::RenderSettings;
use glowbrick::world::generate::endless::EndlessGenerator;
use glowbrick::world::recipe::{generated_world, load_scene};
use glowbrick::world::traversal::{Counts, trace_counted, trace_occupancy_counted};
use glowbrick::world::{CameraView, VoxelWorld, trace};
use glowbrick::world::{camera_ray, view_transform, world_from_clip};

fn render(world: VoxelWorld, view: &CameraView, settings: RenderSettings, w: u32, h: u32) -> LinearImage {
    render_counted(world, view, settings, w, h).0
}

/// The image and its last frame's traversal steps and loads (the per-pixel passes' rays).
fn render_counted(
    world: VoxelWorld,
    view: &CameraView,
    settings: RenderSettings,
    w: u32,
    h: u32,
) -> (LinearImage, Counts) {
    let options = HeadlessOptions { width: w, height: h, frames: 2, settings, ..Default::default() };
    let mut renderer = common::renderer(world, view, &options);
    let image = renderer.render(options.frames).expect("render");
    let counters = renderer.counters().expect("counters");
    let steps = counters[GpuCounter::TraceSteps as usize] as u64;
    let loads = counters[GpuCounter::TraceLoads as usize] as u64;
    let rays = counters[GpuCounter::RaysPrimary as usize] as u64;
    (image, Counts { rays, steps, loads, ..Default::default() })
}

/// The CPU walk's steps and loads over the camera rays of a `w` x `h` view.
fn cpu_counts(world: &VoxelWorld, view: &CameraView, w: u32, h: u32, occupancy: bool) -> Counts {
    let transform = view_transform(view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), w, h);
    let mut counts = Counts::default();
    for i in 0..w * h {
        let ray = camera_ray(m, transform.translation, UVec2::new(i % w, i / w), w, h);
        counts.rays += 1;
        if occupancy {
            trace_occupancy_counted(&world.grid, &ray, f32::INFINITY, &mut counts);
        } else {
            trace_counted(&world.grid, &ray, f32::INFINITY, &mut counts);
        }
    }
    counts
}

/// Both walks of the grid (the `traversal` setting), on rooms and on terrain wider than a region of the occupancy
/// hierarchy (128 voxels).
pub fn gpu_primary_rays_match_cpu_traversal() {
    let room = load_scene("test-room").unwrap();
    let terrain = generated_world(9, UVec3::new(64, 40, 64)).unwrap();
    let wide = generated_world(3, UVec3::new(300, 72, 260)).unwrap();
    // The endless world a million voxels out, in its window's own coordinates (as `render --endless` has it).
    let endless = EndlessGenerator::new(1, 96).unwrap();
    let window = endless.window(EndlessGenerator::region_of(1_000_000, 1_000_000), 3, None).unwrap();
    let far = CameraView {
        name: "far".into(),
        origin: [1_000_000.5, 90.0, 1_000_000.5],
        direction: [0.7, -0.5, 0.6],
        fov_deg: 60.0,
    };
    let far = window.local_view(&far);
    // A window scrolled two regions along x: its storage wraps at x = 256, in the middle of the view.
    let mut scrolled = endless.window(IVec2::new(10, 4), 4, None).unwrap();
    scrolled.scroll_to(IVec2::new(12, 4), |keys| Ok(endless.regions(keys))).unwrap();
    assert_eq!(scrolled.world.grid.window().0.x, 128);
    let across = CameraView {
        name: "across the wrap".into(),
        origin: [200.5, 88.0, 160.5],
        direction: [0.8, -0.45, 0.3],
        fov_deg: 60.0,
    };
    // A scroll two regions on along x begun and not finished: the storage of the strip entering ahead still holds
    // the strip that left, outside the window, and neither walk may see it.
    let mut under_way = scrolled.world.clone();
    under_way.grid.begin_scroll(IVec3::new(256, 0, 0)).unwrap();
    assert_eq!(under_way.grid.window(), (IVec3::new(256, 0, 0), IVec3::new(384, 96, 256)));
    let ahead = CameraView { origin: [300.5, 88.0, 120.5], ..across.clone() };
    let cases = [
        ("endless window mid-scroll", under_way, ahead),
        ("endless window scrolled, wrapping mid-view", scrolled.world, across),
        ("endless world a million voxels out", window.world, far),
        ("test-room inside", room.clone(), room.view(Some("inside")).unwrap().clone()),
        ("test-room top", room.clone(), room.view(Some("top")).unwrap().clone()),
        ("terrain overview", terrain.clone(), terrain.overview()),
        ("wide terrain overview", wide.clone(), wide.overview()),
    ];
    for (name, world, view) in cases
        .iter()
        .flat_map(|c| [(c, "dda"), (c, "occupancy")])
        .map(|((n, w, v), t)| (format!("{n} traversal={t}"), w.clone(), v.clone()))
    {
        let traversal = name.rsplit(' ').next().unwrap().to_string();
        let hit_view = RenderSettings::default().with_pairs(&["debug=hit".to_string(), traversal.clone()]).unwrap();
        let (gpu, counted) = render_counted(world.clone(), &view, hit_view, 96, 64);
        let c = compare_hits(&world, &view, &gpu);
        eprintln!("{name}: {} pixels, {} hits, {} mismatches", c.pixels, c.hits, c.mismatches);
        assert!(c.hits * 3 > c.pixels, "{name}: the view should mostly hit voxels ({} of {})", c.hits, c.pixels);
        assert!(c.mismatches * 200 <= c.pixels, "{name}: {} of {} pixels differ", c.mismatches, c.pixels);
        // The GPU walks the CPU's walk step for step: its counters over the camera rays (the only rays of a
        // `debug=hit` frame) are the CPU's, but for the few rays through an edge that the two round apart.
        let cpu = cpu_counts(&world, &view, 96, 64, traversal == "traversal=occupancy");
        eprintln!(
            "{name}: steps GPU {} CPU {}, loads GPU {} CPU {}",
            counted.steps, cpu.steps, counted.loads, cpu.loads
        );
        assert_eq!(counted.rays, cpu.rays, "{name}: one primary ray a pixel");
        let near = |gpu: u64, cpu: u64| gpu.abs_diff(cpu) * 200 <= cpu;
        assert!(near(counted.steps, cpu.steps), "{name}: steps GPU {} CPU {}", counted.steps, cpu.steps);
        assert!(near(counted.loads, cpu.loads), "{name}: loads GPU {} CPU {}", counted.loads, cpu.loads);
    }
}

pub fn lit_render_is_finite_and_shows_emission() {
    let room = load_scene("test-room").unwrap();
    let view = room.view(Some("inside")).unwrap().clone();
    // Sun off: inside the closed room only the window's sky light and the lamp remain.
    let settings = RenderSettings::default().with_pairs(&["sun=off".to_string()]).unwrap();
    let image = render(room.clone(), &view, settings, 96, 64);
    assert_eq!(image.non_finite_pixels(), 0);
    // Every pixel that sees the lamp is at least as bright as the lamp's own radiance.
    let transform = view_transform(&view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), 96, 64);
    let lamp = room.palette.id_of("lamp").unwrap();
    let radiance = room.palette.get(lamp).unwrap().radiance();
    let mut lamp_pixels = 0;
    for y in 0..64 {
        for x in 0..96 {
            let ray = camera_ray(m, transform.translation, UVec2::new(x, y), 96, 64);
            if trace(&room.grid, &ray, f32::INFINITY).is_some_and(|h| h.material == lamp) {
                let p = image.pixel(x, y);
                // f16 storage: allow its relative precision.
                assert!((0..3).all(|c| p[c] >= radiance[c] * 0.999), "lamp pixel ({x}, {y}) = {p:?}");
                lamp_pixels += 1;
            }
        }
    }
    assert!(lamp_pixels > 0, "the view should see the lamp");
}

/// `render_sequence` returns every frame of a path once, in order, each with its own set-up: a camera walking
/// towards a wall half a voxel a frame sees it nearer by exactly that much in each frame's depth view.
pub fn a_rendered_sequence_returns_each_frame_with_its_own_camera() {
    use glowbrick::world::palette::{Material, Palette};
    let mut palette = Palette::new(vec![]);
    let white = palette.push(Material::solid("white", [0.8; 3]));
    let mut world = VoxelWorld::new(UVec3::splat(16), palette);
    world.grid.fill_box(bevy::math::IVec3::new(0, 0, 15), bevy::math::IVec3::new(16, 16, 16), white).unwrap();
    let at = |k: u32| CameraView {
        name: "walk".into(),
        origin: [8.0, 8.0, 2.0 + 0.5 * k as f32],
        direction: [0.0, 0.0, 1.0],
        fov_deg: 60.0,
    };
    let mut renderer = common::renderer_with(&world, &at(0), 32, 32, &["debug=depth"]);
    renderer.render(2).unwrap();
    let frames = renderer.render_sequence(6, |k, r| r.set_view(&at(k))).unwrap();
    let depths: Vec<f32> = frames.iter().map(|f| f.pixel(16, 16)[0]).collect();
    eprintln!("depth at the centre, frame by frame: {depths:?}");
    assert_eq!(frames.len(), 6);
    for (k, depth) in depths.iter().enumerate() {
        let expected = 15.0 - (2.0 + 0.5 * k as f32);
        assert!((depth - expected).abs() < 0.02, "frame {k}: depth {depth}, expected {expected} ({depths:?})");
    }
}

/// What a player's GPU runs (`traversal=auto` takes the occupancy walk on a GPU, the DDA on lavapipe): the game's
/// lit frame, every pass and bounce through the occupancy walk, is the DDA's frame. Same seeds and same hits, so
/// only the rays through an edge and the GI cache's own run-to-run noise (MAE about 0.0002 here) tell them apart;
/// a walk that let one shadow or bounce ray in twenty through a wall would move the frame by percents.
/// The GI entries' light reservoirs are off here: each carries one light sample across frames, seeded by the
/// entry's slot, which the insert race between workgroups decides, so two runs of one walk drew frames up to
/// 0.8% apart under the suite's load (0.1-0.25% alone) where this bound is 0.5%. Their shadow rays go through
/// the same `trace_scene` as the light sample this frame still takes.
pub fn the_game_frame_is_the_same_through_either_walk() {
    let room = load_scene("window-room").unwrap();
    let view = room.view(Some("inside")).unwrap().clone();
    let frame = |walk: &str| {
        let settings =
            RenderSettings::game().with_pairs(&[format!("traversal={walk}"), "gi_reservoirs=off".into()]).unwrap();
        let options = HeadlessOptions { width: 96, height: 64, frames: 6, settings, ..Default::default() };
        common::renderer(room.clone(), &view, &options).render(options.frames).expect("render")
    };
    let (dda, occupancy) = (frame("dda"), frame("occupancy"));
    let mean = dda.pixels.iter().map(|p| luminance([p[0], p[1], p[2]]) as f64).sum::<f64>() / dda.pixels.len() as f64;
    let m = compare(&occupancy, &dda).unwrap();
    eprintln!("occupancy walk against the DDA: {m}, mean {mean:.5}");
    assert!(mean > 0.01, "the room is lit: mean luminance {mean}");
    assert!(m.relmse < 1e-4, "relMSE {} (mean {mean})", m.relmse);
    assert!(m.bias.abs() < 0.005 * mean, "bias {} of a mean {mean}", m.bias);
}
