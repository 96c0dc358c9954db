//! Lighting=full on the CPU: the reference integrates the sun's disk and the sky exactly where the answer is
//! known; the time of day is a setting, is saved with a world and old files without it still load.

use bevy::math::{IVec3, UVec3, Vec3};
use glowbrick::lights::daylight::Daylight;
use glowbrick::reference::objects::ReferenceObjects;
use glowbrick::reference::sampling::Pcg;
use glowbrick::reference::{ReferenceLights, ReferenceOptions, Scene, SurfaceHit, render_reference};
use glowbrick::settings::{Lighting, RenderSettings};
use glowbrick::world::format::{parse_world, world_to_string};
use glowbrick::world::{CameraView, Edit, Material, Palette, VoxelWorld};

const ALBEDO: f32 = 0.6;

/// A 64 x 64 floor (top at y = 1) under nothing.
fn bare_floor() -> VoxelWorld {
    let palette = Palette::new(vec![Material::solid("floor", [ALBEDO; 3])]);
    let mut world = VoxelWorld::new(UVec3::new(64, 32, 64), palette);
    world.apply(Edit::FillBox { min: IVec3::ZERO, max: IVec3::new(63, 0, 63), material: 1 }).unwrap();
    world
}

/// The floor with a 4 x 20 x 4 pillar in its middle.
fn open_floor() -> VoxelWorld {
    let mut world = bare_floor();
    world.apply(Edit::FillBox { min: IVec3::new(30, 1, 30), max: IVec3::new(33, 20, 33), material: 1 }).unwrap();
    world
}

/// A sky of one radiance everywhere and a disk straight overhead.
fn uniform_sky(sky: f32, disk: f32) -> Daylight {
    let mut day = Daylight::at(12.0, true);
    day.direction = Vec3::Y;
    day.disk = Vec3::splat(disk);
    day.zenith = Vec3::splat(sky);
    day.horizon = Vec3::splat(sky);
    day
}

fn floor_hit(x: f32, z: f32) -> SurfaceHit {
    SurfaceHit {
        position: Vec3::new(x, 1.0, z),
        normal: Vec3::Y,
        albedo: [ALBEDO; 3],
        emission: Vec3::ZERO,
        on_object: false,
    }
}

#[test]
fn an_open_floor_reflects_exactly_the_sky_and_the_disk() {
    let (bare, world) = (bare_floor(), open_floor());
    // No lamps: the reference lights are the sun, the moon and the sky alone.
    let (lights, no_objects) = (ReferenceLights::of(&world), ReferenceObjects::default());
    assert!(lights.pool.is_empty());
    let open = Scene::new(&bare, &lights, &no_objects);
    let scene = Scene::new(&world, &lights, &no_objects);
    let options = ReferenceOptions { daylight: Some(uniform_sky(0.5, 2.0)), bounces: 0, ..Default::default() };
    // In the open, every cosine ray leaves the world and the disk is unoccluded: each sample is exact,
    // albedo x (sky + disk x cos), with cos within the disk's tiny cone of 1.
    let mut rng = Pcg::new(3, 0);
    let mut rays = 0;
    for _ in 0..200 {
        let value = open.path_sample(&floor_hit(8.5, 8.5), &options, &mut rng, &mut rays);
        assert!((value.x - ALBEDO * (0.5 + 2.0)).abs() < 1e-4, "{value}");
    }
    // Right beside the pillar the disk overhead is unoccluded, but the pillar hides nearly half of the sky
    // (an infinite wall would hide exactly half of the cosine-weighted sky).
    let mut beside = Vec3::ZERO;
    for _ in 0..4000 {
        beside += scene.path_sample(&floor_hit(29.5, 31.5), &options, &mut rng, &mut rays);
    }
    let beside = beside.x / 4000.0;
    assert!(beside < ALBEDO * 2.4 && beside > ALBEDO * 2.05, "{beside}");
    // With bounces the sky is still counted once at each vertex: in the open the value stays exact.
    let bounced = ReferenceOptions { bounces: 2, ..options.clone() };
    for _ in 0..50 {
        let value = open.path_sample(&floor_hit(4.5, 60.5), &bounced, &mut rng, &mut rays);
        assert!((value.x - ALBEDO * 2.5).abs() < 1e-4, "{value}");
    }
    // Emitters only: nothing lights this world.
    let dark = ReferenceOptions { daylight: None, ..options };
    assert_eq!(open.path_sample(&floor_hit(8.5, 8.5), &dark, &mut rng, &mut rays), Vec3::ZERO);
}

#[test]
fn the_reference_image_shows_the_floor_and_the_pillars_shadow() {
    let world = open_floor();
    let mut day = uniform_sky(0.25, 1.0);
    // The sun 45 degrees up from +X: the pillar's 20-voxel-tall, 4-wide shadow falls 20 voxels towards -X.
    day.direction = Vec3::new(1.0, 1.0, 0.0).normalize();
    let view =
        CameraView { name: "down".into(), origin: [32.0, 30.0, 32.0], direction: [0.0, -1.0, 0.0001], fov_deg: 90.0 };
    let options = ReferenceOptions { width: 64, height: 64, spp: 64, daylight: Some(day), ..Default::default() };
    let image = render_reference(&world, &view, &options).unwrap().image;
    let lum = |p: &[f32; 4]| p[1];
    // Open floor far from the pillar: albedo x (sky + disk x cos 45), less the sliver of sky the distant pillar
    // hides (under 1%).
    let open = ALBEDO * (0.25 + std::f32::consts::FRAC_1_SQRT_2);
    for (x, y) in [(2, 2), (61, 2), (2, 61), (61, 61)] {
        let value = lum(&image.pixel(x, y));
        assert!((value - open).abs() < 0.01 * open, "open floor at pixel ({x}, {y}): {value} vs {open}");
    }
    // The shadow: sky light only (about 80 voxels of floor, 1.2 pixels each).
    let shadowed: Vec<f32> = image.pixels.iter().map(lum).filter(|&l| l < ALBEDO * 0.3).collect();
    assert!((50..=150).contains(&shadowed.len()), "{} shadow pixels", shadowed.len());
    let darkest = shadowed.iter().cloned().fold(f32::MAX, f32::min);
    assert!(darkest > ALBEDO * 0.1, "the shadow keeps the sky's light: {darkest}");
    // The same view with emitters only is black.
    let dark = render_reference(&world, &view, &ReferenceOptions { daylight: None, ..options }).unwrap().image;
    assert!(dark.pixels.iter().all(|p| p[0] == 0.0 && p[1] == 0.0 && p[2] == 0.0));
}

#[test]
fn a_camera_ray_into_the_sky_sees_the_sky_and_the_disk() {
    let world = open_floor();
    let day = Daylight::at(12.0, true);
    let up = CameraView { name: "up".into(), origin: [5.0, 5.0, 5.0], direction: day.direction.into(), fov_deg: 2.0 };
    let options = ReferenceOptions { width: 9, height: 9, spp: 1, daylight: Some(day), ..Default::default() };
    let image = render_reference(&world, &up, &options).unwrap().image;
    let centre = Vec3::from_slice(&image.pixel(4, 4)[..3]);
    let expected = day.sky(day.direction) + day.disk / (2.0 * day.cone);
    assert!((centre - expected).abs().max_element() < 1e-2 * expected.max_element(), "{centre} vs {expected}");
    // The corner pixel, a degree off the sun, is outside its 0.7 degree disk: sky only.
    let corner = Vec3::from_slice(&image.pixel(0, 0)[..3]);
    assert!(corner.max_element() < 1.0, "{corner}");
}

#[test]
fn time_is_a_setting_with_a_range_and_the_lighting_names_are_stable() {
    let s = RenderSettings::default();
    assert_eq!((s.lighting, s.time), (Lighting::Full, 10.0));
    let dusk = s.clone().with_pairs(&["time=17.5".to_string()]).unwrap();
    assert_eq!(dusk.time, 17.5);
    assert_eq!(dusk.daylight(), Some(Daylight::at(17.5, true)));
    for bad in ["time=25", "time=-1", "time=NaN", "time=dusk"] {
        let e = s.clone().with_pairs(&[bad.to_string()]).unwrap_err();
        assert!(e.starts_with("setting time: ") && e.contains("0..24"), "{bad}: {e}");
    }
    let emitters = s.clone().with_pairs(&["lighting=emitters".to_string()]).unwrap();
    assert_eq!(emitters.daylight(), None);
    let old_name = s.with_pairs(&["lighting=restir".to_string()]).unwrap();
    assert_eq!(old_name.lighting, Lighting::Emitters);
}

#[test]
fn a_world_keeps_its_time_of_day_and_old_files_load_without_one() {
    let mut world = open_floor();
    let old = world_to_string(&world);
    assert!(!old.contains("time_of_day"), "a world without a time writes none (files stay as they were)");
    assert_eq!(parse_world(&old, "old.ron").unwrap().time_of_day, None);
    world.time_of_day = Some(19.25);
    let text = world_to_string(&world);
    let loaded = parse_world(&text, "new.ron").unwrap();
    assert_eq!(loaded.time_of_day, Some(19.25));
    assert_eq!(RenderSettings::default().with_world_time(&loaded).time, 19.25);
    for (bad, shown) in [("Some(24.5)", "24.5"), ("Some(-3)", "-3"), ("Some(inf)", "inf"), ("Some(NaN)", "NaN")] {
        let hostile = text.replace("Some(19.25)", bad);
        let e = parse_world(&hostile, "bad.ron").unwrap_err().to_string();
        assert!(e.contains(&format!("time_of_day {shown} must be within 0..24 hours")), "{bad}: {e}");
    }
}

#[test]
fn the_clock_steps_an_hour_and_wraps_at_midnight() {
    use glowbrick::game::step_clock;
    assert_eq!(step_clock(10.0, 1.0), 11.0);
    assert_eq!(step_clock(23.5, 1.0), 0.5);
    assert_eq!(step_clock(0.0, -1.0), 23.0);
    assert_eq!(step_clock(24.0, 0.0), 0.0);
}
