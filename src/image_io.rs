//! Linear float images: writing EXR (linear values kept) and PNG (tonemapped and sRGB-encoded).

use crate::colour::{linear_to_srgb, luminance, tonemap_aces};
use image::{ImageBuffer, Rgb, Rgba32FImage};
use std::path::Path;

/// A linear RGBA float image, rows top to bottom.
#[derive(Clone, Debug, PartialEq)]
pub struct LinearImage {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<[f32; 4]>,
}

impl LinearImage {
    pub fn pixel(&self, x: u32, y: u32) -> [f32; 4] {
        self.pixels[(y * self.width + x) as usize]
    }

    /// Every `step`-th pixel in each direction, at `step * i + step / 2`: the pixels a reference with
    /// `lattice: step` integrates (`reference::ReferenceOptions`). `step` must be at least 1.
    pub fn lattice(&self, step: u32) -> LinearImage {
        let (width, height) = (self.width / step, self.height / step);
        let pixels = (0..width * height)
            .map(|i| self.pixel((i % width) * step + step / 2, (i / width) * step + step / 2))
            .collect();
        LinearImage { width, height, pixels }
    }

    /// Every colour channel clamped to at most `limit` (alpha kept): what an 8-bit export without tone mapping
    /// holds at `limit` 1, e.g. to compare with numbers measured on such exports.
    pub fn clamped(&self, limit: f32) -> LinearImage {
        let pixels = self.pixels.iter().map(|p| [p[0].min(limit), p[1].min(limit), p[2].min(limit), p[3]]).collect();
        LinearImage { pixels, ..*self }
    }

    /// The pixel-wise mean of images of one size (e.g. successive frames accumulated); an empty slice gives an
    /// empty image.
    pub fn mean_of(images: &[LinearImage]) -> LinearImage {
        let Some(first) = images.first() else { return LinearImage { width: 0, height: 0, pixels: Vec::new() } };
        let mut sum = vec![[0.0f64; 4]; first.pixels.len()];
        for image in images {
            for (s, p) in sum.iter_mut().zip(&image.pixels) {
                for c in 0..4 {
                    s[c] += p[c] as f64;
                }
            }
        }
        let n = images.len() as f64;
        let pixels = sum.iter().map(|s| s.map(|v| (v / n) as f32)).collect();
        LinearImage { pixels, ..*first }
    }

    /// Count of pixels with a NaN or infinite channel.
    pub fn non_finite_pixels(&self) -> usize {
        self.pixels.iter().filter(|p| p.iter().any(|c| !c.is_finite())).count()
    }

    /// Mean Rec. 709 luminance of the pixels.
    pub fn mean_luminance(&self) -> f64 {
        let sum: f64 = self.pixels.iter().map(|p| luminance([p[0], p[1], p[2]]) as f64).sum();
        sum / self.pixels.len().max(1) as f64
    }
}

/// Writes `.exr` (linear float) or `.png` (tonemapped 8-bit sRGB), by the file's extension.
pub fn write_image(image: &LinearImage, path: &Path) -> Result<(), String> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    let result = match ext.as_deref() {
        Some("exr") => {
            let flat: Vec<f32> = image.pixels.iter().flatten().copied().collect();
            let buffer = Rgba32FImage::from_raw(image.width, image.height, flat).ok_or("image size mismatch")?;
            buffer.save(path)
        }
        Some("png") => {
            match ImageBuffer::<Rgb<u8>, Vec<u8>>::from_raw(image.width, image.height, display_rgb8(image)) {
                Some(buffer) => buffer.save(path),
                None => return Err(format!("{}: image size mismatch", path.display())),
            }
        }
        _ => return Err(format!("{}: output must end in .png or .exr", path.display())),
    };
    result.map_err(|e| format!("{}: cannot write image: {e}", path.display()))
}

/// The image as a viewer sees it: tonemapped (ACES), sRGB-encoded, 8 bits per channel, RGB rows.
pub fn display_rgb8(image: &LinearImage) -> Vec<u8> {
    image
        .pixels
        .iter()
        .flat_map(|p| [0, 1, 2].map(|c| (linear_to_srgb(tonemap_aces(p[c])) * 255.0 + 0.5) as u8))
        .collect()
}

/// Values already in [0, 1] (false colour, debug views; no tonemapping), sRGB-encoded, 8 bits, RGB rows.
pub fn plain_rgb8(image: &LinearImage) -> Vec<u8> {
    image
        .pixels
        .iter()
        .flat_map(|p| [0, 1, 2].map(|c| (linear_to_srgb(p[c].clamp(0.0, 1.0)) * 255.0 + 0.5) as u8))
        .collect()
}

/// Writes a PNG of values already in [0, 1] (sRGB-encoded, no tonemapping): false-colour and debug images.
pub fn write_png_plain(image: &LinearImage, path: &Path) -> Result<(), String> {
    let buffer = ImageBuffer::<Rgb<u8>, Vec<u8>>::from_raw(image.width, image.height, plain_rgb8(image))
        .ok_or_else(|| format!("{}: image size mismatch", path.display()))?;
    buffer.save(path).map_err(|e| format!("{}: cannot write image: {e}", path.display()))
}

/// Reads a linear float image (EXR, or anything the `image` crate decodes) with a clear one-line error.
pub fn read_image(path: &Path) -> Result<LinearImage, String> {
    let decoded = image::open(path).map_err(|e| format!("{}: cannot read image: {e}", path.display()))?;
    let rgba = decoded.into_rgba32f();
    let (width, height) = rgba.dimensions();
    let pixels = rgba.pixels().map(|p| p.0).collect();
    Ok(LinearImage { width, height, pixels })
}
