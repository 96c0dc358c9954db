//! `glowbrick stress --saves N`: a child process saves two different worlds in a loop (with the game's
//! backup step, `save_with_backup`) and is killed (SIGKILL: no destructors, no cleanup) at N moments spread
//! evenly over one save cycle (as the child timed its first). After each kill the save and its backup must load as one of the two complete
//! worlds, and the next load must clear the temporaries the killed save left.
//!
//! Where a kill landed is read from what it left on disk: a `.bak.tmp<pid>` (the backup being written), a
//! `.tmp<pid>` (the new save being written), or neither (reading the old save for the backup, serialising the
//! new one, or between a rename and the next step).

use crate::game::save_load::{backup_path, save_with_backup};
use crate::progress::Progress;
use crate::world::format::{load_world, temporaries_of, world_to_string};
use crate::world::palette::Palette;
use crate::world::recipe::{SceneOp, SceneRecipe};
use crate::world::source::load_path;
use crate::world::terrain::TerrainParams;
use crate::world::{Edit, VoxelWorld};
use bevy::math::IVec3;
use std::io::{BufRead, BufReader, Write};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Two worlds that differ, big enough that one save takes tens of milliseconds: rolling hills (the first
/// terrain generator's recipe, 160 x 48 x 160, kept because its saves spend enough of a cycle writing that
/// kills land inside writes; the game's generator of issue 44 spends more of it serialising caves and trees).
pub fn two_worlds() -> Result<(VoxelWorld, VoxelWorld), String> {
    let a = rolling_hills().map_err(|e| e.to_string())?;
    let mut b = a.clone();
    b.apply(Edit::FillBox { min: IVec3::new(10, 30, 10), max: IVec3::new(150, 40, 150), material: 7 })
        .map_err(|e| e.to_string())?;
    Ok((a, b))
}

/// Hills of stone, dirt and grass with wooden posts and lamps scattered on them, 160 x 48 x 160.
fn rolling_hills() -> Result<VoxelWorld, crate::world::format::LoadError> {
    let scatter =
        |material: &str, count: u32, size: (i32, i32, i32)| SceneOp::Scatter { material: material.into(), count, size };
    let recipe = SceneRecipe {
        size: (160, 48, 160),
        seed: 21,
        materials: Palette::default_blocks().materials,
        ops: vec![
            SceneOp::Terrain {
                params: TerrainParams {
                    base_height: 14.4,
                    amplitude: 12.0,
                    frequency: 0.012,
                    octaves: 4,
                    soil_depth: 3,
                },
                rock: "stone".into(),
                soil: "dirt".into(),
                surface: "grass".into(),
            },
            scatter("wood", 28, (1, 5, 1)),
            scatter("lamp-warm", 17, (1, 2, 1)),
            scatter("lamp-blue", 6, (1, 1, 1)),
        ],
        views: Vec::new(),
    };
    recipe.build("kill-test hills")
}

/// The child's side: times one save cycle (`a` then `b`), says "ready MICROSECONDS" on stdout, then saves `a`
/// and `b` to `path` in turn until killed.
pub fn save_forever(path: &Path) -> Result<(), String> {
    let (a, b) = two_worlds()?;
    let save = |w: &VoxelWorld| save_with_backup(w, path).map_err(|e| format!("{}: {e}", path.display()));
    let start = Instant::now();
    save(&a)?;
    save(&b)?;
    println!("ready {}", start.elapsed().as_micros());
    std::io::stdout().flush().map_err(|e| e.to_string())?;
    loop {
        save(&a)?;
        save(&b)?;
    }
}

/// Where one kill landed, by what it left on disk.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Moment {
    WritingBackup,
    WritingSave,
    Between,
}

/// What the kills did.
#[derive(Clone, Debug, Default)]
pub struct KillReport {
    pub kills: u32,
    pub writing_backup: u32,
    pub writing_save: u32,
    pub between: u32,
    /// Kills after which the save did not load as a complete world.
    pub saves_lost: u32,
    /// Kills after which the backup existed but was not a complete world.
    pub backups_broken: u32,
    /// Temporaries left by a kill, and of those, still there after the next load.
    pub temporaries_left: u32,
    pub temporaries_after_load: u32,
    /// The longest save cycle (two saves with their backups) a saver measured before it was killed.
    pub cycle: Duration,
    pub problems: Vec<String>,
}

impl KillReport {
    pub fn failure(&self) -> Option<String> {
        (self.saves_lost + self.backups_broken + self.temporaries_after_load > 0).then(|| {
            format!(
                "{} saves lost, {} backups broken, {} temporaries not cleared; first: {}",
                self.saves_lost,
                self.backups_broken,
                self.temporaries_after_load,
                self.problems.first().map(String::as_str).unwrap_or("?")
            )
        })
    }
}

impl std::fmt::Display for KillReport {
    fn fmt(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
        writeln!(
            f,
            "kills {} spread over a save cycle of up to {:.1} ms: writing the backup {}, writing the save {}, between writes {}",
            self.kills,
            self.cycle.as_secs_f64() * 1e3,
            self.writing_backup,
            self.writing_save,
            self.between
        )?;
        writeln!(f, "saves lost {}, backups broken {}", self.saves_lost, self.backups_broken)?;
        write!(
            f,
            "temporaries left by a kill {}, still there after the next load {}",
            self.temporaries_left, self.temporaries_after_load
        )
    }
}

/// Starts the saver and waits for its "ready": the child and the length of its save cycle.
fn start_saver(mut command: Command) -> Result<(Child, Duration), String> {
    let mut child = command
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .map_err(|e| format!("cannot start the saver: {e}"))?;
    let stdout = child.stdout.take().ok_or("the saver has no stdout")?;
    // A test harness may print its own words first (libtest: "test NAME ... " before the test's output).
    let mut said = Vec::new();
    for line in BufReader::new(stdout).lines().take(20) {
        let line = line.map_err(|e| e.to_string())?;
        if let Some(us) = line.rsplit_once("ready ").and_then(|(_, us)| us.trim().parse::<u64>().ok()) {
            return Ok((child, Duration::from_micros(us)));
        }
        said.push(line);
    }
    let _ = child.kill();
    let _ = child.wait();
    Err(format!("the saver did not start (said {:?})", said.join(" / ")))
}

/// Kills `kills` savers, each started by `saver(path)` (a command that runs `save_forever(path)`), at moments
/// spread over one save cycle, and checks what each left in `dir`.
pub fn run_kills(kills: u32, dir: &Path, saver: impl Fn(&Path) -> Command) -> Result<KillReport, String> {
    if kills == 0 {
        return Err("--saves must be at least 1".into());
    }
    std::fs::create_dir_all(dir).map_err(|e| format!("{}: {e}", dir.display()))?;
    // A name of its own, so `--dir` pointed at a saves folder cannot touch a player's world.
    let path = dir.join("glowbrick-kill-test.ron");
    if path.exists() {
        return Err(format!("{} exists: is another kill test running there?", path.display()));
    }
    let (a, b) = two_worlds()?;
    let texts = [world_to_string(&a), world_to_string(&b)];
    let complete = |p: &Path| load_world(p).map(|w| texts.contains(&world_to_string(&w)));
    save_with_backup(&a, &path).map_err(|e| format!("{}: {e}", path.display()))?;
    let mut report = KillReport { kills, ..Default::default() };
    let progress = Progress::new("kills", kills as u64);
    for k in 0..kills {
        progress.advance(1);
        let (mut child, cycle) = start_saver(saver(&path))?;
        report.cycle = report.cycle.max(cycle);
        let pid = child.id();
        std::thread::sleep(cycle.mul_f64((k as f64 + 0.5) / kills as f64));
        child.kill().map_err(|e| e.to_string())?;
        child.wait().map_err(|e| e.to_string())?;
        let left = temporaries_of(&path);
        let mine = |backup: bool| {
            left.iter().any(|(p, owner)| *owner == pid && p.to_string_lossy().contains(".bak.tmp") == backup)
        };
        let moment = if mine(true) {
            Moment::WritingBackup
        } else if mine(false) {
            Moment::WritingSave
        } else {
            Moment::Between
        };
        match moment {
            Moment::WritingBackup => report.writing_backup += 1,
            Moment::WritingSave => report.writing_save += 1,
            Moment::Between => report.between += 1,
        }
        report.temporaries_left += left.len() as u32;
        // The next load: the save is complete, and the load clears the temporaries.
        match load_path(&path).map(|w| texts.contains(&world_to_string(&w))) {
            Ok(true) => {}
            Ok(false) => {
                report.saves_lost += 1;
                report.problems.push(format!("kill {k} ({moment:?}): the save is neither world"));
            }
            Err(e) => {
                report.saves_lost += 1;
                report.problems.push(format!("kill {k} ({moment:?}): the save does not load: {e}"));
            }
        }
        let backup = backup_path(&path);
        if backup.exists() && !matches!(complete(&backup), Ok(true)) {
            report.backups_broken += 1;
            report.problems.push(format!("kill {k} ({moment:?}): the backup is not a complete world"));
        }
        let after = temporaries_of(&path).len() as u32;
        report.temporaries_after_load += after;
        if after > 0 {
            report.problems.push(format!("kill {k} ({moment:?}): {after} temporaries survived the next load"));
        }
    }
    progress.finish();
    for file in [backup_path(&path), path] {
        let _ = std::fs::remove_file(file);
    }
    Ok(report)
}
