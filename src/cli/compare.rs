//! `glowbrick compare`: the error of one image against a reference, optionally as a false-colour image.

use super::check_output;
use crate::image_io::{read_image, write_png_plain};
use crate::reference::metrics;
use clap::Args;
use std::path::PathBuf;

#[derive(Args)]
pub struct CompareArgs {
    image: PathBuf,
    reference: PathBuf,
    /// Also write a false-colour error image (PNG).
    #[arg(long)]
    diff: Option<PathBuf>,
}

impl CompareArgs {
    pub fn run(self) -> Result<(), String> {
        let a = read_image(&self.image)?;
        let b = read_image(&self.reference)?;
        let m = metrics::compare(&a, &b)?;
        if let Some(path) = self.diff {
            check_output(&path, &["png"])?;
            // White at four times the mean absolute error: the worst pixels stand out.
            write_png_plain(&metrics::error_image(&a, &b, (4.0 * m.mae).max(1e-6) as f32), &path)?;
        }
        println!("{m}");
        Ok(())
    }
}
