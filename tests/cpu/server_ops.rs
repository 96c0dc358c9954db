//! Running a server for a season: stop signals save and exit 0 (a second one during the save leaves a whole save
//! or `.bak`), and the console's `list`, `kick`, `ban`, `unban` and `say` act on real clients over loopback.

use crate::net::{free_port, join, join_process, loaded, pump, seq, serve, start_server};
use bevy::prelude::*;
use glowbrick::net::client::NetClient;
use glowbrick::net::console::{BanList, ConsoleCommand};
use glowbrick::net::server::{Bans, ServerRules, run_console_command};
use glowbrick::world::events::EditRequest;
use glowbrick::world::format::{backup_path, load_world};
use glowbrick::world::{Edit, VoxelWorld};
use std::io::Read;
use std::process::Child;
use std::time::{Duration, Instant};

/// Sends signal `name` to the child; whether it was still there to receive it.
fn signal(child: &Child, name: &str) -> bool {
    let status = std::process::Command::new("kill").args([&format!("-{name}"), &child.id().to_string()]).status();
    status.expect("run kill").success()
}

/// Reads the child's standard output until `line` appears (or panics after a minute), returning all it read.
fn wait_for_line(child: &mut Child, line: &str) -> String {
    let stdout = child.stdout.as_mut().expect("piped stdout");
    let start = Instant::now();
    let mut text = String::new();
    let mut byte = [0u8; 1];
    while !text.contains(line) {
        assert!(start.elapsed() < Duration::from_secs(60), "no '{line}' in: {text}");
        match stdout.read(&mut byte) {
            Ok(1) => text.push(byte[0] as char),
            _ => panic!("the server's output ended before '{line}': {text}"),
        }
    }
    text
}

#[test]
fn a_stop_signal_saves_the_players_edits_and_exits_zero() {
    let dir = std::env::temp_dir().join(format!("glowbrick-signal-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let lamp = IVec3::new(6, 4, 6);
    for (round, name) in ["TERM", "INT", "HUP"].into_iter().enumerate() {
        let save = dir.join(format!("{name}.ron"));
        let port = free_port();
        // Saves only hourly: whatever the save holds, the stop wrote.
        let server = serve(&["--scene", "test-room", "--save", save.to_str().unwrap(), "--save-every", "3600"], port);
        let mut client = join_process(port, 60 + round as u64);
        client.world_mut().write_message(EditRequest::player(Edit::Place { at: lamp, material: 2 }));
        pump(&mut [&mut client], Duration::from_secs(30), |apps| seq(apps[0]) >= 1);
        assert!(!save.exists(), "no save before the signal");
        assert!(signal(&server, name));
        let out = server.wait_with_output().unwrap();
        let stdout = String::from_utf8_lossy(&out.stdout);
        assert_eq!(out.status.code(), Some(0), "SIG{name}: {stdout}\n{}", String::from_utf8_lossy(&out.stderr));
        assert!(stdout.contains("stopping on a signal"), "{stdout}");
        let saved = load_world(&save).expect("the save loads");
        assert_eq!(saved.grid.get(lamp), 2, "SIG{name}: the unsaved edit is in the save");
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_second_signal_during_the_save_leaves_a_whole_save_or_backup() {
    let _alone = crate::EXCLUSIVE.lock().unwrap_or_else(|e| e.into_inner());
    let dir = std::env::temp_dir().join(format!("glowbrick-signal-twice-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let save = dir.join("big.ron");
    let save_arg = save.to_str().unwrap();
    // A world large enough that its save takes a while (10 MB, about 0.1 s here), so the second signal, sent as
    // soon as the server says it is saving, most often lands in the save.
    let world = ["--new", "--seed", "3", "--size", "768,96,768", "--save", save_arg, "--save-every", "3600"];
    let mut first = serve(&world, free_port());
    // A closed standard input (a service's): the server runs on until the signal.
    first.stdin.take();
    wait_for_line(&mut first, "commands:");
    assert!(signal(&first, "TERM"));
    assert_eq!(first.wait().unwrap().code(), Some(0));
    let before = load_world(&save).expect("the first stop saved");

    let mut second = serve(&["--world", save_arg, "--save", save_arg, "--save-every", "3600"], free_port());
    wait_for_line(&mut second, "commands:");
    assert!(signal(&second, "TERM"));
    wait_for_line(&mut second, "before stopping");
    let landed = signal(&second, "TERM");
    let code = second.wait().unwrap().code();
    assert!(code == Some(130) || code == Some(0), "exit {code:?}");
    assert!(landed || code == Some(0), "the server was gone before the second signal, so it finished its save");
    println!("second signal: {}", if code == Some(130) { "landed in the save" } else { "after the save" });
    let whole = [load_world(&save), load_world(&backup_path(&save))];
    let sizes: Vec<Option<UVec3>> = whole.iter().map(|w| w.as_ref().ok().map(|w| w.grid.size())).collect();
    assert!(sizes.contains(&Some(before.grid.size())), "neither the save nor its .bak loads whole: exit {code:?}");
    let _ = std::fs::remove_dir_all(&dir);
}

fn notice(app: &App) -> Option<String> {
    app.world().resource::<NetClient>().last_notice.clone()
}

fn sent_away(app: &App) -> Option<String> {
    app.world().resource::<NetClient>().sent_away.clone()
}

#[test]
fn the_console_lists_kicks_bans_and_speaks_to_real_clients() {
    let dir = std::env::temp_dir().join(format!("glowbrick-console-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let bans_path = BanList::path_beside(&dir.join("world.ron"));
    let (mut server, addr) = start_server(ServerRules::default());
    server.insert_resource(Bans { list: BanList::default(), path: Some(bans_path.clone()) });
    let mut ada = join(addr, "ada", 71);
    let mut grief = join(addr, "Grief", 72);
    pump(&mut [&mut server, &mut ada, &mut grief], Duration::from_secs(60), |apps| loaded(apps[1]) && loaded(apps[2]));

    let list = run_console_command(server.world_mut(), &ConsoleCommand::List);
    assert!(list.starts_with("2 playing") && list.contains("ada") && list.contains("Grief"), "{list}");

    let said = run_console_command(server.world_mut(), &ConsoleCommand::Say("dinner at six".into()));
    assert_eq!(said, "[server] dinner at six");
    pump(&mut [&mut server, &mut ada, &mut grief], Duration::from_secs(10), |apps| {
        notice(apps[1]).is_some() && notice(apps[2]).is_some()
    });
    assert_eq!(notice(&ada).as_deref(), Some("[server] dinner at six"));
    assert_eq!(sent_away(&ada), None, "a line is not a farewell");

    // Kicked: told why and disconnected; the other player stays.
    assert_eq!(
        run_console_command(server.world_mut(), &ConsoleCommand::Kick("nobody".into())),
        "nobody called 'nobody' is playing"
    );
    assert_eq!(run_console_command(server.world_mut(), &ConsoleCommand::Kick("grief".into())), "kicked grief");
    let players =
        |server: &mut App| server.world_mut().query::<&glowbrick::net::server::Peer>().iter(server.world()).count();
    pump(&mut [&mut server, &mut ada, &mut grief], Duration::from_secs(10), |apps| players(apps[0]) == 1);
    assert!(sent_away(&grief).is_some_and(|why| why.contains("sent you away")), "{:?}", sent_away(&grief));

    // Banned (not playing now): the ban is kept in the file, and the name cannot join again, in any case.
    let banned = run_console_command(server.world_mut(), &ConsoleCommand::Ban("GRIEF".into()));
    assert!(banned.contains("banned the name GRIEF"), "{banned}");
    assert!(BanList::load(&bans_path).unwrap().refuses(Some("grief"), None), "the ban is in the file");
    let mut again = join(addr, "grief", 73);
    pump(&mut [&mut server, &mut ada, &mut again], Duration::from_secs(20), |apps| sent_away(apps[2]).is_some());
    assert_eq!(sent_away(&again).as_deref(), Some("you are banned from this server"));
    assert!(!loaded(&again), "a banned player is sent no world");

    // Lifted: the same name joins.
    assert_eq!(run_console_command(server.world_mut(), &ConsoleCommand::Unban("grief".into())), "grief may join again");
    let mut back = join(addr, "grief", 74);
    pump(&mut [&mut server, &mut ada, &mut back], Duration::from_secs(60), |apps| loaded(apps[2]));
    assert_eq!(back.world().resource::<VoxelWorld>().grid.size(), server.world().resource::<VoxelWorld>().grid.size());
    let _ = std::fs::remove_dir_all(&dir);
}

fn peer_names(server: &mut App) -> Vec<String> {
    let mut q = server.world_mut().query::<&glowbrick::net::server::Peer>();
    q.iter(server.world()).map(|p| p.name.clone()).collect()
}

#[test]
fn a_lost_connection_and_a_restarted_client_come_back_as_the_same_player_with_their_undo() {
    use glowbrick::net::client::{Join, Rejoin};
    use glowbrick::net::protocol::Pose;
    let (mut server, addr) = start_server(ServerRules::default());
    let mut ada = join(addr, "ada", 91);
    ada.insert_resource(Join { server: addr, secret: None, name: "ada".into(), view: None });
    pump(&mut [&mut server, &mut ada], Duration::from_secs(60), |apps| loaded(apps[1]));
    let pose = Pose { position: [5.5, 6.0, 7.25], yaw: 0.5 };
    ada.world_mut().write_message(pose);
    ada.world_mut().write_message(EditRequest::player(Edit::Place { at: IVec3::new(6, 4, 6), material: 2 }));
    pump(&mut [&mut server, &mut ada], Duration::from_secs(10), |apps| seq(apps[0]) >= 1);

    // The network drops until the server has dropped the silent client (15 s): the client dials again by itself.
    let dropped = |apps: &mut [&mut App]| peer_names(apps[0]).is_empty();
    pump(&mut [&mut server], Duration::from_secs(40), dropped);
    pump(&mut [&mut server, &mut ada], Duration::from_secs(60), |apps| {
        let c = apps[1].world().resource::<NetClient>();
        c.loaded && c.returned_to.is_some()
    });
    let client = ada.world().resource::<NetClient>();
    assert_eq!(client.returned_to, Some(pose), "the server put ada back where she was");
    assert_eq!(client.seq, 1, "the world came again with the edit in it");
    assert_eq!(ada.world().resource::<VoxelWorld>().grid.get(IVec3::new(6, 4, 6)), 2);
    assert_eq!(ada.world().resource::<Rejoin>().attempts, 0, "joined: the backoff restarts");
    assert_eq!(peer_names(&mut server), ["ada"]);

    // Killed (no goodbye) and started again under the same name: back where the server last had her.
    drop(ada);
    pump(&mut [&mut server], Duration::from_secs(40), dropped);
    let mut again = join(addr, "ADA", 92);
    pump(&mut [&mut server, &mut again], Duration::from_secs(60), |apps| {
        let c = apps[1].world().resource::<NetClient>();
        c.loaded && c.returned_to.is_some()
    });
    assert_eq!(again.world().resource::<NetClient>().returned_to, Some(pose));
    // Her undo history waited on the server: Ctrl+Z in the new game takes back the block she placed before.
    let histories = server.world().resource::<glowbrick::net::server::Histories>();
    assert_eq!(histories.undo_len("Ada"), 1);
    again.world_mut().write_message(glowbrick::game::undo::HistoryAction::Undo);
    pump(&mut [&mut server, &mut again], Duration::from_secs(30), |apps| seq(apps[1]) == 2);
    for app in [&server, &again] {
        assert_eq!(app.world().resource::<VoxelWorld>().grid.get(IVec3::new(6, 4, 6)), 0, "undone everywhere");
    }
}

/// The "state: ..." line a server or bot printed.
fn state_of(stdout: &str) -> String {
    let line = stdout.lines().find(|l| l.contains("state: seq=")).unwrap_or_else(|| panic!("no state in: {stdout}"));
    line[line.find("state: ").unwrap()..].to_string()
}

#[test]
fn bots_in_their_own_processes_build_over_udp_and_end_with_the_servers_world() {
    use std::io::Write;
    use std::process::{Command, Stdio};
    let dir = std::env::temp_dir().join(format!("glowbrick-bots-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let save = dir.join("bots.ron");
    let port = free_port();
    let mut server = serve(&["--scene", "test-room", "--save", save.to_str().unwrap(), "--save-every", "3600"], port);
    let address = format!("127.0.0.1:{port}");
    let bots: Vec<Child> = (0..3)
        .map(|i| {
            Command::new(env!("CARGO_BIN_EXE_glowbrick"))
                .args(["bot", "--connect", &address, "--name", &format!("bot{i}"), "--seconds", "5"])
                .args(["--edits-per-second", "10"])
                .stdout(Stdio::piped())
                .stderr(Stdio::piped())
                .spawn()
                .expect("start a bot")
        })
        .collect();
    let states: Vec<String> = bots
        .into_iter()
        .map(|bot| {
            let out = bot.wait_with_output().unwrap();
            let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
            assert!(out.status.success(), "{stdout}\n{}", String::from_utf8_lossy(&out.stderr));
            state_of(&stdout)
        })
        .collect();
    server.stdin.as_mut().unwrap().write_all(b"quit\n").unwrap();
    let out = server.wait_with_output().unwrap();
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success(), "{stdout}");
    let expected = state_of(&stdout);
    let seq: u64 = expected["state: seq=".len()..].split(' ').next().unwrap().parse().unwrap();
    assert!(seq > 50, "three bots at 10 edits a second for 5 s applied {seq} edits: {stdout}");
    for (i, state) in states.iter().enumerate() {
        assert_eq!(state, &expected, "bot{i}'s world differs from the server's");
    }
    assert!(stdout.contains("ticks: ") && stdout.contains("p99 "), "the server reports its ticks: {stdout}");
    let _ = std::fs::remove_dir_all(&dir);
}
