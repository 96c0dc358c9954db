//! `glowbrick stress`: the headless soak of the renderer; a failed check is exit code 1.

use super::on_gpu;
use crate::stress::{StressConfig, run_stress};
use clap::Args;

#[derive(Args)]
pub struct StressArgs {
    /// A short run (240 frames at 64x48) for CI.
    #[arg(long)]
    quick: bool,
    /// Frames of the soak (default 5000, or 240 with --quick).
    #[arg(long)]
    frames: Option<u32>,
    #[arg(long, default_value = "test-room")]
    scene: String,
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

impl StressArgs {
    pub fn run(self) -> Result<(), String> {
        let mut config = if self.quick { StressConfig::quick() } else { StressConfig::full() };
        config.frames = self.frames.unwrap_or(config.frames);
        if config.frames == 0 || config.frames > 1_000_000 {
            return Err(format!("--frames {} must be within 1..=1000000", config.frames));
        }
        config.scene = self.scene;
        config.seed = self.seed;
        let start = std::time::Instant::now();
        let report = on_gpu(|| run_stress(&config))?;
        println!("{report}\n({:.1} s)", start.elapsed().as_secs_f64());
        match report.failure() {
            Some(why) => Err(format!("stress failed: {why}")),
            None => Ok(()),
        }
    }
}
