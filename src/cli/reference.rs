//! `glowbrick reference`: the CPU ground truth (direct light, or with `--bounces` diffuse bounces) of a view.

use super::args::ShotArgs;
use super::check_output;
use crate::image_io::write_image;
use crate::reference::{ReferenceOptions, render_reference};
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct ReferenceArgs {
    #[command(flatten)]
    shot: ShotArgs,
    /// Samples per pixel.
    #[arg(long, default_value_t = 256)]
    spp: u32,
    /// Diffuse bounces after the camera hit (0: direct light only).
    #[arg(long, default_value_t = 0)]
    bounces: u32,
    /// Stop after this many seconds (after a whole batch of samples).
    #[arg(long)]
    seconds: Option<f64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Lights resampled per shadow ray (1: plain next-event estimation by power).
    #[arg(long, default_value_t = 16)]
    candidates: u32,
    /// Output image (.exr keeps linear values).
    #[arg(long)]
    out: PathBuf,
}

impl ReferenceArgs {
    pub fn run(self) -> Result<(), String> {
        let (world, view) = self.shot.world_and_view("reference")?;
        check_output(&self.out, &["exr", "png"])?;
        if let Some(s) = self.seconds.filter(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(format!("--seconds {s} must be a positive number"));
        }
        let options = ReferenceOptions {
            width: self.shot.width,
            height: self.shot.height,
            spp: self.spp,
            bounces: self.bounces,
            seed: self.seed,
            candidates: self.candidates,
            time_budget: self.seconds.map(std::time::Duration::from_secs_f64),
            show_progress: true,
        };
        let result = render_reference(&world, &view, &options)?;
        write_image(&result.image, &self.out)?;
        println!(
            "wrote {} ({}x{}, view '{}', {} spp, {} bounces, {} candidates, {:.1} s, {:.2} Mrays/s)",
            self.out.display(),
            self.shot.width,
            self.shot.height,
            view.name,
            result.spp,
            self.bounces,
            self.candidates,
            result.elapsed.as_secs_f64(),
            result.rays_per_second() / 1e6
        );
        Ok(())
    }
}
