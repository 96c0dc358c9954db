//! `glowbrick stress`: the soak of the renderer (default), or `--fuzz N` inputs through the loaders, or
//! `--saves N` kills of a saving process. A failed check is exit code 1.

use super::on_gpu;
use crate::stress::fuzz::{FuzzConfig, Target, replay, run_fuzz};
use crate::stress::kills::{run_kills, save_forever};
use crate::stress::{StressConfig, run_stress};
use clap::Args;
use std::path::PathBuf;
use std::process::Command;

#[derive(Args)]
pub struct StressArgs {
    /// A short run (330 frames at 64x48, every soaked configuration once) for CI.
    #[arg(long)]
    quick: bool,
    /// Frames of the soak (default 5000, or 330 with --quick).
    #[arg(long)]
    frames: Option<u32>,
    #[arg(long, default_value = "test-room")]
    scene: String,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Instead of the soak: N corrupted inputs, split over the loaders (world, recipe, vx, vox, settings).
    #[arg(long, value_name = "N", conflicts_with_all = ["quick", "frames", "saves"])]
    fuzz: Option<u64>,
    /// With --fuzz: only these loaders (repeatable).
    #[arg(long = "fuzz-target", value_name = "NAME", requires = "fuzz")]
    fuzz_targets: Vec<String>,
    /// Replays one fuzz input, TARGET:INDEX (with the run's --seed); --fuzz-save writes its bytes.
    #[arg(long, value_name = "TARGET:INDEX", conflicts_with_all = ["quick", "frames", "saves", "fuzz"])]
    fuzz_only: Option<String>,
    #[arg(long, value_name = "FILE", requires = "fuzz_only")]
    fuzz_save: Option<PathBuf>,
    /// Threads of the fuzzer (default: every core).
    #[arg(long)]
    threads: Option<usize>,
    /// Instead of the soak: kill a saving process N times and check no save is lost.
    #[arg(long, value_name = "N", conflicts_with_all = ["quick", "frames"])]
    saves: Option<u32>,
    /// Where --saves and --fuzz write (default: a folder in the system's temporary directory).
    #[arg(long, value_name = "DIR")]
    dir: Option<PathBuf>,
    /// The saving child of --saves (not for people).
    #[arg(long, hide = true, value_name = "PATH")]
    save_loop: Option<PathBuf>,
}

impl StressArgs {
    pub fn run(self) -> Result<(), String> {
        let start = std::time::Instant::now();
        let dir = self
            .dir
            .clone()
            .unwrap_or_else(|| std::env::temp_dir().join(format!("glowbrick-stress-{}", std::process::id())));
        if let Some(path) = &self.save_loop {
            return save_forever(path);
        }
        if let Some(which) = &self.fuzz_only {
            let (target, index) = which.split_once(':').ok_or_else(|| format!("'{which}' is not TARGET:INDEX"))?;
            let index: u64 = index.parse().map_err(|_| format!("'{index}' is not an input number"))?;
            let answer = replay(Target::from_name(target)?, self.seed, index, self.fuzz_save.as_deref())?;
            println!("{answer}");
            return Ok(());
        }
        if let Some(inputs) = self.fuzz {
            let targets = match self.fuzz_targets.is_empty() {
                true => Target::ALL.to_vec(),
                false => self.fuzz_targets.iter().map(|t| Target::from_name(t)).collect::<Result<_, _>>()?,
            };
            if inputs == 0 || inputs > 1_000_000_000 {
                return Err(format!("--fuzz {inputs} must be within 1..=1000000000"));
            }
            let threads = self.threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
            if threads == 0 || threads > 256 {
                return Err(format!("--threads {threads} must be within 1..=256"));
            }
            let config =
                FuzzConfig { inputs, targets, seed: self.seed, threads, findings_dir: dir.join("fuzz-findings") };
            let report = run_fuzz(&config)?;
            println!("{report}\n({:.1} s on {threads} threads)", start.elapsed().as_secs_f64());
            return report.failure().map_or(Ok(()), |why| Err(format!("fuzz failed: {why}")));
        }
        if let Some(kills) = self.saves {
            if kills > 100_000 {
                return Err(format!("--saves {kills} must be within 1..=100000"));
            }
            let exe = std::env::current_exe().map_err(|e| format!("cannot find this program to run the saver: {e}"))?;
            let saver = |path: &std::path::Path| {
                let mut command = Command::new(&exe);
                command.arg("stress").arg("--save-loop").arg(path);
                command
            };
            let report = run_kills(kills, &dir, saver)?;
            let _ = std::fs::remove_dir(&dir); // only when empty: never anything of the user's
            println!("{report}\n({:.1} s)", start.elapsed().as_secs_f64());
            return report.failure().map_or(Ok(()), |why| Err(format!("kills failed: {why}")));
        }
        let mut config = if self.quick { StressConfig::quick() } else { StressConfig::full() };
        config.frames = self.frames.unwrap_or(config.frames);
        if config.frames == 0 || config.frames > 1_000_000 {
            return Err(format!("--frames {} must be within 1..=1000000", config.frames));
        }
        config.scene = self.scene;
        config.seed = self.seed;
        let report = on_gpu(|| run_stress(&config))?;
        println!("{report}\n({:.1} s)", start.elapsed().as_secs_f64());
        match report.failure() {
            Some(why) => Err(format!("stress failed: {why}")),
            None => Ok(()),
        }
    }
}
