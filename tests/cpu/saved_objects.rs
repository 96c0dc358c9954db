//! Moving objects in world files: they round-trip with their phase, old files load without them, hostile entries
//! are one error line, and a loaded world spawns each object where it was saved.

use bevy::prelude::*;
use glowbrick::dynamic::saved::{saved_objects, spawn_saved};
use glowbrick::dynamic::{BUILTIN_MODELS, DynamicObject, Motion, ObjectClock};
use glowbrick::world::format::{parse_world, world_to_string};
use glowbrick::world::objects::{MODEL_NAMES, SavedMotion, SavedObject};
use glowbrick::world::palette::Palette;
use glowbrick::world::{Edit, VoxelWorld};

fn floor_world() -> VoxelWorld {
    let mut world = VoxelWorld::new(UVec3::new(32, 16, 32), Palette::default_blocks());
    world.apply(Edit::FillBox { min: IVec3::ZERO, max: IVec3::new(31, 0, 31), material: 1 }).unwrap();
    world
}

fn lantern(age: f32) -> SavedObject {
    SavedObject {
        model: "lantern".into(),
        motion: SavedMotion::Drift { radius: 5.0, period: 12.0 },
        anchor: (12.0, 6.0, 14.0),
        age,
    }
}

fn swinging_block() -> SavedObject {
    SavedObject {
        model: "block".into(),
        motion: SavedMotion::Swing { length: 4.0, amplitude: 0.7, period: 5.0 },
        anchor: (20.0, 12.0, 16.0),
        age: 1.25,
    }
}

#[test]
fn the_model_names_a_file_may_use_are_the_built_in_models() {
    let builtin: Vec<&str> = BUILTIN_MODELS.iter().map(|(n, _)| *n).collect();
    assert_eq!(builtin, MODEL_NAMES);
}

#[test]
fn objects_round_trip_with_their_phase_and_old_files_load_without_them() {
    let mut world = floor_world();
    let old = world_to_string(&world);
    assert!(!old.contains("objects"), "a world without objects writes no objects field");
    assert_eq!(parse_world(&old, "old.ron").unwrap().objects, None);
    world.objects = Some(vec![lantern(3.5), swinging_block()]);
    let text = world_to_string(&world);
    let loaded = parse_world(&text, "new.ron").unwrap();
    assert_eq!(loaded.objects, world.objects);
    // An explicit empty list stays empty (a player who has no objects left gets none back, not the defaults).
    world.objects = Some(Vec::new());
    assert_eq!(parse_world(&world_to_string(&world), "empty.ron").unwrap().objects, Some(Vec::new()));
}

#[test]
fn hostile_object_entries_are_one_error_line() {
    let mut world = floor_world();
    world.objects = Some(vec![lantern(3.5)]);
    let text = world_to_string(&world);
    let cases: [(&str, &str, &str); 7] = [
        ("\"lantern\"", "\"dragon\"", "objects[0]: model 'dragon' is not a built-in model (lantern, block)"),
        ("period: 12.0", "period: 1e-30", "objects[0]: period 0.000000000000000000000000000001 must be within"),
        ("period: 12.0", "period: inf", "objects[0]: period inf must be within"),
        ("age: 3.5", "age: NaN", "objects[0]: age NaN must be within"),
        ("age: 3.5", "age: -1", "objects[0]: age -1 must be within"),
        ("radius: 5.0", "radius: 1e9", "objects[0]: radius 1000000000 must be within +-32"),
        (
            "anchor: (12.0, 6.0, 14.0)",
            "anchor: (1e7, 6.0, 14.0)",
            "objects[0]: anchor (10000000.0, 6.0, 14.0) is outside",
        ),
    ];
    for (from, to, expected) in cases {
        assert!(text.contains(from), "{from} not in {text}");
        let hostile = text.replace(from, to);
        let e = parse_world(&hostile, "bad.ron").unwrap_err().to_string();
        assert!(e.contains(expected), "{to}: {e}");
        assert!(!e.contains('\n'), "{to}: one line: {e}");
    }
    let many = format!(
        "objects: Some([{}])",
        vec!["(model: \"block\", motion: Still, anchor: (1, 1, 1), age: 0)"; 65].join(", ")
    );
    let start = text.find("objects: Some([").unwrap();
    let end = start + text[start..].find("])").unwrap() + 2;
    let e = parse_world(&format!("{}{many}{}", &text[..start], &text[end..]), "many.ron").unwrap_err().to_string();
    assert!(e.contains("65 objects, the most a world holds is 64"), "{e}");
}

#[test]
fn a_loaded_world_spawns_each_object_where_it_was_saved() {
    let mut app = App::new();
    app.init_resource::<ObjectClock>().insert_resource(floor_world());
    let saved = vec![lantern(3.5), swinging_block()];
    spawn_saved(app.world_mut(), &saved).unwrap();
    let mut query = app.world_mut().query::<(&DynamicObject, &Transform)>();
    let live: Vec<(DynamicObject, Transform)> = query.iter(app.world()).map(|(o, t)| (o.clone(), *t)).collect();
    assert_eq!(live.len(), 2);
    for (object, transform) in &live {
        let expected = object.anchor + object.motion.offset(object.age);
        assert!(transform.translation.distance(expected) < 1e-5, "{} at {}", object.model.name, transform.translation);
    }
    let lantern_live = live.iter().find(|(o, _)| o.model.name == "lantern").unwrap();
    assert_eq!(lantern_live.0.age, 3.5);
    assert_eq!(lantern_live.0.motion, Motion::Drift { radius: 5.0, period: 12.0 });
    // Saving the spawned objects gives back what was loaded.
    assert_eq!(saved_objects(live.iter().map(|(o, _)| o)), saved);
}

#[test]
fn the_player_cannot_walk_through_a_moving_object_and_aims_at_it() {
    use glowbrick::dynamic::{PlacedModel, model_for_world};
    use glowbrick::game::interaction::{Aim, aim};
    use glowbrick::game::player::{BODY_HALF, EYE_HEIGHT, move_among_objects, move_with_collision};
    let mut world = floor_world();
    let block = model_for_world("block", &mut world).unwrap();
    // A 3x3x3 block standing on the floor at x 20..23, in the player's path along +x.
    let placed = PlacedModel { model: &block, min: Vec3::new(20.0, 1.0, 15.0) };
    let eye = Vec3::new(10.5, 1.0 + EYE_HEIGHT, 16.5);
    let walk = Vec3::new(15.0, 0.0, 0.0);
    let (free, free_blocked) = move_with_collision(&world, eye, walk);
    assert!(!free_blocked.x && (free.x - 25.5).abs() < 1e-3, "nothing stops the walk without the object: {free}");
    let (stopped, blocked) = move_among_objects(&world, &[placed], eye, walk);
    assert!(blocked.x, "the object blocks the walk");
    let front = stopped.x + BODY_HALF.x;
    assert!(front <= 20.0 + 1e-3 && front > 19.9, "the body rests against the object's face: front at {front}");
    // Once the object has moved into the player, the player can step out of it.
    let inside = PlacedModel { model: &block, min: Vec3::new(10.0, 1.0, 15.0) };
    let (out, out_blocked) = move_among_objects(&world, &[inside], eye, Vec3::new(-5.0, 0.0, 0.0));
    assert!(!out_blocked.x && out.x < 6.0, "stepping out of an object that moved into the player: {out}");

    // The crosshair at chest height along +x meets the object's face at x = 20, not the floor or the world edge.
    let chest = Vec3::new(10.5, 2.5, 16.5);
    match aim(&world, &[placed], chest, Vec3::X) {
        Aim::Object(0, distance) => assert!((distance - 9.5).abs() < 0.05, "distance {distance}"),
        other => panic!("aimed at {other:?}"),
    }
    // Looking down in front of the object the floor is nearer: the voxel is the target.
    match aim(&world, &[placed], chest, Vec3::new(1.0, -1.0, 0.0).normalize()) {
        Aim::Voxel(hit) => assert_eq!(hit.voxel.y, 0, "{hit:?}"),
        other => panic!("aimed at {other:?}"),
    }
}

/// The CPU reference draws a saved lantern where its phase puts it: the camera sees its glowing core through a
/// gap in its frame, and the core (not in the light pool) lights the floor through the reference's
/// cosine-sampled rays. Without the lantern the world has no light at all.
#[test]
fn the_reference_draws_a_saved_lantern_and_its_light() {
    use glowbrick::reference::{ReferenceOptions, render_reference};
    use glowbrick::world::CameraView;
    let mut world = floor_world();
    let still = SavedObject { motion: SavedMotion::Still, ..lantern(0.0) };
    world.objects = Some(vec![still]);
    // The lantern's minimum corner is at (12, 6, 14): its core is the column x = 13, z = 15, y = 7..9, open to
    // -z through the frame's gap at z = 14. The camera looks at that gap along +z from eye height, and the floor
    // fills the lower half of the view.
    let view = CameraView { name: "gap".into(), origin: [13.5, 8.0, 2.0], direction: [0.0, 0.0, 1.0], fov_deg: 60.0 };
    let options = ReferenceOptions { width: 48, height: 32, spp: 64, bounces: 0, seed: 3, ..Default::default() };
    let lit = render_reference(&world, &view, &options).unwrap().image;
    let mut empty = world.clone();
    empty.objects = None;
    let dark = render_reference(&empty, &view, &options).unwrap().image;
    assert_eq!(dark.mean_luminance(), 0.0, "no light without the lantern");
    let lum = |p: [f32; 4]| 0.2126 * p[0] + 0.7152 * p[1] + 0.0722 * p[2];
    let lamp = world.palette.get(world.palette.id_of("lamp-warm").unwrap()).unwrap();
    let [r, g, b] = lamp.radiance();
    let core = lum([r, g, b, 1.0]);
    let centre = lum(lit.pixel(24, 16));
    let floor_lit = (0..48 * 10).filter(|i| lum(lit.pixel(i % 48, 31 - i / 48)) > 0.0).count();
    eprintln!(
        "centre {centre:.3} (core emission {core:.3}); lit floor pixels in the bottom 10 rows {floor_lit} of 480"
    );
    assert!((centre - core).abs() < 0.05 * core, "the camera sees the lantern's core: {centre} vs {core}");
    // Its light leaves through one-voxel gaps: a narrow band of the floor in line with the gap catches it.
    assert!(floor_lit >= 5, "the core lights the floor in front of the lantern: {floor_lit} pixels");
    assert!(lit.non_finite_pixels() == 0);
}
