//! Image metrics over linear RGB, as seed 000 §3.3 defines MAE and MSE, plus relMSE and the signed luminance bias.
//!
//! - MSE = sum over pixels of (dr^2 + dg^2 + db^2) / (pixels * 3)   (seed 000 eq. 1-2)
//! - MAE = sum over pixels of (|dr| + |dg| + |db|) / (pixels * 3)  (seed 000 eq. 3-4)
//! - relMSE = mean over pixels and channels of d^2 / (reference^2 + 0.01) (the 0.01 keeps black pixels finite)
//! - bias = mean luminance of the image minus that of the reference (negative: darker, as biased ReSTIR is)
//! - fireflies = pixels whose luminance is above 100x the reference's plus 1 (issue 15's count)

use crate::colour::luminance;
use crate::image_io::LinearImage;

/// Errors of an image against a reference.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Metrics {
    pub mae: f64,
    pub mse: f64,
    pub relmse: f64,
    pub bias: f64,
    pub fireflies: u64,
}

impl std::fmt::Display for Metrics {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "mae={:.6} mse={:.6} relmse={:.6} bias={:+.6}", self.mae, self.mse, self.relmse, self.bias)
    }
}

const RELMSE_EPSILON: f64 = 0.01;

/// Compares `image` against `reference`. Different sizes or a non-finite pixel in either are errors.
pub fn compare(image: &LinearImage, reference: &LinearImage) -> Result<Metrics, String> {
    if (image.width, image.height) != (reference.width, reference.height) {
        return Err(format!(
            "images differ in size: {}x{} against {}x{}",
            image.width, image.height, reference.width, reference.height
        ));
    }
    if image.pixels.is_empty() {
        return Err("images are empty".into());
    }
    for (name, img) in [("image", image), ("reference", reference)] {
        if let Some(i) = img.pixels.iter().position(|p| p[..3].iter().any(|c| !c.is_finite())) {
            let (x, y) = (i as u32 % img.width, i as u32 / img.width);
            return Err(format!("{name} has a non-finite pixel at ({x}, {y}): {:?}", img.pixels[i]));
        }
    }
    let (mut abs, mut sq, mut rel, mut lum_a, mut lum_b) = (0.0f64, 0.0f64, 0.0f64, 0.0f64, 0.0f64);
    let mut fireflies = 0u64;
    for (a, b) in image.pixels.iter().zip(&reference.pixels) {
        for c in 0..3 {
            let d = (a[c] - b[c]) as f64;
            abs += d.abs();
            sq += d * d;
            rel += d * d / ((b[c] as f64).powi(2) + RELMSE_EPSILON);
        }
        let (la, lb) = (luminance([a[0], a[1], a[2]]) as f64, luminance([b[0], b[1], b[2]]) as f64);
        fireflies += (la > 100.0 * lb + 1.0) as u64;
        lum_a += la;
        lum_b += lb;
    }
    let n = image.pixels.len() as f64;
    Ok(Metrics {
        mae: abs / (3.0 * n),
        mse: sq / (3.0 * n),
        relmse: rel / (3.0 * n),
        bias: (lum_a - lum_b) / n,
        fireflies,
    })
}

/// A false-colour image of the per-pixel absolute error (mean over channels), black to red to yellow to white,
/// scaled so `scale` maps to white.
pub fn error_image(image: &LinearImage, reference: &LinearImage, scale: f32) -> LinearImage {
    let pixels = image
        .pixels
        .iter()
        .zip(&reference.pixels)
        .map(|(a, b)| {
            let e = ((0..3).map(|c| (a[c] - b[c]).abs()).sum::<f32>() / 3.0 / scale.max(1e-12)).clamp(0.0, 1.0);
            // Piecewise ramp; values are linear and become sRGB when written as PNG.
            [(e * 3.0).min(1.0), (e * 3.0 - 1.0).clamp(0.0, 1.0), (e * 3.0 - 2.0).clamp(0.0, 1.0), 1.0]
        })
        .collect();
    LinearImage { width: image.width, height: image.height, pixels }
}
