//! Building together in the endless world, on loopback: two clients 5 km apart each stream their own window from
//! the seed and hear only the edits near them; when one flies to the other it is sent the region the other
//! changed and sees the edit; undo and the server's save work in world coordinates; hostile asks change nothing.

use super::net::pump;
use bevy::prelude::*;
use glowbrick::game::undo::{HistoryAction, UndoPlugin};
use glowbrick::net::client::NetClient;
use glowbrick::net::endless_client::{EndlessClient, EndlessWindowConfig};
use glowbrick::net::endless_server::{EndlessStats, EndlessWorld};
use glowbrick::net::protocol::RegionAsk;
use glowbrick::net::server::{SaveNow, ServerRules, ServerStats};
use glowbrick::net::{endless_server_app, headless_client_app, transport};
use glowbrick::world::events::EditRequest;
use glowbrick::world::generate::endless::{EndlessGenerator, REGION_EDGE};
use glowbrick::world::region_save::EndlessSave;
use glowbrick::world::{Edit, Voxel, VoxelWorld};
use std::collections::HashSet;
use std::net::SocketAddr;
use std::time::Duration;

const SEED: u32 = 9;
const HEIGHT: u32 = 64;
/// A small window keeps the test quick: 4 x 4 regions, streamed 3 regions around the player.
fn small_window(start: Vec3) -> EndlessWindowConfig {
    EndlessWindowConfig { regions: 4, radius: 3, workers: 1, start: Some(start) }
}

fn join(addr: SocketAddr, name: &str, id: u64, start: Vec3) -> App {
    let mut client = headless_client_app(name, UndoPlugin);
    client.insert_resource(small_window(start));
    transport::dial(&mut client, addr, None, id).expect("dials");
    client
}

fn endless(app: &App) -> &EndlessClient {
    app.world().resource::<EndlessClient>()
}

/// A world position in `app`'s window coordinates.
fn local(app: &App, world: IVec3) -> IVec3 {
    world - endless(app).offset().expect("the window is made")
}

fn voxel_at(app: &App, world: IVec3) -> Voxel {
    app.world().resource::<VoxelWorld>().grid.get(local(app, world))
}

fn seq_of(app: &App) -> u64 {
    app.world().resource::<NetClient>().seq
}

/// Moves `app`'s player to `world` (world coordinates) and plays until its window is centred there.
fn fly(apps: &mut [&mut App], who: usize, world: Vec3) {
    let to = world - endless(apps[who]).offset().unwrap().as_vec3();
    apps[who].world_mut().resource_mut::<EndlessClient>().at = to;
    pump(apps, Duration::from_secs(120), |apps| {
        let grid = &apps[who].world().resource::<VoxelWorld>().grid;
        let (lo, hi) = grid.window();
        let whole = hi.x - lo.x == grid.size().x as i32 && hi.z - lo.z == grid.size().z as i32;
        let inside = to.x >= (lo.x + REGION_EDGE) as f32
            && to.x < (hi.x - REGION_EDGE) as f32
            && to.z >= (lo.z + REGION_EDGE) as f32
            && to.z < (hi.z - REGION_EDGE) as f32;
        whole && inside
    });
}

/// Every voxel of region `key` as `app`'s window holds it.
fn region_in_window(app: &App, key: IVec2) -> Vec<Voxel> {
    let world = app.world().resource::<VoxelWorld>();
    let corner = IVec3::new(key.x * REGION_EDGE, 0, key.y * REGION_EDGE);
    let at = local(app, corner);
    world.grid.read_box(at, at + IVec3::new(REGION_EDGE, HEIGHT as i32, REGION_EDGE)).to_vec()
}

#[test]
fn two_players_five_km_apart_stream_their_own_surroundings_and_meet() {
    let folder = std::env::temp_dir().join(format!("glowbrick-net-endless-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&folder);
    let save = EndlessSave::open_or_create(&folder, SEED, HEIGHT).unwrap();
    let world = EndlessWorld::new(SEED, HEIGHT, Some(save)).unwrap();
    let rules = ServerRules { save_every: Duration::from_secs(3600), ..default() };
    let mut server = endless_server_app(world, rules, 12.0);
    let addr = transport::listen(&mut server, "127.0.0.1:0".parse().unwrap(), None, 16).expect("listens");

    let (home_a, home_b) = (Vec3::new(40.0, 50.0, 40.0), Vec3::new(5040.0, 50.0, 40.0));
    let mut a = join(addr, "ada", 1, home_a);
    let mut b = join(addr, "bo", 2, home_b);
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(120), |apps| {
        apps[1..].iter().all(|app| app.world().get_resource::<EndlessClient>().is_some_and(|e| e.started()))
    });
    // Each streams its own surroundings: its window is where it stands, made from the seed here.
    let min_a = endless(&a).offset().unwrap();
    let min_b = endless(&b).offset().unwrap();
    assert!(min_a.x <= 40 && min_a.x + 4 * REGION_EDGE > 40, "a's window {min_a} holds a");
    assert!(min_b.x <= 5040 && min_b.x + 4 * REGION_EDGE > 5040, "b's window {min_b} holds b");
    let generator = EndlessGenerator::new(SEED, HEIGHT).unwrap();
    let key_a = IVec2::new(0, 0);
    assert_eq!(
        region_in_window(&a, key_a),
        generator.region(key_a).grid.read_box(IVec3::ZERO, IVec3::new(64, HEIGHT as i32, 64)).to_vec()
    );
    // The server holds the regions around the players, not their windows.
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(30), |apps| {
        apps[0].world().resource::<EndlessWorld>().counts().0 >= 18
    });
    let (in_memory, changed) = server.world().resource::<EndlessWorld>().counts();
    assert!(in_memory <= 2 * 25, "the server holds {in_memory} regions");
    assert_eq!(changed, 0);

    // Each builds at home. A lamp for a, stone for b; neither hears the other's edit.
    let lamp = generator.palette().id_of("lamp-warm").expect("the generator has a warm lamp");
    let (at_a, at_b) = (IVec3::new(70, 60, 50), IVec3::new(5050, 60, 45));
    let place_a = Edit::Place { at: local(&a, at_a), material: lamp };
    a.world_mut().write_message(EditRequest::player(place_a));
    let place_b = Edit::Place { at: local(&b, at_b), material: 1 };
    b.world_mut().write_message(EditRequest::player(place_b));
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(20), |apps| {
        voxel_at(apps[1], at_a) == lamp && voxel_at(apps[2], at_b) == 1
    });
    for _ in 0..30 {
        for app in [&mut server, &mut a, &mut b] {
            app.update();
        }
    }
    assert_eq!(server.world().resource::<ServerStats>().seq, 2);
    let (seq_a, seq_b) = (seq_of(&a), seq_of(&b));
    assert!(seq_a == 1 || seq_b == 1, "one of the two edits came first");
    assert_eq!(seq_a.min(seq_b), 1);
    assert_eq!(seq_a + seq_b, 3, "each heard only its own edit (a {seq_a}, b {seq_b})");
    let sent = server.world().resource::<EndlessStats>().edits_sent;
    assert_eq!(sent, 2, "two edits, each sent to one client");

    // b flies 5 km to a: it is sent a's changed region and sees the lamp.
    fly(&mut [&mut server, &mut a, &mut b], 2, home_a + Vec3::new(20.0, 0.0, 0.0));
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(20), |apps| voxel_at(apps[2], at_a) == lamp);
    assert!(server.world().resource::<EndlessStats>().changed_regions_sent >= 1);
    let key = EndlessGenerator::region_of(at_a.x, at_a.z);
    assert_eq!(region_in_window(&b, key), region_in_window(&a, key), "a's region is the same in both windows");

    // Now together: a's second edit reaches both; its undo too.
    let above = at_a + IVec3::Y;
    let place = Edit::Place { at: local(&a, above), material: 1 };
    a.world_mut().write_message(EditRequest::player(place));
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(20), |apps| {
        voxel_at(apps[1], above) == 1 && voxel_at(apps[2], above) == 1
    });
    a.world_mut().write_message(HistoryAction::Undo);
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(20), |apps| {
        voxel_at(apps[1], above) == 0 && voxel_at(apps[2], above) == 0
    });
    assert_eq!(voxel_at(&b, at_a), lamp, "undo took back only the latest edit");
    let server_region = server
        .world()
        .resource::<EndlessWorld>()
        .region(key)
        .expect("the server holds it")
        .grid
        .read_box(IVec3::ZERO, IVec3::new(REGION_EDGE, HEIGHT as i32, REGION_EDGE));
    assert_eq!(region_in_window(&a, key), server_region.to_vec(), "the server's region is the clients'");

    // Hostile asks: a region past the world's end is refused, and nothing changes.
    let refused = server.world().resource::<ServerStats>().refused;
    a.world_mut().write_message(RegionAsk { key: [i32::MAX, 0], ticket: 7 });
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(10), |apps| {
        apps[0].world().resource::<ServerStats>().refused > refused
    });
    assert_eq!(voxel_at(&a, at_a), lamp);

    // The save holds the changed regions only: a's and b's.
    server.world_mut().write_message(SaveNow);
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(20), |apps| {
        apps[0].world().resource::<ServerStats>().saves >= 1
    });
    let saved: HashSet<IVec2> = EndlessSave::open(&folder).unwrap().saved_regions().into_iter().collect();
    let expected: HashSet<IVec2> = [key, EndlessGenerator::region_of(at_b.x, at_b.z)].into_iter().collect();
    assert_eq!(saved, expected);
    let reopened = EndlessSave::open(&folder).unwrap();
    let region = reopened.load_region(key, generator.palette()).unwrap().unwrap();
    assert_eq!(region.grid.get(at_a - IVec3::new(key.x * REGION_EDGE, 0, key.y * REGION_EDGE)), lamp);
    let _ = std::fs::remove_dir_all(&folder);
}
