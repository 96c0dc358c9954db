//! `glowbrick render`: a world rendered headless (no window) to a PNG (tonemapped) or EXR (linear) image.

use super::args::{SettingArgs, ShotArgs};
use super::{check_output, on_gpu};
use crate::headless::{HeadlessOptions, render_headless};
use crate::image_io::write_image;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct RenderArgs {
    #[command(flatten)]
    shot: ShotArgs,
    /// Frames to render before writing the last one.
    #[arg(long, default_value_t = 1)]
    frames: u32,
    #[command(flatten)]
    settings: SettingArgs,
    /// Output image: .png (tonemapped) or .exr (linear float).
    #[arg(long)]
    out: PathBuf,
}

impl RenderArgs {
    pub fn run(self) -> Result<(), String> {
        // Bad settings are refused before the world is read; the world's saved time of day goes under them.
        self.settings.settings()?;
        let (world, view) = self.shot.world_and_view("render")?;
        let settings = self.settings.settings_for(&world)?;
        check_output(&self.out, &["png", "exr"])?;
        let options = HeadlessOptions {
            width: self.shot.width,
            height: self.shot.height,
            frames: self.frames,
            settings,
            ..Default::default()
        };
        let start = std::time::Instant::now();
        let image = on_gpu(|| render_headless(world, &view, &options))?;
        write_image(&image, &self.out)?;
        println!(
            "wrote {} ({}x{}, view '{}', {} frames, {:.2} s)",
            self.out.display(),
            image.width,
            image.height,
            view.name,
            self.frames,
            start.elapsed().as_secs_f64()
        );
        Ok(())
    }
}
