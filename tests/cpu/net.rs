//! Building together on loopback: a real server and headless clients over UDP (renet + netcode), no GPU. Random
//! edits from several clients must leave every world identical (voxels, lights, objects), with clients joining
//! late and one killed; hostile bytes and requests must change nothing.

use bevy::prelude::*;
use glowbrick::game::undo::{HistoryAction, UndoPlugin};
use glowbrick::lights::LightPool;
use glowbrick::net::client::NetClient;
use glowbrick::net::server::{ServerRules, ServerStats};
use glowbrick::net::state_hash::{lights_hash, voxels_hash};
use glowbrick::net::{headless_client_app, server_app, transport};
use glowbrick::world::events::EditRequest;
use glowbrick::world::objects::{SavedMotion, SavedObject};
use glowbrick::world::source::WorldSource;
use glowbrick::world::{Edit, VoxelWorld};
use std::net::SocketAddr;
use std::time::{Duration, Instant};

struct Rng(u64);

impl Rng {
    fn next(&mut self) -> u64 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        self.0
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

pub(crate) fn test_world() -> VoxelWorld {
    let mut world = WorldSource::Scene("test-room".into()).load().expect("the test room loads");
    world.objects = Some(vec![SavedObject {
        model: "lantern".into(),
        motion: SavedMotion::Drift { radius: 3.0, period: 7.0 },
        anchor: (16.0, 8.0, 16.0),
        age: 1.5,
    }]);
    world
}

pub(crate) fn start_server(rules: ServerRules) -> (App, SocketAddr) {
    let mut server = server_app(test_world(), rules);
    let addr = transport::listen(&mut server, "127.0.0.1:0".parse().unwrap(), None, 16).expect("listens");
    (server, addr)
}

pub(crate) fn join(addr: SocketAddr, name: &str, id: u64) -> App {
    let mut client = headless_client_app(name, UndoPlugin);
    transport::dial(&mut client, addr, None, id).expect("dials");
    client
}

/// Updates every app in turn until `done` holds (or panics after `limit`).
pub(crate) fn pump(apps: &mut [&mut App], limit: Duration, mut done: impl FnMut(&mut [&mut App]) -> bool) {
    let start = Instant::now();
    while !done(apps) {
        assert!(start.elapsed() < limit, "timed out after {limit:?}");
        for app in apps.iter_mut() {
            app.update();
        }
        std::thread::sleep(Duration::from_millis(1));
    }
}

pub(crate) fn loaded(app: &App) -> bool {
    app.world().resource::<NetClient>().loaded
}

pub(crate) fn seq(app: &App) -> u64 {
    app.world().get_resource::<NetClient>().map_or_else(|| app.world().resource::<ServerStats>().seq, |c| c.seq)
}

/// Voxels, lights and objects (model and anchor) of one app.
fn state(app: &mut App) -> (u64, u64, Vec<(String, [i32; 3])>) {
    let world = app.world().resource::<VoxelWorld>();
    let hashes = (voxels_hash(world), lights_hash(app.world().resource::<LightPool>()));
    let key = |model: &str, anchor: Vec3| (model.to_string(), (anchor * 100.0).round().as_ivec3().to_array());
    let mut objects: Vec<_> = match app.world().get_resource::<NetClient>() {
        Some(_) => {
            let mut q = app.world_mut().query::<&glowbrick::dynamic::DynamicObject>();
            q.iter(app.world()).map(|o| key(&o.model.name, o.anchor)).collect()
        }
        None => (world.objects.iter().flatten()).map(|o| key(&o.model, Vec3::from(o.anchor))).collect(),
    };
    objects.sort();
    (hashes.0, hashes.1, objects)
}

/// A random edit near or inside the 32x16x32 test room: blocks, lamps, boxes, breaks, and some outside it.
fn random_edit(rng: &mut Rng, materials: u64) -> Edit {
    let mut at = || IVec3::new(rng.below(36) as i32 - 2, rng.below(18) as i32 - 1, rng.below(36) as i32 - 2);
    let a = at();
    match rng.below(10) {
        0..=3 => Edit::Place { at: a, material: 1 + rng.below(materials - 1) as u16 },
        4..=6 => Edit::Break { at: a },
        _ => {
            let max = a + IVec3::new(rng.below(4) as i32, rng.below(4) as i32, rng.below(4) as i32);
            Edit::FillBox { min: a, max, material: rng.below(materials) as u16 }
        }
    }
}

#[test]
fn ten_thousand_edits_from_two_clients_leave_every_world_identical() {
    let rules = ServerRules { edits_per_second: 1e6, edit_burst: 1e6, ..default() };
    let (mut server, addr) = start_server(rules);
    let mut a = join(addr, "ada", 1);
    let mut b = join(addr, "bo", 2);
    let mut doomed = join(addr, "doomed", 3);
    pump(&mut [&mut server, &mut a, &mut b, &mut doomed], Duration::from_secs(60), |apps| {
        apps[1..].iter().all(|app| loaded(app))
    });
    let materials = server.world().resource::<VoxelWorld>().palette.id_count() as u64;
    assert!(materials > 2);
    let emissive = (1..materials as u16).filter(|&m| server.world().resource::<VoxelWorld>().palette.is_emissive(m));
    assert!(emissive.count() > 0, "the test room has a lamp material");

    let mut rng = Rng(0x9e37_79b9_7f4a_7c15);
    let mut late: Option<App> = None;
    let mut doomed = Some(doomed);
    let (rounds, per_round) = (200, 25);
    for round in 0..rounds {
        for client in [&mut a, &mut b] {
            for _ in 0..per_round {
                let edit = random_edit(&mut rng, materials);
                client.world_mut().write_message(EditRequest::player(edit));
            }
            if rng.below(4) == 0 {
                client.world_mut().write_message(HistoryAction::Undo);
            }
        }
        if round == rounds / 2 {
            late = Some(join(addr, "late", 4));
        }
        if round == 60 {
            // Killed: no goodbye, its socket just goes quiet.
            drop(doomed.take());
        }
        let mut apps: Vec<&mut App> = vec![&mut server, &mut a, &mut b];
        apps.extend(late.as_mut());
        apps.extend(doomed.as_mut());
        for app in apps {
            app.update();
        }
    }
    let mut late = late.expect("joined");
    pump(&mut [&mut server, &mut a, &mut b, &mut late], Duration::from_secs(120), |apps| {
        let server_seq = seq(apps[0]);
        apps[1..].iter().all(|app| loaded(app) && seq(app) == server_seq)
    });
    // A few more frames so the light pools catch up with the last edits.
    for _ in 0..3 {
        for app in [&mut server, &mut a, &mut b, &mut late] {
            app.update();
        }
    }
    let stats = server.world().resource::<ServerStats>().clone();
    println!(
        "10,000 edits: {} applied, {} refused (outside the room), server and three clients identical",
        stats.seq, stats.refused
    );
    assert!(stats.seq > 5_000, "most of the 10,000 edits changed something (applied {})", stats.seq);
    assert!(stats.refused > 100, "edits outside the room were refused ({})", stats.refused);
    let expected = state(&mut server);
    assert!(!expected.2.is_empty(), "the server has an object");
    for (name, app) in [("ada", &mut a), ("bo", &mut b), ("late", &mut late)] {
        assert_eq!(state(app), expected, "{name}'s world differs from the server's");
    }
    let names: Vec<String> = a.world().resource::<NetClient>().players.iter().map(|p| p.name.clone()).collect();
    assert!(names.contains(&"bo".to_string()) && names.contains(&"late".to_string()), "players: {names:?}");
}

#[test]
fn undo_takes_back_only_your_own_edit() {
    let (mut server, addr) = start_server(ServerRules::default());
    let mut a = join(addr, "ada", 11);
    let mut b = join(addr, "bo", 12);
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(60), |apps| apps[1..].iter().all(|a| loaded(a)));
    let (pa, pb) = (IVec3::new(5, 5, 5), IVec3::new(7, 5, 5));
    assert_eq!(server.world().resource::<VoxelWorld>().grid.get(pa), 0);
    a.world_mut().write_message(EditRequest::player(Edit::Place { at: pa, material: 1 }));
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(30), |apps| seq(apps[2]) == 1);
    b.world_mut().write_message(EditRequest::player(Edit::Place { at: pb, material: 2 }));
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(30), |apps| seq(apps[1]) == 2);
    // Ada undoes: her block goes, Bo's stays, everywhere.
    a.world_mut().write_message(HistoryAction::Undo);
    pump(&mut [&mut server, &mut a, &mut b], Duration::from_secs(30), |apps| seq(apps[2]) == 3);
    for app in [&server, &a, &b] {
        let grid = &app.world().resource::<VoxelWorld>().grid;
        assert_eq!((grid.get(pa), grid.get(pb)), (0, 2));
    }
}

/// This process's resident memory, in bytes (Linux).
fn resident_bytes() -> u64 {
    let statm = std::fs::read_to_string("/proc/self/statm").unwrap_or_default();
    statm.split_whitespace().nth(1).and_then(|p| p.parse::<u64>().ok()).unwrap_or(0) * 4096
}

#[test]
fn hostile_messages_change_nothing_and_valid_clients_play_on() {
    use bevy_replicon::prelude::{ClientMessages, RepliconChannels};
    use glowbrick::net::protocol::{ClockAsk, EditAsk, Hello, NetEdit, NetMaterial, SpawnAsk};
    let rules = ServerRules { edits_per_second: 50.0, edit_burst: 100.0, ..default() };
    let (mut server, addr) = start_server(rules);
    let mut good = join(addr, "good", 21);
    let mut evil = join(addr, "evil", 22);
    pump(&mut [&mut server, &mut good, &mut evil], Duration::from_secs(60), |apps| apps[1..].iter().all(|a| loaded(a)));
    let before = state(&mut server);
    let palette_before = server.world().resource::<VoxelWorld>().palette.clone();
    // Which channels take garbage without ending the connection: garbage on replicon's own handshake channel
    // reads as another protocol's hash, and the server hangs up on that client (the others play on).
    let channels = evil.world().resource::<RepliconChannels>().client_channels().len();
    let mut rng = Rng(7);
    let mut survivable = Vec::new();
    for channel in 0..channels {
        let mut probe = join(addr, "probe", 100 + channel as u64);
        pump(&mut [&mut server, &mut good, &mut probe], Duration::from_secs(30), |apps| loaded(apps[2]));
        for _ in 0..100 {
            let bytes: Vec<u8> = (0..rng.below(160)).map(|_| rng.next() as u8).collect();
            probe.world_mut().resource_mut::<ClientMessages>().send(channel, bytes);
        }
        for _ in 0..20 {
            for app in [&mut server, &mut good, &mut probe] {
                app.update();
            }
        }
        if probe.world().resource::<bevy_replicon_renet::RenetClient>().is_connected() {
            survivable.push(channel as u64);
        }
    }
    assert!(survivable.len() >= 3, "garbage on the game's message channels is dropped ({survivable:?} of {channels})");
    assert!(survivable.len() < channels, "garbage on the handshake channel ends the connection");
    let memory_before = resident_bytes();
    let (mut sent, mut typed) = (0u64, 0u64);
    let huge = 1 << 20;
    while sent < 100_000 {
        {
            let world = evil.world_mut();
            for _ in 0..250 {
                // Garbage on every channel that does not end the connection.
                let len = rng.below(160) as usize;
                let bytes: Vec<u8> = (0..len).map(|_| rng.next() as u8).collect();
                let channel = survivable[rng.below(survivable.len() as u64) as usize];
                world.resource_mut::<ClientMessages>().send(channel as usize, bytes);
                sent += 1;
            }
            // Well-formed but hostile: outside the world, absurd boxes, unknown materials, lying restores, NaN
            // clocks, huge names, and a flood beyond the rate limit.
            let hostile = [
                NetEdit::Place { at: [i32::MAX, 0, i32::MIN], material: 1 },
                NetEdit::FillBox { min: [i32::MIN; 3], max: [i32::MAX; 3], material: 1 },
                NetEdit::FillBox { min: [0; 3], max: [31, 15, 31], material: 1 },
                NetEdit::Place { at: [3, 3, 3], material: u16::MAX },
                NetEdit::Restore { min: [0; 3], max: [huge, huge, huge], voxels: vec![1; 8] },
                NetEdit::Restore { min: [0; 3], max: [1, 1, 1], voxels: vec![1; 3] },
            ];
            for edit in hostile {
                world.write_message(EditAsk::plain(edit, true));
                sent += 1;
                typed += 1;
            }
            // Materials that may not join the palette, and objects that may not be spawned.
            let first_new = palette_before.id_count() as u16;
            let material = |name: &str, strength: f32, albedo: f32| NetMaterial {
                name: name.into(),
                albedo: [albedo; 3],
                emission: [1.0; 3],
                strength,
                variation: 0.0,
            };
            let place = NetEdit::Place { at: [4, 4, 4], material: first_new };
            for materials in [vec![material("sun", 1e6, 0.5)], vec![material("nan", 1.0, f32::NAN)], vec![]] {
                world.write_message(EditAsk { edit: place.clone(), undoable: false, first_new, materials });
            }
            let object = |model: &str, period: f32, anchor: f32| {
                let motion = glowbrick::world::objects::SavedMotion::Drift { radius: 2.0, period };
                SavedObject { model: model.into(), motion, anchor: (anchor, 8.0, 8.0), age: 0.0 }
            };
            for object in [object("dragon", 8.0, 8.0), object("lantern", 1e-30, 8.0), object("block", 8.0, f32::NAN)] {
                world.write_message(SpawnAsk { object });
            }
            sent += 6;
            typed += 6;
            world.write_message(ClockAsk { hours: f32::NAN });
            world.write_message(Hello { name: "\u{7}x".repeat(4096) });
            sent += 2;
        }
        for app in [&mut server, &mut good, &mut evil] {
            app.update();
        }
    }
    // The valid client still plays: its edit arrives (after whatever of the flood was still on its way) and
    // everyone agrees.
    let probe = IVec3::new(9, 9, 9);
    good.world_mut().write_message(EditRequest::player(Edit::Break { at: probe }));
    good.world_mut().write_message(EditRequest::player(Edit::Place { at: probe, material: 2 }));
    pump(&mut [&mut server, &mut good, &mut evil], Duration::from_secs(30), |apps| {
        apps[1].world().resource::<VoxelWorld>().grid.get(probe) == 2 && seq(apps[1]) == seq(apps[0])
    });
    for _ in 0..3 {
        for app in [&mut server, &mut good] {
            app.update();
        }
    }
    assert_eq!(state(&mut good), state(&mut server));
    let stats = server.world().resource::<ServerStats>().clone();
    // Only the good edit and at most the flood's allowance of in-world boxes got through.
    assert!(evil.world().resource::<bevy_replicon_renet::RenetClient>().is_connected(), "the flood reached the server");
    // Five of the six typed requests a round are refused by the checks; the whole-room box passes them and is
    // then held to the rate limit (100 at once, 50 a second) with everything else.
    assert!(stats.refused >= typed * 5 / 6, "hostile requests refused: {} of {typed}", stats.refused);
    assert_ne!(state(&mut server).0, before.0, "the good edit changed the world");
    assert_eq!(server.world().resource::<VoxelWorld>().grid.get(probe), 2);
    assert_eq!(server.world().resource::<VoxelWorld>().palette, palette_before, "no hostile material joined");
    let grown = resident_bytes().saturating_sub(memory_before);
    println!(
        "hostile: {sent} messages ({typed} well-formed), {} refused, garbage survives on channels {survivable:?} of \
         {channels}, resident memory grew {:.1} MB",
        stats.refused,
        grown as f64 / 1e6
    );
    assert!(grown < 256 << 20, "memory grew {} MB under the flood", grown >> 20);
    let names: Vec<String> = good.world().resource::<NetClient>().players.iter().map(|p| p.name.clone()).collect();
    assert!(names.iter().all(|n| n.chars().count() <= glowbrick::net::server::MAX_NAME_CHARS), "{names:?}");
}

#[test]
fn a_secret_keeps_strangers_out() {
    let mut server = server_app(test_world(), ServerRules::default());
    let addr = transport::listen(&mut server, "127.0.0.1:0".parse().unwrap(), Some("lamplight"), 4).unwrap();
    let mut friend = headless_client_app("friend", ());
    transport::dial(&mut friend, addr, Some("lamplight"), 31).unwrap();
    let mut wrong = headless_client_app("wrong", ());
    transport::dial(&mut wrong, addr, Some("lamplight "), 32).unwrap();
    let mut open = headless_client_app("open", ());
    transport::dial(&mut open, addr, None, 33).unwrap();
    pump(&mut [&mut server, &mut friend, &mut wrong, &mut open], Duration::from_secs(30), |apps| loaded(apps[1]));
    // Give the strangers as long again as the friend took.
    for _ in 0..200 {
        for app in [&mut server, &mut friend, &mut wrong, &mut open] {
            app.update();
        }
        std::thread::sleep(Duration::from_millis(2));
    }
    assert!(!loaded(&wrong) && !loaded(&open), "only the client with the secret got the world");
    assert_eq!(server.world().resource::<bevy_replicon_renet::RenetServer>().connected_clients(), 1);
}

/// A free UDP port on loopback (taken, then released for the server to take).
pub(crate) fn free_port() -> u16 {
    std::net::UdpSocket::bind("127.0.0.1:0").unwrap().local_addr().unwrap().port()
}

pub(crate) fn serve(args: &[&str], port: u16) -> std::process::Child {
    std::process::Command::new(env!("CARGO_BIN_EXE_glowbrick"))
        .args(["serve", "--bind", "127.0.0.1", "--port", &port.to_string()])
        .args(args)
        .stdin(std::process::Stdio::piped())
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .expect("start glowbrick serve")
}

/// Joins the server at `port` and waits for the world, retrying while the server process starts.
pub(crate) fn join_process(port: u16, id: u64) -> App {
    let addr: SocketAddr = format!("127.0.0.1:{port}").parse().unwrap();
    let mut client = join(addr, "builder", id);
    pump(&mut [&mut client], Duration::from_secs(60), |apps| loaded(apps[0]));
    client
}

#[test]
fn the_server_saves_what_players_built_and_a_kill_loses_only_the_last_seconds() {
    use std::io::Write;
    let dir = std::env::temp_dir().join(format!("glowbrick-serve-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let save = dir.join("shared.ron");
    let save_arg = save.to_str().unwrap();
    let (lamp, block) = (IVec3::new(6, 4, 6), IVec3::new(8, 4, 6));

    // Saves every second; killed (SIGKILL) two seconds after the edit: the save holds it.
    let port = free_port();
    let mut server = serve(&["--scene", "test-room", "--save", save_arg, "--save-every", "1"], port);
    let mut client = join_process(port, 41);
    let material = 2;
    client.world_mut().write_message(EditRequest::player(Edit::Place { at: lamp, material }));
    pump(&mut [&mut client], Duration::from_secs(30), |apps| seq(apps[0]) >= 1);
    let until = Instant::now() + Duration::from_millis(2500);
    pump(&mut [&mut client], Duration::from_secs(30), |_| Instant::now() > until);
    server.kill().unwrap();
    server.wait().unwrap();
    let saved = glowbrick::world::format::load_world(&save).expect("the save loads");
    assert_eq!(saved.grid.get(lamp), material, "the edit made 2.5 s before the kill is in the save");
    drop(client);

    // Started again from the save: a new client gets the world as it was, builds, and `quit` saves and stops.
    let port = free_port();
    let mut server = serve(&["--world", save_arg, "--save", save_arg, "--save-every", "3600"], port);
    let mut client = join_process(port, 42);
    assert_eq!(client.world().resource::<VoxelWorld>().grid.get(lamp), material);
    client.world_mut().write_message(EditRequest::player(Edit::Place { at: block, material: 1 }));
    pump(&mut [&mut client], Duration::from_secs(30), |apps| seq(apps[0]) >= 1);
    server.stdin.as_mut().unwrap().write_all(b"quit\n").unwrap();
    let out = server.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
    assert!(stdout.contains("the server is open"), "an open server says so: {stdout}");
    assert!(stdout.contains("player 1 joined") && stdout.contains("is called builder"), "{stdout}");
    let saved = glowbrick::world::format::load_world(&save).expect("the save loads");
    assert_eq!((saved.grid.get(lamp), saved.grid.get(block)), (material, 1));
    let backup = glowbrick::world::format::backup_path(&save);
    assert_eq!(
        glowbrick::world::format::load_world(&backup).unwrap().grid.get(block),
        0,
        "the .bak is the save before"
    );
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn bad_server_and_join_arguments_fail_in_one_line() {
    let run = |args: &[&str]| {
        std::process::Command::new(env!("CARGO_BIN_EXE_glowbrick")).args(args).output().expect("run glowbrick")
    };
    let out = run(&["serve", "--scene", "test-room", "--edits-per-second", "0", "--port", "0"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("--edits-per-second 0 must be within") && stderr.lines().count() == 1, "{stderr}");
    let out = run(&["serve", "--scene", "no-such-scene", "--port", "0"]);
    assert_eq!(out.status.code(), Some(1));
    let out = run(&["play", "--connect", "127.0.0.1:1", "--scene", "cornell"]);
    assert_eq!(out.status.code(), Some(2), "clap refuses a world with --connect");
    let out = run(&["play", "--name", "ada"]);
    assert_eq!(out.status.code(), Some(2), "--name needs --connect");
}
