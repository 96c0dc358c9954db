//! FLIP (Andersson et al. 2020), the perceptual image difference real-time rendering papers report, computed by
//! NVIDIA's reference implementation (the `nv-flip` crate compiles and binds its C++ source).
//!
//! LDR-FLIP compares images as a viewer sees them: a linear image (EXR, or a frame in memory) is tonemapped and
//! sRGB-encoded exactly as `image_io::write_image` writes a PNG; a PNG is taken as it is. Viewing conditions are
//! FLIP's default, 67 pixels per degree (a 0.7 m wide 4K monitor seen from 0.7 m).

use crate::colour::srgb_to_linear;
use crate::image_io::{LinearImage, display_rgb8};

/// How an image's values are encoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Encoding {
    /// Linear radiance: tonemapped before comparing.
    Linear,
    /// Already display-encoded values in [0, 1] (a PNG as `read_image` returns it).
    Display,
}

/// The FLIP error of an image against a reference: its mean (0 = identical, 1 = as different as can be) and the
/// per-pixel map in FLIP's magma colours.
#[derive(Clone, Debug)]
pub struct FlipError {
    pub mean: f64,
    pub map: LinearImage,
}

fn to_bytes(image: &LinearImage, encoding: Encoding) -> Vec<u8> {
    match encoding {
        Encoding::Linear => display_rgb8(image),
        Encoding::Display => {
            image.pixels.iter().flat_map(|p| [0, 1, 2].map(|c| (p[c].clamp(0.0, 1.0) * 255.0).round() as u8)).collect()
        }
    }
}

/// FLIP of `image` against `reference`. Different sizes or an empty image are errors (the C++ code would abort).
pub fn flip(
    image: &LinearImage,
    image_encoding: Encoding,
    reference: &LinearImage,
    reference_encoding: Encoding,
) -> Result<FlipError, String> {
    let (w, h) = (image.width, image.height);
    if (w, h) != (reference.width, reference.height) {
        return Err(format!("images differ in size: {w}x{h} against {}x{}", reference.width, reference.height));
    }
    if image.pixels.is_empty() || image.pixels.len() != (w * h) as usize || reference.pixels.len() != image.pixels.len()
    {
        return Err(format!("image of {w}x{h} has {} pixels", image.pixels.len()));
    }
    let test = nv_flip::FlipImageRgb8::with_data(w, h, &to_bytes(image, image_encoding));
    let truth = nv_flip::FlipImageRgb8::with_data(w, h, &to_bytes(reference, reference_encoding));
    let errors = nv_flip::flip(truth, test, nv_flip::DEFAULT_PIXELS_PER_DEGREE);
    let mean = nv_flip::FlipPool::from_image(&errors).mean() as f64;
    let colours = errors.apply_color_lut(&nv_flip::magma_lut()).to_vec();
    // Stored linear, like every LinearImage: `write_png_plain` encodes it back to the same sRGB bytes.
    let pixels = colours
        .chunks_exact(3)
        .map(|c| [srgb_to_linear(c[0]), srgb_to_linear(c[1]), srgb_to_linear(c[2]), 1.0])
        .collect();
    Ok(FlipError { mean, map: LinearImage { width: w, height: h, pixels } })
}
