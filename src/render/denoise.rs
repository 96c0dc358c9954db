//! The spatiotemporal denoiser (SVGF family: Schied et al. 2017, with A-SVGF's restart on change), our own
//! compute passes after shading, on any GPU. The shading passes write the noisy frame instead of the image
//! (`write_output` in `shaders/lib/frame.wgsl`); then, per camera:
//!
//! 1. `temporal` (`shaders/denoise/temporal.wgsl`): demodulate (lighting / albedo, emission set aside),
//!    reproject last frame's history through the G-buffer (same face axis and sign, object and depth within
//!    10%), blend (1 / history length, at least 0.1), luminance moments give the variance (a 3x3 estimate while
//!    the history is short). No firefly clamp: one at 10x the brightest neighbour cost -5% of the mean and
//!    gained nothing (docs/bench/denoise.md).
//! 2. `wavelet` (`shaders/denoise/wavelet.wgsl`), passes 2 to 5: four a-trous iterations of a 5x5 B3-spline
//!    kernel (steps 1, 2, 4, 8 pixels), each tap kept only on the same voxel-face plane (voxel faces are flat: an
//!    exact edge stop) and weighted by luminance against the larger variance of the pair (each pixel's own
//!    darkened the image by 5%: a dark pixel refused a bright neighbour's light); the last remodulates (albedo x
//!    filtered + emission), draws the highlight and writes the image.
//!
//! The history restarts on frames where an edit changed the world or its lights (`frame::prepare_view_resources`),
//! so a lamp switched on or off shows at once, noisier for a few frames. Off (`denoise=off`, `render`'s
//! default) none of the passes runs and the shading passes write the image themselves.

use super::frame::{Dispatch, VoxelPass};

const fn pass(name: &'static str, shader: &'static str, entry_point: &'static str) -> VoxelPass {
    VoxelPass { name, shader, entry_point, dispatch: Dispatch::Pixels }
}

/// The passes in dispatch order.
pub const PASSES: [VoxelPass; 5] = [
    pass("glowbrick_denoise_temporal", "denoise/temporal.wgsl", "main"),
    pass("glowbrick_denoise_wavelet_1", "denoise/wavelet.wgsl", "step_1"),
    pass("glowbrick_denoise_wavelet_2", "denoise/wavelet.wgsl", "step_2"),
    pass("glowbrick_denoise_wavelet_4", "denoise/wavelet.wgsl", "step_4"),
    pass("glowbrick_denoise_wavelet_8", "denoise/wavelet.wgsl", "step_8_and_write"),
];

/// GPU-time names of the passes, in dispatch order.
pub const DENOISE_PASS_NAMES: [&str; 5] =
    [PASSES[0].name, PASSES[1].name, PASSES[2].name, PASSES[3].name, PASSES[4].name];
