//! The game's building rules driven headless (no window): actions on the targeted voxel, placing on the right
//! side of a face and never inside the player, the box brush, undo/redo bit for bit, and save/load in game.

use bevy::prelude::*;
use glowbrick::game::GameLogicPlugin;
use glowbrick::game::hud::StatusLine;
use glowbrick::game::interaction::{Brush, Hotbar, PlayerAction, Target};
use glowbrick::game::player::Player;
use glowbrick::game::save_load::{SaveAction, SavePath, backup_path};
use glowbrick::game::undo::HistoryAction;
use glowbrick::lights::plugin::LightsPlugin;
use glowbrick::world::events::{EditRequest, WorldEditPlugin};
use glowbrick::world::format::world_to_string;
use glowbrick::world::recipe::load_scene;
use glowbrick::world::{CameraView, Edit, VoxelWorld};
use std::path::PathBuf;

fn temp_path(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("glowbrick-game-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir.join("save.ron")
}

/// A headless game on the test room with a camera at `eye` looking along `dir`.
fn game(eye: Vec3, dir: Vec3, save: PathBuf) -> App {
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, WorldEditPlugin, LightsPlugin, GameLogicPlugin))
        .insert_resource(load_scene("test-room").unwrap())
        .insert_resource(SavePath(save));
    let view = CameraView { name: "test".into(), origin: eye.into(), direction: dir.into(), fov_deg: 60.0 };
    spawn_player(&mut app, &view);
    app
}

/// Puts the player's camera at `view` and runs one frame (the headless games of every test module).
pub(crate) fn spawn_player(app: &mut App, view: &CameraView) {
    app.world_mut().spawn((
        glowbrick::world::view_transform(view),
        Player::looking(view),
        Projection::Perspective(PerspectiveProjection::default()),
    ));
    app.update();
}

pub(crate) fn world(app: &App) -> &VoxelWorld {
    app.world().resource::<VoxelWorld>()
}

fn act(app: &mut App, action: PlayerAction) {
    app.world_mut().write_message(action);
    app.update();
}

fn aim(app: &mut App, eye: Vec3, dir: Vec3) {
    let view = CameraView { name: "aim".into(), origin: eye.into(), direction: dir.into(), fov_deg: 60.0 };
    let mut q = app.world_mut().query::<&mut Transform>();
    *q.single_mut(app.world_mut()).unwrap() = glowbrick::world::view_transform(&view);
    app.update();
}

/// Positions where two worlds differ.
fn differences(a: &VoxelWorld, b: &VoxelWorld) -> Vec<IVec3> {
    let s = a.grid.size().as_ivec3();
    let mut out = Vec::new();
    for z in 0..s.z {
        for y in 0..s.y {
            for x in 0..s.x {
                let p = IVec3::new(x, y, z);
                if a.grid.get(p) != b.grid.get(p) {
                    out.push(p);
                }
            }
        }
    }
    out
}

#[test]
fn break_and_place_change_exactly_the_targeted_voxel() {
    // Looking along -x at the red block (x 5..10, y 1..6, z 20..25) from inside the room.
    let mut app = game(Vec3::new(20.5, 3.5, 22.5), Vec3::NEG_X, temp_path("place"));
    let hit = app.world().resource::<Target>().0.expect("the red block is targeted");
    assert_eq!((hit.voxel, hit.face.normal()), (IVec3::new(10, 3, 22), IVec3::X));
    let before = world(&app).clone();
    act(&mut app, PlayerAction::Break);
    assert_eq!(differences(&before, world(&app)), vec![IVec3::new(10, 3, 22)]);
    assert_eq!(world(&app).grid.get(IVec3::new(10, 3, 22)), 0);

    // Next frame the voxel behind is targeted; placing puts the selected block back on its +x face.
    app.update();
    let hit = app.world().resource::<Target>().0.unwrap();
    assert_eq!(hit.voxel, IVec3::new(9, 3, 22));
    let selected = app.world().resource::<Hotbar>().material();
    act(&mut app, PlayerAction::Place);
    assert_eq!(world(&app).grid.get(IVec3::new(10, 3, 22)), selected);
    assert_eq!(differences(&before, world(&app)).len(), (selected != before.grid.get(IVec3::new(10, 3, 22))) as usize);
}

#[test]
fn placing_goes_on_the_targeted_side_and_never_into_the_player() {
    // Each case: eye, direction, expected placed voxel (the air cell in front of the hit face).
    let cases = [
        (Vec3::new(8.5, 12.5, 22.5), Vec3::NEG_Y, IVec3::new(8, 7, 22)), // top of the red block
        (Vec3::new(2.5, 3.5, 22.5), Vec3::X, IVec3::new(4, 3, 22)),      // red block's -x face
        (Vec3::new(8.5, 3.5, 29.5), Vec3::NEG_Z, IVec3::new(8, 3, 26)),  // red block's +z face
    ];
    for (i, (eye, dir, expected)) in cases.into_iter().enumerate() {
        let mut app = game(eye, dir, temp_path(&format!("side{i}")));
        let before = world(&app).clone();
        act(&mut app, PlayerAction::Place);
        assert_eq!(differences(&before, world(&app)), vec![expected], "case {i}");
    }
    // Looking straight down at the floor from just above it: the cell in front of the face holds the player.
    let mut app = game(Vec3::new(16.5, 1.3, 16.5), Vec3::NEG_Y, temp_path("inside"));
    assert_eq!(app.world().resource::<Target>().0.unwrap().voxel, IVec3::new(16, 0, 16));
    let before = world(&app).clone();
    act(&mut app, PlayerAction::Place);
    assert!(differences(&before, world(&app)).is_empty(), "placing inside the player is refused");
}

#[test]
fn box_brush_fills_between_two_clicked_corners() {
    let mut app = game(Vec3::new(16.5, 12.5, 16.5), Vec3::NEG_Y, temp_path("brush"));
    *app.world_mut().resource_mut::<Brush>() = Brush::Box { first_corner: None };
    app.world_mut().resource_mut::<Hotbar>().slots[0] = 3; // red
    app.world_mut().resource_mut::<Hotbar>().selected = 0;
    let before = world(&app).clone();
    act(&mut app, PlayerAction::Place); // first corner: (16, 1, 16), on the floor
    assert_eq!(*app.world().resource::<Brush>(), Brush::Box { first_corner: Some(IVec3::new(16, 1, 16)) });
    aim(&mut app, Vec3::new(19.5, 12.5, 14.5), Vec3::NEG_Y);
    act(&mut app, PlayerAction::Place); // second corner: (19, 1, 14)
    let changed = differences(&before, world(&app));
    assert_eq!(changed.len(), 4 * 3, "a 4 x 1 x 3 box: {changed:?}");
    assert!(changed.iter().all(|p| world(&app).grid.get(*p) == 3 && p.y == 1));
}

#[test]
fn undo_and_redo_restore_the_world_bit_for_bit() {
    let mut app = game(Vec3::new(20.5, 3.5, 22.5), Vec3::NEG_X, temp_path("undo"));
    let start = world_to_string(world(&app));
    act(&mut app, PlayerAction::Break);
    act(&mut app, PlayerAction::Break);
    app.world_mut().write_message(EditRequest::player(Edit::FillBox {
        min: IVec3::new(2, 1, 2),
        max: IVec3::new(29, 13, 18),
        material: 4,
    }));
    app.update();
    act(&mut app, PlayerAction::Place);
    let end = world_to_string(world(&app));
    assert_ne!(start, end);
    for _ in 0..4 {
        app.world_mut().write_message(HistoryAction::Undo);
        app.update();
    }
    assert_eq!(world_to_string(world(&app)), start, "four undos give back the starting world");
    app.world_mut().write_message(HistoryAction::Undo);
    app.update();
    assert_eq!(world_to_string(world(&app)), start, "undo with an empty history changes nothing");
    for _ in 0..4 {
        app.world_mut().write_message(HistoryAction::Redo);
        app.update();
    }
    assert_eq!(world_to_string(world(&app)), end, "four redos give back the edited world");
    // The light pool followed every step: it equals a rescan.
    let pool = app.world().resource::<glowbrick::lights::LightPool>();
    assert_eq!(pool.counts(), glowbrick::lights::LightPool::from_world(world(&app)).counts());
}

#[test]
fn save_then_load_gives_the_same_world_and_a_bad_load_changes_nothing() {
    let path = temp_path("save");
    let mut app = game(Vec3::new(20.5, 3.5, 22.5), Vec3::NEG_X, path.clone());
    act(&mut app, PlayerAction::Break);
    app.world_mut().write_message(SaveAction::Save);
    app.update();
    let saved = world_to_string(world(&app));
    assert!(!backup_path(&path).exists(), "no backup of a first save");
    // Keep building, save again: the first save becomes the backup.
    act(&mut app, PlayerAction::Break);
    let first_file = std::fs::read_to_string(&path).unwrap();
    app.world_mut().write_message(SaveAction::Save);
    app.update();
    assert_eq!(std::fs::read_to_string(backup_path(&path)).unwrap(), first_file);
    let second = world_to_string(world(&app));
    act(&mut app, PlayerAction::Break);
    app.world_mut().write_message(SaveAction::Load);
    app.update();
    assert_eq!(world_to_string(world(&app)), second, "loading gives back the saved world");
    assert_ne!(saved, second);

    // A corrupt save: the load fails, the world and the file stay as they are, and the HUD says why.
    std::fs::write(&path, "(format: \"glowbrick-world\", version: 1, size: (16, 16").unwrap();
    act(&mut app, PlayerAction::Break);
    let current = world_to_string(world(&app));
    app.world_mut().write_message(SaveAction::Load);
    app.update();
    assert_eq!(world_to_string(world(&app)), current);
    assert!(app.world().resource::<StatusLine>().text.starts_with("load failed, world unchanged"));
    assert_eq!(std::fs::read_to_string(&path).unwrap(), "(format: \"glowbrick-world\", version: 1, size: (16, 16");
}

#[test]
fn a_64_cubed_fill_marks_exactly_the_touched_bricks_dirty() {
    let mut app = game(Vec3::new(20.5, 3.5, 22.5), Vec3::NEG_X, temp_path("fill"));
    let big = VoxelWorld::new(UVec3::splat(128), load_scene("test-room").unwrap().palette);
    app.insert_resource(big);
    app.update();
    app.world_mut().resource_mut::<VoxelWorld>().grid.take_dirty();
    app.world_mut().write_message(EditRequest::player(Edit::FillBox {
        min: IVec3::new(4, 4, 4),
        max: IVec3::new(67, 67, 67),
        material: 4,
    }));
    let start = std::time::Instant::now();
    app.update();
    eprintln!("64^3 fill frame: {:?}", start.elapsed());
    let dirty = app.world_mut().resource_mut::<VoxelWorld>().grid.take_dirty();
    // 4..=67 spans bricks 0..=8 on each axis.
    assert_eq!(dirty.len(), 9 * 9 * 9);
    assert_eq!(world(&app).summary().voxels, 64 * 64 * 64);
}

#[test]
fn walking_falls_onto_the_floor_and_walls_stop_it() {
    use glowbrick::game::player::{EYE_HEIGHT, move_with_collision};
    let room = load_scene("test-room").unwrap();
    // Dropping from 5 voxels above the floor (whose top is y = 1): the feet stop on it.
    let eye = Vec3::new(16.5, 6.0 + EYE_HEIGHT, 16.5);
    let (landed, blocked) = move_with_collision(&room, eye, Vec3::new(0.0, -20.0, 0.0));
    assert!(blocked.y && !blocked.x && !blocked.z);
    assert!((landed.y - EYE_HEIGHT - 1.0).abs() < 0.01, "feet at {}", landed.y - EYE_HEIGHT);
    // Walking 20 voxels towards -x runs into the wall (x 0..1): the body's side stops before x = 1.
    let (stopped, blocked) =
        move_with_collision(&room, Vec3::new(16.5, 1.0 + EYE_HEIGHT, 16.5), Vec3::new(-20.0, 0.0, 0.0));
    assert!(blocked.x);
    assert!(stopped.x - 0.3 >= 1.0 && stopped.x - 0.3 < 1.01, "stopped at x = {}", stopped.x);
}

#[test]
fn a_vox_model_drops_in_front_of_the_player_as_one_undoable_edit() {
    use glowbrick::game::models::{ModelToPlace, PlaceModel};
    use glowbrick::world::import::vox::parse_vox;
    let bytes = std::fs::read(concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/vox/ship.vox")).unwrap();
    let model = ModelToPlace::from_vox("ship", &parse_vox(&bytes).unwrap()).unwrap();
    let mut app = game(Vec3::new(32.5, 40.0, 32.5), Vec3::NEG_Y, temp_path("model"));
    let mut big = VoxelWorld::new(UVec3::splat(64), load_scene("test-room").unwrap().palette);
    big.apply(Edit::FillBox { min: IVec3::ZERO, max: IVec3::new(63, 0, 63), material: 1 }).unwrap();
    app.insert_resource(big).insert_resource(model);
    app.update();
    let before = world(&app).clone();
    let voxels_before = world(&app).summary().voxels;
    app.world_mut().write_message(PlaceModel);
    app.update();
    // The ship's 410 voxels stand on the floor, centred under the crosshair.
    assert_eq!(world(&app).summary().voxels, voxels_before + 410);
    assert!(world(&app).grid.get(IVec3::new(32, 0, 32)) == 1, "the floor is untouched");
    app.world_mut().write_message(HistoryAction::Undo);
    app.update();
    // Undo removes the whole model in one step (its colours stay in the palette, unused).
    assert!(differences(&before, world(&app)).is_empty());
}
