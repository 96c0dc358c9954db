//! The GPU primary-ray pass against the CPU traversal, per pixel, on any adapter (lavapipe in CI).
//!
//! The pass runs with `debug=hit`, which writes `(voxel.x, voxel.y, voxel.z, face + 1)` (exact in f16), and the
//! CPU traces the same camera rays. Tolerance: at most 0.5% of pixels may differ, and only where the two disagree
//! about a ray through a voxel edge or corner (the hit voxels are neighbours) or grazing a silhouette.
//! With `GLOWBRICK_REQUIRE_GPU=1` a missing adapter fails the test; otherwise it is reported ignored (main.rs).

use crate::common;

use bevy::math::{UVec2, UVec3};
use common::compare_hits;
use glowbrick::headless::HeadlessOptions;
use glowbrick::image_io::LinearImage;
use glowbrick::settings::RenderSettings;
use glowbrick::world::scene::{generated_world, load_scene};
use glowbrick::world::{CameraView, VoxelWorld, trace};
use glowbrick::world::{camera_ray, view_transform, world_from_clip};

fn render(world: VoxelWorld, view: &CameraView, settings: RenderSettings, w: u32, h: u32) -> LinearImage {
    let options = HeadlessOptions { width: w, height: h, frames: 2, settings, ..Default::default() };
    common::renderer(world, view, &options).render(options.frames).expect("render")
}

pub fn gpu_primary_rays_match_cpu_traversal() {
    let hit_view = RenderSettings::default().with_pairs(&["debug=hit".to_string()]).unwrap();
    let room = load_scene("test-room").unwrap();
    let terrain = generated_world(9, UVec3::new(64, 40, 64)).unwrap();
    let cases = [
        ("test-room inside", room.clone(), room.view(Some("inside")).unwrap().clone()),
        ("test-room top", room.clone(), room.view(Some("top")).unwrap().clone()),
        ("terrain overview", terrain.clone(), terrain.overview()),
    ];
    for (name, world, view) in cases {
        let gpu = render(world.clone(), &view, hit_view.clone(), 96, 64);
        let c = compare_hits(&world, &view, &gpu);
        eprintln!("{name}: {} pixels, {} hits, {} mismatches", c.pixels, c.hits, c.mismatches);
        assert!(c.hits * 3 > c.pixels, "{name}: the view should mostly hit voxels ({} of {})", c.hits, c.pixels);
        assert!(c.mismatches * 200 <= c.pixels, "{name}: {} of {} pixels differ", c.mismatches, c.pixels);
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
