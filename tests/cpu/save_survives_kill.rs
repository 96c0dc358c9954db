//! A crash during save (the process killed mid-write) never leaves a broken save: the save file always loads as
//! one of the complete worlds written, never a half-written one, and the next load clears what the killed save
//! left behind. The same runner as `glowbrick stress --saves N` (100 kills, docs/bench/stress.md), at 24 kills
//! (at 12, one of five runs here had fewer than two land mid-write);
//! the saving child is this test binary (ignored helper below).

use glowbrick::stress::kills::{run_kills, save_forever};
use glowbrick::world::format::{remove_stale_temporaries, save_world};
use glowbrick::world::recipe::generated_world;
use std::process::Command;

#[test]
#[ignore = "helper run by killed_saves_leave_a_complete_save; saves forever"]
fn saver_child() {
    let Some(path) = std::env::var_os("GLOWBRICK_SAVE_LOOP") else { return };
    save_forever(std::path::Path::new(&path)).unwrap();
}

#[test]
fn killed_saves_leave_a_complete_save() {
    let _alone = crate::EXCLUSIVE.lock().unwrap_or_else(|e| e.into_inner());
    let dir = std::env::temp_dir().join(format!("glowbrick-kill-{}", std::process::id()));
    let saver = |path: &std::path::Path| {
        let mut command = Command::new(std::env::current_exe().unwrap());
        command.args(["--ignored", "--exact", "save_survives_kill::saver_child", "--test-threads", "1", "--nocapture"]);
        command.env("GLOWBRICK_SAVE_LOOP", path);
        command
    };
    let report = run_kills(24, &dir, saver).unwrap();
    assert_eq!(report.kills, 24);
    assert_eq!(report.failure(), None, "{report}");
    // The kills landed inside writes, not only between them (a cycle is tens of milliseconds of writing).
    assert!(report.writing_backup + report.writing_save >= 2, "{report}");
    assert!(report.temporaries_left >= 2, "kills mid-write leave temporaries for the load to clear: {report}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn a_save_clears_a_dead_process_temporary_and_keeps_a_live_one() {
    let dir = std::env::temp_dir().join(format!("glowbrick-stale-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("w.ron");
    // PIDs above the kernel's maximum (4194304) never run; PID 1 (init) always does.
    let dead = [dir.join("w.ron.tmp4294967295"), dir.join("w.ron.bak.tmp4294967294")];
    let live = dir.join("w.ron.tmp1");
    let other = dir.join("w.ron.tmpnotapid");
    for file in dead.iter().chain([&live, &other]) {
        std::fs::write(file, b"half a save").unwrap();
    }
    save_world(&generated_world(1, bevy::math::UVec3::splat(16)).unwrap(), &path).unwrap();
    for file in &dead {
        assert!(!file.exists(), "{} survived the save", file.display());
    }
    assert!(live.exists(), "a save still running in another process keeps its temporary");
    assert!(other.exists(), "a file that is not a temporary of ours is left alone");
    assert_eq!(remove_stale_temporaries(&path), 0, "nothing stale is left");
    let _ = std::fs::remove_dir_all(&dir);
}
