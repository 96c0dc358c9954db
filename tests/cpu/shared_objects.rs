//! Moving objects and materials shared through a server: objects follow the server's clock whatever a client's
//! frame rate, a lantern one player spawns is everyone's and in the server's save, and a dropped model's colours
//! join the server's palette for everyone.

use crate::net::{join, loaded, pump, seq, start_server};
use bevy::prelude::*;
use bevy::time::TimeUpdateStrategy;
use glowbrick::dynamic::{BornAt, DynamicObject};
use glowbrick::net::protocol::SpawnAsk;
use glowbrick::net::server::{SaveNow, ServerRules};
use glowbrick::world::events::EditRequest;
use glowbrick::world::format::load_world;
use glowbrick::world::objects::{SavedMotion, SavedObject};
use glowbrick::world::{Edit, Material, VoxelWorld};
use std::time::Duration;

/// The test world's lantern (drifting, period 7 s) as one app has it: its age and its offset from its anchor.
fn lantern(app: &mut App) -> (f32, Vec3) {
    if app.world().get_resource::<glowbrick::net::client::NetClient>().is_none() {
        let world = app.world().resource::<VoxelWorld>();
        let object = &world.objects.as_ref().expect("the server's objects")[0];
        return (object.age, object.motion().offset(object.age));
    }
    let mut query = app.world_mut().query_filtered::<(&DynamicObject, &Transform), With<BornAt>>();
    let (object, transform) = query.iter(app.world()).min_by_key(|(o, _)| o.id).expect("the lantern");
    (object.age, transform.translation - object.anchor)
}

#[test]
fn clients_at_10_and_144_frames_a_second_see_the_lantern_where_the_server_has_it() {
    let (mut server, addr) = start_server(ServerRules::default());
    let mut slow = join(addr, "slow", 41);
    let mut fast = join(addr, "fast", 42);
    // Each app's clock steps by its own frame (in 1/720 s): the server ticks at 60 Hz, one client draws 10 frames
    // a second and the other 144; they update in the order their frames fall due, the server first.
    let periods = [12u64, 72, 5];
    for (app, &period) in [&mut server, &mut slow, &mut fast].into_iter().zip(&periods) {
        app.insert_resource(TimeUpdateStrategy::ManualDuration(Duration::from_secs_f64(period as f64 / 720.0)));
    }
    let mut unit = 0u64;
    let step = |apps: [&mut App; 3], unit: &mut u64| {
        for (app, &period) in apps.into_iter().zip(&periods) {
            if *unit % period == 0 {
                app.update();
            }
        }
        *unit += 1;
    };
    while !(loaded(&slow) && loaded(&fast)) {
        assert!(unit < 720 * 60, "joined within a minute of the apps' time");
        step([&mut server, &mut slow, &mut fast], &mut unit);
    }
    // A minute of play, ending on a moment all three draw (a multiple of 360 units).
    let end = (unit / 360 + 1) * 360 + 720 * 60;
    while unit <= end {
        step([&mut server, &mut slow, &mut fast], &mut unit);
    }
    let (server_age, server_at) = lantern(&mut server);
    let tick = 1.0 / 60.0;
    // Drift of radius 3 in 7 s: 2.7 voxels a second, 0.045 voxels a tick.
    let speed = std::f32::consts::TAU * 3.0 / 7.0;
    for (name, client) in [("10 fps", &mut slow), ("144 fps", &mut fast)] {
        let (age, at) = lantern(client);
        println!("{name}: age {age:.4} s, server's {server_age:.4} s, apart {:.4} voxels", at.distance(server_at));
        assert!(server_age > 60.0, "a minute passed on the server ({server_age} s)");
        assert!((age - server_age).abs() <= tick + 1e-3, "{name}: age {age} against the server's {server_age}");
        assert!(at.distance(server_at) <= speed * tick + 1e-3, "{name}: at {at} against the server's {server_at}");
    }
}

#[test]
fn a_lantern_one_player_spawns_is_everyones_and_in_the_servers_save() {
    let dir = std::env::temp_dir().join(format!("glowbrick-shared-objects-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let save = dir.join("world.ron");
    let rules = ServerRules { save_path: Some(save.clone()), ..default() };
    let (mut server, addr) = start_server(rules);
    let mut ada = join(addr, "ada", 51);
    let mut bob = join(addr, "bob", 52);
    pump(&mut [&mut server, &mut ada, &mut bob], Duration::from_secs(60), |apps| apps[1..].iter().all(|a| loaded(a)));
    let motion = SavedMotion::Slide { offset: (4.0, 0.0, 0.0), period: 3.0 };
    let spawned = SavedObject { model: "lantern".into(), motion, anchor: (10.0, 6.0, 20.0), age: 0.0 };
    ada.world_mut().write_message(SpawnAsk { object: spawned.clone() });
    let count = |app: &mut App| app.world_mut().query::<&DynamicObject>().iter(app.world()).count();
    pump(&mut [&mut server, &mut ada, &mut bob], Duration::from_secs(30), |apps| {
        seq(apps[0]) == 1 && seq(apps[1]) == 1 && seq(apps[2]) == 1
    });
    for _ in 0..3 {
        for app in [&mut server, &mut ada, &mut bob] {
            app.update();
        }
    }
    assert_eq!(
        (count(&mut ada), count(&mut bob)),
        (2, 2),
        "both clients show the test world's lantern and the new one"
    );
    let anchors = |app: &mut App| {
        let mut query = app.world_mut().query::<&DynamicObject>();
        let mut anchors: Vec<[i32; 3]> =
            query.iter(app.world()).map(|o| (o.anchor * 100.0).round().as_ivec3().to_array()).collect();
        anchors.sort();
        anchors
    };
    assert_eq!(anchors(&mut ada), anchors(&mut bob));
    assert!(anchors(&mut bob).contains(&[1000, 600, 2000]), "{:?}", anchors(&mut bob));
    // A client joining later gets it with the world.
    let mut cy = join(addr, "cy", 53);
    pump(&mut [&mut server, &mut cy], Duration::from_secs(60), |apps| loaded(apps[1]));
    for _ in 0..3 {
        for app in [&mut server, &mut cy] {
            app.update();
        }
    }
    assert_eq!(anchors(&mut cy), anchors(&mut ada));
    server.world_mut().write_message(SaveNow);
    pump(&mut [&mut server], Duration::from_secs(30), |_| save.exists());
    glowbrick::net::server::finish_saving(server.world_mut());
    let saved = load_world(&save).expect("the server's save loads");
    let objects = saved.objects.expect("objects saved");
    assert_eq!(objects.len(), 2);
    assert_eq!(
        (objects[1].model.as_str(), objects[1].anchor, &objects[1].motion),
        ("lantern", (10.0, 6.0, 20.0), &spawned.motion)
    );
    assert!(objects[1].age > 0.0, "saved at its phase ({} s)", objects[1].age);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_dropped_models_colours_join_the_servers_palette_for_everyone() {
    let rules = ServerRules { materials_per_player: 2, ..default() };
    let (mut server, addr) = start_server(rules);
    let mut ada = join(addr, "ada", 61);
    let mut bob = join(addr, "bob", 62);
    pump(&mut [&mut server, &mut ada, &mut bob], Duration::from_secs(60), |apps| apps[1..].iter().all(|a| loaded(a)));
    let ids_before = server.world().resource::<VoxelWorld>().palette.id_count();
    // What V does: the model's colours join this client's palette, then one edit uses them.
    let drop = |app: &mut App, names: &[&str], at: IVec3| {
        let mut world = app.world_mut().resource_mut::<VoxelWorld>();
        let ids: Vec<u16> = names.iter().map(|n| world.palette.push(Material::solid(n, [0.3, 0.6, 0.9]))).collect();
        let max = at + IVec3::new(ids.len() as i32 - 1, 0, 0);
        let edit = Edit::Restore { min: at, max, voxels: ids.into() };
        app.world_mut().write_message(EditRequest::player(edit));
    };
    // Both players drop models at once: each sees its colours under the ids the server gave them.
    drop(&mut ada, &["model-ada-1", "model-ada-2"], IVec3::new(4, 3, 4));
    drop(&mut bob, &["model-bob-1"], IVec3::new(8, 3, 4));
    pump(&mut [&mut server, &mut ada, &mut bob], Duration::from_secs(30), |apps| {
        seq(apps[0]) == 2 && seq(apps[1]) == 2 && seq(apps[2]) == 2
    });
    let palette = server.world().resource::<VoxelWorld>().palette.clone();
    assert_eq!(palette.id_count(), ids_before + 3);
    for app in [&mut ada, &mut bob] {
        let world = app.world().resource::<VoxelWorld>();
        assert_eq!(world.palette, palette, "every palette is the server's");
        let name_at = |p: IVec3| world.palette.get(world.grid.get(p)).map(|m| m.name.clone());
        assert_eq!(name_at(IVec3::new(4, 3, 4)).as_deref(), Some("model-ada-1"));
        assert_eq!(name_at(IVec3::new(5, 3, 4)).as_deref(), Some("model-ada-2"));
        assert_eq!(name_at(IVec3::new(8, 3, 4)).as_deref(), Some("model-bob-1"));
    }
    // Ada has used her two; a third is refused and no palette grows.
    drop(&mut ada, &["model-ada-3"], IVec3::new(4, 5, 4));
    pump(&mut [&mut server, &mut ada, &mut bob], Duration::from_secs(30), |apps| {
        apps[1].world().resource::<glowbrick::net::client::NetClient>().refusals > 0
    });
    let refusal = ada.world().resource::<glowbrick::net::client::NetClient>().last_refusal.clone().unwrap();
    assert!(refusal.contains("no room for material"), "{refusal}");
    assert_eq!(server.world().resource::<VoxelWorld>().palette, palette);
    assert_eq!(ada.world().resource::<VoxelWorld>().palette, palette, "the refused colour left ada's palette too");
}
