//! `glowbrick reference`: the CPU ground truth (direct light, or with `--bounces` diffuse bounces) of a view,
//! under the lighting `render` uses: the `--set` keys `lighting`, `time` and `sun` (others are `render`'s own).

use super::args::{SettingArgs, ShotArgs};
use super::check_output;
use crate::image_io::write_image;
use crate::reference::{ReferenceOptions, render_reference};
use crate::settings::Lighting;
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
    /// Only the light that reaches the camera's hits by bouncing: what `render --set debug=indirect` shows of the
    /// GI cache (no emission, direct light or disk at the hit; the sky its bounce finds counts).
    #[arg(long)]
    indirect: bool,
    /// Stop after this many seconds (after a whole batch of samples).
    #[arg(long)]
    seconds: Option<f64>,
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Lights resampled per shadow ray (1: plain next-event estimation by power).
    #[arg(long, default_value_t = 16)]
    candidates: u32,
    #[command(flatten)]
    settings: SettingArgs,
    /// Output image (.exr keeps linear values).
    #[arg(long)]
    out: PathBuf,
}

impl ReferenceArgs {
    pub fn run(self) -> Result<(), String> {
        self.settings.settings()?;
        let (world, view) = self.shot.world_and_view("reference")?;
        let settings = self.settings.settings_for(&world)?;
        if settings.lighting == Lighting::Sun {
            return Err("lighting=sun is a debug look with no ground truth; use lighting=full (the same sun and \
                        sky, physically) or lighting=emitters"
                .into());
        }
        check_output(&self.out, &["exr", "png"])?;
        if let Some(s) = self.seconds.filter(|s| !(s.is_finite() && *s > 0.0)) {
            return Err(format!("--seconds {s} must be a positive number"));
        }
        let options = ReferenceOptions {
            width: self.shot.width,
            height: self.shot.height,
            spp: self.spp,
            bounces: self.bounces,
            indirect_only: self.indirect,
            seed: self.seed,
            candidates: self.candidates,
            time_budget: self.seconds.map(std::time::Duration::from_secs_f64),
            show_progress: true,
            daylight: settings.daylight(),
            lattice: 1,
        };
        let result = render_reference(&world, &view, &options)?;
        write_image(&result.image, &self.out)?;
        println!(
            "wrote {} ({}x{}, view '{}', lighting={} time={}, {} spp, {} bounces, {} candidates, {:.1} s, {:.2} Mrays/s)",
            self.out.display(),
            self.shot.width,
            self.shot.height,
            view.name,
            crate::settings::Named::name(settings.lighting),
            settings.time,
            result.spp,
            self.bounces,
            self.candidates,
            result.elapsed.as_secs_f64(),
            result.rays_per_second() / 1e6
        );
        Ok(())
    }
}
