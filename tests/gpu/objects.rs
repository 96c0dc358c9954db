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
