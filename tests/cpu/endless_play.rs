//! The endless world played headless: the window follows the player, the light pool follows the window, an edit
//! survives its region leaving the window and coming back, F5 writes only the changed region, and F9 and a
//! restart bring the edit and the player back.

use super::game_building::{spawn_player, world};
use bevy::prelude::*;
use glowbrick::game::GameLogicPlugin;
use glowbrick::game::endless::{EndlessPlay, EndlessPlugin};
use glowbrick::game::player::Player;
use glowbrick::game::save_load::{SaveAction, SavePath};
use glowbrick::lights::LightPool;
use glowbrick::lights::plugin::LightsPlugin;
use glowbrick::net::state_hash::lights_hash;
use glowbrick::world::events::{EditRequest, WorldEditPlugin};
use glowbrick::world::generate::endless::{EndlessGenerator, REGION_EDGE};
use glowbrick::world::region_save::EndlessSave;
use glowbrick::world::{CameraView, Edit, VoxelWorld};
use std::path::PathBuf;
use std::time::{Duration, Instant};

const SEED: u32 = 5;
const HEIGHT: u32 = 64;

fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("glowbrick-endless-play-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    dir
}

fn game(folder: &std::path::Path) -> App {
    let save = EndlessSave::open_or_create(folder, SEED, HEIGHT).unwrap();
    let (play, world) = EndlessPlay::open(save, 2).unwrap();
    let view = world.view(None).unwrap().clone();
    let mut app = App::new();
    app.add_plugins((MinimalPlugins, WorldEditPlugin, LightsPlugin, GameLogicPlugin, EndlessPlugin))
        .insert_resource(world)
        .insert_resource(play)
        .insert_resource(SavePath(folder.to_path_buf()));
    spawn_player(&mut app, &view);
    app
}

fn player_at(app: &mut App) -> Vec3 {
    let mut q = app.world_mut().query_filtered::<&Transform, With<Player>>();
    q.single(app.world()).unwrap().translation
}

/// Moves the player to `to` (window coordinates) and plays until the window is centred on it and lit.
fn fly_to(app: &mut App, to: Vec3) {
    {
        let mut q = app.world_mut().query_filtered::<&mut Transform, With<Player>>();
        q.single_mut(app.world_mut()).unwrap().translation = to;
    }
    let start = Instant::now();
    loop {
        app.update();
        let (lo, hi) = world(app).grid.window();
        let centred = (to.x - (lo.x + hi.x) as f32 / 2.0).abs() < 2.0 * REGION_EDGE as f32
            && (to.z - (lo.z + hi.z) as f32 / 2.0).abs() < 2.0 * REGION_EDGE as f32
            && hi.x - lo.x == world(app).grid.size().x as i32;
        if centred && app.world().resource::<EndlessPlay>().lights_waiting() == 0 {
            return;
        }
        assert!(start.elapsed() < Duration::from_secs(120), "the window never reached {to} (it is {lo}..{hi})");
        std::thread::sleep(Duration::from_millis(2));
    }
}

fn pool_is_rebuilt_pool(app: &App) {
    let pool = app.world().resource::<LightPool>();
    assert_eq!(lights_hash(pool), lights_hash(&LightPool::from_world(world(app))), "incremental = rebuilt");
}

#[test]
fn an_edit_survives_leaving_the_window_f5_saves_only_its_region_and_f9_and_a_restart_bring_it_back() {
    let folder = scratch("round-trip");
    let mut app = game(&folder);
    let start = player_at(&mut app);
    // The game adds materials of its own (the moving objects'): region files still load as the generator's.
    {
        let mut world = app.world_mut().resource_mut::<VoxelWorld>();
        let mut glass = world.palette.materials[1].clone();
        glass.name = "lantern-glass".into();
        world.palette.materials.push(glass);
    }
    let lamp = world(&app).palette.id_of("lamp-warm").unwrap();
    let at = IVec3::new(start.x.floor() as i32, 3, start.z.floor() as i32);
    app.world_mut().write_message(EditRequest::player(Edit::Place { at, material: lamp }));
    app.update();
    assert_eq!(world(&app).grid.get(at), lamp);
    let window_before = world(&app).grid.window();

    // Twelve regions east: the edited region leaves the window, lamps and all, and the pool follows.
    let east = start + Vec3::X * (12 * REGION_EDGE) as f32;
    fly_to(&mut app, east);
    let window_east = world(&app).grid.window();
    assert!(window_east.0.x >= window_before.0.x + 8 * REGION_EDGE, "{window_before:?} -> {window_east:?}");
    assert!(!world(&app).grid.contains(at), "the edit's region left the window");
    pool_is_rebuilt_pool(&app);

    // F5 far from it: the one changed region is written, nothing else.
    app.world_mut().write_message(SaveAction::Save);
    app.update();
    let saved = EndlessSave::open(&folder).unwrap();
    assert_eq!(saved.saved_regions().len(), 1, "only the changed region is saved");
    let first_min = app.world().resource::<EndlessPlay>().window_min();
    let key = EndlessGenerator::region_of(at.x + first_min.x, at.z + first_min.y);
    assert_eq!(saved.saved_regions(), vec![key]);
    let size = std::fs::metadata(saved.region_path(key)).unwrap().len();
    assert!(size > 0 && size < 2_000_000, "a region file of {size} bytes");
    let player = saved.player.clone().expect("the player saved");
    assert!(player.0.x > key.x + 8, "the player saved where it stands, region {}", player.0);

    // Back west: the edited region comes back with the edit, not the generator's made again.
    fly_to(&mut app, start);
    assert_eq!(world(&app).grid.get(at), lamp, "the edit came back with its region");
    pool_is_rebuilt_pool(&app);

    // Change the region again without saving; F9 goes back to the save, where the lamp is and the player east.
    app.world_mut().write_message(EditRequest::player(Edit::Break { at }));
    app.update();
    assert_ne!(world(&app).grid.get(at), lamp);
    app.world_mut().write_message(SaveAction::Load);
    app.update();
    let back = player_at(&mut app);
    // The reopened window has a column (0, 0) of its own: the lamp's world position in its coordinates.
    let min = app.world().resource::<EndlessPlay>().window_min();
    let at_now = at + IVec3::new(first_min.x - min.x, 0, first_min.y - min.y);
    assert!(
        (back.x - (at_now.x as f32 + 12.0 * REGION_EDGE as f32)).abs() < REGION_EDGE as f32,
        "F9 puts the player back where F5 found it: {back}, the lamp at {at_now}"
    );
    fly_to(&mut app, at_now.as_vec3() + Vec3::new(0.5, 40.0, 0.5));
    assert_eq!(world(&app).grid.get(at_now), lamp, "F9 brings the saved edit back");

    // F5 beside the lamp writes no region (none changed since F9) but moves the saved player; a restart opens
    // the window around it, the lamp in it.
    let file = saved.region_path(key);
    let written = std::fs::metadata(&file).unwrap().modified().unwrap();
    app.world_mut().write_message(SaveAction::Save);
    app.update();
    assert_eq!(std::fs::metadata(&file).unwrap().modified().unwrap(), written, "an unchanged region is not rewritten");
    drop(app);
    let (play, restarted) = EndlessPlay::open(EndlessSave::open(&folder).unwrap(), 2).unwrap();
    let min = play.window_min();
    let at_restart = at + IVec3::new(first_min.x - min.x, 0, first_min.y - min.y);
    let view = Vec3::from(restarted.view(None).unwrap().origin);
    assert!((view - at_restart.as_vec3()).length() < 64.0, "the player back beside the lamp: {view}, {at_restart}");
    assert_eq!(restarted.grid.get(at_restart), lamp);
    let _ = std::fs::remove_dir_all(&folder);
}

#[test]
fn moving_objects_and_the_player_come_back_where_they_were_saved() {
    use glowbrick::game::endless::save_regions;
    use glowbrick::world::objects::{SavedMotion, SavedObject};
    let folder = scratch("objects");
    let save = EndlessSave::open_or_create(&folder, SEED, HEIGHT).unwrap();
    let (mut play, world) = EndlessPlay::open(save, 2).unwrap();
    assert_eq!(world.objects, None, "a new endless world gets the default objects");
    let view = world.view(None).unwrap().clone();
    let lantern = |anchor| SavedObject {
        model: "lantern".into(),
        motion: SavedMotion::Drift { radius: 5.0, period: 12.0 },
        anchor,
        age: 3.0,
    };
    let at = (view.origin[0] + 7.25, 50.5, view.origin[2] - 130.0);
    let min = play.window_min();
    let (regions, _) = save_regions(&mut play, &world, Some(view.clone()), Some(19.0), &[lantern(at)]).unwrap();
    assert_eq!(regions, 0, "nothing was edited");
    drop(play);
    let (play, reopened) = EndlessPlay::open(EndlessSave::open(&folder).unwrap(), 2).unwrap();
    assert_eq!(play.window_min(), min, "the same window around the same player");
    assert_eq!(reopened.time_of_day, Some(19.0));
    let back = Vec3::from(reopened.view(None).unwrap().origin);
    assert!((back - Vec3::from(view.origin)).length() < 1e-3, "{back} vs {:?}", view.origin);
    let objects = reopened.objects.clone().expect("the saved objects");
    assert_eq!(objects.len(), 1);
    assert_eq!(objects[0], lantern(at));

    // What the loader would refuse is fitted or left out as it is saved: a player far above the world comes back
    // at the height a save allows, an object flown far above it is not saved, and the save still opens.
    let mut play = play;
    let high = CameraView { origin: [view.origin[0], 9000.0, view.origin[2]], ..view.clone() };
    let above = (at.0, 5000.0, at.2);
    save_regions(&mut play, &reopened, Some(high), None, &[lantern(at), lantern(above)]).unwrap();
    drop(play);
    let (_, again) = EndlessPlay::open(EndlessSave::open(&folder).unwrap(), 2).unwrap();
    assert_eq!(again.view(None).unwrap().origin[1], 4096.0);
    assert_eq!(again.objects.unwrap(), vec![lantern(at)]);
    let _ = std::fs::remove_dir_all(&folder);
}
