//! `glowbrick compare`: the error of one image against a reference (MAE, MSE, relMSE, bias and FLIP), optionally
//! as a false-colour image of the absolute error or the FLIP map.

use super::check_output;
use crate::image_io::{read_image, write_png_plain};
use crate::reference::flip::{Encoding, flip};
use crate::reference::metrics;
use clap::{Args, ValueEnum};
use std::path::{Path, PathBuf};

#[derive(Args)]
pub struct CompareArgs {
    image: PathBuf,
    reference: PathBuf,
    /// Also write a false-colour error image (PNG).
    #[arg(long)]
    diff: Option<PathBuf>,
    /// What `--diff` shows: the absolute error (white at 4x the MAE) or the FLIP map (magma).
    #[arg(long, value_enum, default_value_t = DiffKind::Absolute)]
    diff_kind: DiffKind,
    /// Clamp every channel of both images to at most this before measuring (1: what an 8-bit export without
    /// tone mapping holds).
    #[arg(long)]
    clamp: Option<f32>,
}

#[derive(Clone, Copy, Debug, ValueEnum)]
enum DiffKind {
    Absolute,
    Flip,
}

/// A PNG holds display values; anything else (EXR) linear radiance.
fn encoding_of(path: &Path) -> Encoding {
    let png = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("png"));
    if png { Encoding::Display } else { Encoding::Linear }
}

impl CompareArgs {
    pub fn run(self) -> Result<(), String> {
        if let Some(path) = &self.diff {
            check_output(path, &["png"])?;
        }
        let (mut a, mut b) = (read_image(&self.image)?, read_image(&self.reference)?);
        if let Some(limit) = self.clamp {
            if !(limit.is_finite() && limit > 0.0) {
                return Err(format!("--clamp {limit} must be a positive number"));
            }
            (a, b) = (a.clamped(limit), b.clamped(limit));
        }
        let m = metrics::compare(&a, &b)?;
        let flip = flip(&a, encoding_of(&self.image), &b, encoding_of(&self.reference))?;
        if let Some(path) = self.diff {
            let picture = match self.diff_kind {
                // White at four times the mean absolute error: the worst pixels stand out.
                DiffKind::Absolute => metrics::error_image(&a, &b, (4.0 * m.mae).max(1e-6) as f32),
                DiffKind::Flip => flip.map,
            };
            write_png_plain(&picture, &path)?;
        }
        // The reference's mean says what a bias is a share of.
        println!("{m} flip={:.6} reference_mean={:.6}", flip.mean, b.mean_luminance());
        Ok(())
    }
}
