//! Moving objects saved with the world: the loaded world shows them where the saved one had them.

use super::common;
use bevy::prelude::*;
use glowbrick::dynamic::saved::saved_objects;
use glowbrick::dynamic::{DynamicObject, Motion, model_for_world, spawn_object_in};
use glowbrick::world::format::{parse_world, world_to_string};
use glowbrick::world::palette::Palette;
use glowbrick::world::{CameraView, Edit, VoxelWorld};
use std::sync::Arc;

/// A floor and a back wall, a camera looking at both.
fn stage() -> (VoxelWorld, CameraView) {
    let mut world = VoxelWorld::new(UVec3::new(32, 24, 32), Palette::default_blocks());
    world.apply(Edit::FillBox { min: IVec3::ZERO, max: IVec3::new(31, 0, 31), material: 1 }).unwrap();
    world.apply(Edit::FillBox { min: IVec3::new(0, 1, 31), max: IVec3::new(31, 23, 31), material: 1 }).unwrap();
    let view =
        CameraView { name: "stage".into(), origin: [16.0, 10.0, 2.0], direction: [0.0, -0.2, 1.0], fov_deg: 60.0 };
    (world, view)
}

pub fn a_saved_world_shows_its_moving_objects_where_they_were() {
    let (mut world, view) = stage();
    let lantern = Arc::new(model_for_world("lantern", &mut world).unwrap());
    let block = Arc::new(model_for_world("block", &mut world).unwrap());
    // Albedo is deterministic: the two renders must agree voxel for voxel, not within noise.
    let pairs = ["lighting=nee", "debug=albedo"];
    let mut playing = common::renderer_with(&world, &view, 96, 64, &pairs);
    let app = playing.app_mut().world_mut();
    spawn_object_in(app, lantern, Motion::Drift { radius: 4.0, period: 3.0 }, Vec3::new(14.0, 6.0, 18.0)).unwrap();
    let swing = Motion::Swing { length: 6.0, amplitude: 0.8, period: 2.0 };
    spawn_object_in(app, block, swing, Vec3::new(20.0, 16.0, 20.0)).unwrap();
    playing.render(37).unwrap();

    // Save as F5 does: the world resource (with the models' materials) and the live objects at their phase.
    let app = playing.app_mut().world_mut();
    let mut file = app.resource::<VoxelWorld>().clone();
    let mut query = app.query::<&DynamicObject>();
    file.objects = Some(saved_objects(query.iter(app)));
    let ages: Vec<f32> = file.objects.as_ref().unwrap().iter().map(|o| o.age).collect();
    assert_eq!(ages.len(), 2);
    assert!(ages.iter().all(|&a| a > 0.5), "the objects have moved before the save: ages {ages:?}");
    let loaded = parse_world(&world_to_string(&file), "saved.ron").unwrap();

    // The next frame of the running game and the first frame of the loaded world: both advance one step.
    let continued = playing.render(1).unwrap();
    let mut restored = common::renderer_with(&loaded, &view, 96, 64, &pairs);
    let first = restored.render(1).unwrap();
    let mut without = loaded.clone();
    without.objects = Some(Vec::new());
    let empty = common::renderer_with(&without, &view, 96, 64, &pairs).render(1).unwrap();

    let differing = |a: &glowbrick::image_io::LinearImage, b: &glowbrick::image_io::LinearImage| {
        let apart = |p: &[f32; 4], q: &[f32; 4]| p.iter().zip(q).any(|(x, y)| (x - y).abs() > 1e-4);
        a.pixels.iter().zip(&b.pixels).filter(|(p, q)| apart(p, q)).count()
    };
    let objects_cover = differing(&continued, &empty);
    eprintln!("pixels the objects cover: {objects_cover}; differing after load: {}", differing(&continued, &first));
    assert!(objects_cover > 40, "the objects are in view ({objects_cover} pixels)");
    assert_eq!(differing(&continued, &first), 0, "the loaded world shows the objects where the saved one did");
}

/// A MagicaVoxel scene's emissive material joins the light pool: Voxel ReSTIR lights the slab under the lamp.
pub fn a_magicavoxel_lamp_lights_its_scene_under_restir() {
    use glowbrick::world::import::vox::{parse_vox, vox_world};
    let mut file = parse_vox(&super::vox_scene::scene_graph_vox()).unwrap();
    let lit = vox_world(&file).unwrap();
    file.emissive.clear();
    let dark = vox_world(&file).unwrap();
    // From above and to the side, looking down at the slab and the lamp over it.
    let view =
        CameraView { name: "above".into(), origin: [3.0, 9.0, -4.0], direction: [0.0, -0.8, 1.0], fov_deg: 60.0 };
    let pairs = ["lighting=emitters", "accumulate=on"];
    let lit_image = common::renderer_with(&lit, &view, 96, 64, &pairs).render(16).unwrap();
    let dark_image = common::renderer_with(&dark, &view, 96, 64, &pairs).render(16).unwrap();
    // The slab's pixels: its albedo is grey (colour 200, 200, 200), the lamp's warm, the sky's none.
    let albedo = common::renderer_with(&lit, &view, 96, 64, &["debug=albedo"]).render(1).unwrap();
    let slab: Vec<usize> = (0..albedo.pixels.len())
        .filter(|&i| {
            let [r, g, b, _] = albedo.pixels[i];
            r > 0.3 && (r - g).abs() < 1e-3 && (r - b).abs() < 1e-3
        })
        .collect();
    let lum = |p: &[f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let mean = |img: &glowbrick::image_io::LinearImage| {
        slab.iter().map(|&i| lum(&img.pixels[i]) as f64).sum::<f64>() / slab.len().max(1) as f64
    };
    let (with_lamp, without) = (mean(&lit_image), mean(&dark_image));
    eprintln!("slab pixels {}: mean luminance with the lamp {with_lamp:.4}, without {without:.4}", slab.len());
    assert!(slab.len() > 200, "the slab is in view: {} pixels", slab.len());
    assert!(without < 1e-6, "without emission nothing lights the slab: {without}");
    assert!(with_lamp > 0.01, "the lamp lights the slab: {with_lamp}");
    assert!(lit_image.non_finite_pixels() == 0);
}
