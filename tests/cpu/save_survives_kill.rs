//! A crash during save (the process killed mid-write) never leaves a broken save: the save file always loads as
//! one of the complete worlds written, never a half-written one. The test runs a child process (this test
//! binary, ignored helper below) that saves two different worlds in a loop, and kills it at random moments.

use bevy::math::{IVec3, UVec3};
use glowbrick::game::save_load::save_with_backup;
use glowbrick::world::format::{load_world, world_to_string};
use glowbrick::world::scene::generated_world;
use glowbrick::world::{Edit, VoxelWorld};
use std::process::{Command, Stdio};
use std::time::Duration;

/// Two worlds that differ, big enough that a save takes a while (tens of milliseconds).
fn worlds() -> (VoxelWorld, VoxelWorld) {
    let a = generated_world(21, UVec3::new(160, 48, 160)).unwrap();
    let mut b = a.clone();
    b.apply(Edit::FillBox { min: IVec3::new(10, 30, 10), max: IVec3::new(150, 40, 150), material: 7 }).unwrap();
    (a, b)
}

#[test]
#[ignore = "helper run by killed_saves_leave_a_complete_save; saves forever"]
fn saver_child() {
    let Some(path) = std::env::var_os("GLOWBRICK_SAVE_LOOP") else { return };
    let (a, b) = worlds();
    loop {
        save_with_backup(&a, std::path::Path::new(&path)).unwrap();
        save_with_backup(&b, std::path::Path::new(&path)).unwrap();
    }
}

#[test]
fn killed_saves_leave_a_complete_save() {
    let dir = std::env::temp_dir().join(format!("glowbrick-kill-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("world.ron");
    let (a, b) = worlds();
    let (text_a, text_b) = (world_to_string(&a), world_to_string(&b));
    save_with_backup(&a, &path).unwrap();
    for (round, wait_ms) in [35u64, 60, 80, 105, 120, 150, 170, 210, 260, 290, 330, 370].into_iter().enumerate() {
        let mut child = Command::new(std::env::current_exe().unwrap())
            .args(["--ignored", "--exact", "save_survives_kill::saver_child", "--test-threads", "1"])
            .env("GLOWBRICK_SAVE_LOOP", &path)
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .unwrap();
        std::thread::sleep(Duration::from_millis(wait_ms));
        child.kill().unwrap(); // SIGKILL: no destructors, no cleanup
        child.wait().unwrap();
        let loaded = load_world(&path).unwrap_or_else(|e| panic!("round {round}: the save is broken: {e}"));
        let text = world_to_string(&loaded);
        assert!(text == text_a || text == text_b, "round {round}: the save is neither complete world");
        // The backup, when present, is complete too.
        let backup = dir.join("world.ron.bak");
        if backup.exists() {
            let text = world_to_string(&load_world(&backup).unwrap());
            assert!(text == text_a || text == text_b, "round {round}: the backup is broken");
        }
    }
}
