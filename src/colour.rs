//! Colour helpers shared by every layer: luminance, the ACES tonemapping curve and the sRGB transfer functions.

/// Rec. 709 luminance weights of linear R, G and B (the shaders' `luminance` uses the same; a CPU test checks).
pub const LUMINANCE_WEIGHTS: [f32; 3] = [0.2126, 0.7152, 0.0722];

/// Rec. 709 luminance of linear RGB.
pub fn luminance(rgb: [f32; 3]) -> f32 {
    let [r, g, b] = LUMINANCE_WEIGHTS;
    r * rgb[0] + g * rgb[1] + b * rgb[2]
}

/// ACES filmic fit (Narkowicz 2015): maps linear HDR radiance to [0, 1].
pub fn tonemap_aces(x: f32) -> f32 {
    // Past 1e4 the curve is 1 anyway; capping keeps x^2 from overflowing to inf / inf = NaN (black pixels).
    let x = x.clamp(0.0, 1.0e4);
    ((x * (2.51 * x + 0.03)) / (x * (2.43 * x + 0.59) + 0.14)).clamp(0.0, 1.0)
}

/// Linear [0, 1] to the sRGB transfer curve.
pub fn linear_to_srgb(x: f32) -> f32 {
    if x <= 0.003_130_8 { x * 12.92 } else { 1.055 * x.powf(1.0 / 2.4) - 0.055 }
}

/// An 8-bit sRGB channel as a linear value.
pub fn srgb_to_linear(c: u8) -> f32 {
    let c = c as f32 / 255.0;
    if c <= 0.04045 { c / 12.92 } else { ((c + 0.055) / 1.055).powf(2.4) }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tonemapping_never_turns_a_bright_pixel_black() {
        for x in [1.0e4f32, 1.0e20, f32::MAX, f32::INFINITY] {
            assert_eq!(tonemap_aces(x), 1.0, "{x}");
        }
        assert_eq!(tonemap_aces(-1.0), 0.0);
        assert!((tonemap_aces(0.18) - 0.2666).abs() < 1e-3, "{}", tonemap_aces(0.18));
    }

    #[test]
    fn srgb_round_trips_every_byte() {
        for c in 0..=255u8 {
            assert_eq!((linear_to_srgb(srgb_to_linear(c)) * 255.0).round() as u8, c);
        }
        assert_eq!(luminance([1.0, 1.0, 1.0]), 1.0);
    }
}
