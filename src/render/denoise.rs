//! The spatiotemporal denoiser (SVGF family: Schied et al. 2017, with A-SVGF's restart on change), our own
//! compute passes after shading, on any GPU. The shading passes write the noisy frame instead of the image
//! (`write_output` in `shaders/lib/frame.wgsl`); then, per camera:
//!
//! 1. `temporal` (`shaders/denoise/temporal.wgsl`): demodulate (lighting / albedo, emission set aside),
//!    reproject last frame's history through the G-buffer (same face axis and sign, object and depth within
//!    10%), blend (1 / history length, at least 0.1), luminance moments give the variance (a 3x3 estimate while
//!    the history is short). No firefly clamp: one at 10x the brightest neighbour darkened the mean and
//!    gained nothing (docs/bench/denoise.md).
//! 2. `wavelet` (`shaders/denoise/wavelet.wgsl`), passes 2 to 6: five a-trous iterations of a 3x3 binomial
//!    kernel (steps 1, 2, 4, 8, 16 pixels: 45 taps a pixel where four 5x5 B3 iterations took 100), each tap kept
//!    only on the same voxel-face plane (voxel faces are flat: an exact edge stop) and weighted by luminance
//!    against the larger variance of the pair (each pixel's own darkened the image: a dark pixel refused a
//!    bright neighbour's light); the last remodulates (albedo x filtered + emission), draws the highlight and
//!    writes the image.
//!
//! Its per-view state (`DenoiseView`): the noisy frame, the history (this and last frame's, swapped), the wavelet's
//! ping-pong, and the rule that restarts the history on frames where an edit changed the world or its lights,
//! so a lamp switched on or off shows at once, noisier for a few frames. Off (`denoise=off`, `render`'s
//! default) none of the passes runs and the shading passes write the image themselves.

use super::gpu_types::{DENOISE_HISTORY, DENOISE_ON, DENOISE_TEXEL_BYTES, FrameParams};
use super::interface::GpuBinding;
use super::pass::{Dispatch, VoxelPass};
use super::plan::FramePlan;
use super::view::{ViewPart, ViewPartKind};
use crate::settings::RenderSettings;
use bevy::render::render_resource::{BindingResource, Buffer, BufferDescriptor, BufferUsages};
use bevy::render::renderer::RenderDevice;
use std::sync::atomic::{AtomicUsize, Ordering};

const fn pass(name: &'static str, shader: &'static str, entry_point: &'static str) -> VoxelPass {
    VoxelPass { name, shader, entry_point, dispatch: Dispatch::Pixels }
}

/// The passes in dispatch order.
pub const PASSES: [VoxelPass; 6] = [
    pass("glowbrick_denoise_temporal", "denoise/temporal.wgsl", "main"),
    pass("glowbrick_denoise_wavelet_1", "denoise/wavelet.wgsl", "step_1"),
    pass("glowbrick_denoise_wavelet_2", "denoise/wavelet.wgsl", "step_2"),
    pass("glowbrick_denoise_wavelet_4", "denoise/wavelet.wgsl", "step_4"),
    pass("glowbrick_denoise_wavelet_8", "denoise/wavelet.wgsl", "step_8"),
    pass("glowbrick_denoise_wavelet_16", "denoise/wavelet.wgsl", "step_16_and_write"),
];

/// GPU-time names of the passes, in dispatch order.
pub const DENOISE_PASS_NAMES: [&str; 6] =
    [PASSES[0].name, PASSES[1].name, PASSES[2].name, PASSES[3].name, PASSES[4].name, PASSES[5].name];

/// Whether the passes run this frame: when asked for, on a view that shows light.
pub fn runs(settings: &RenderSettings) -> bool {
    settings.denoise && settings.debug.is_lit()
}

/// `FrameParams::denoise` for a frame: `DENOISE_ON` when the passes run, `DENOISE_HISTORY` when last frame's
/// history may be reused: last frame ran the denoiser too, and no edit changed the world or its lights (moving
/// objects are left to the reprojection test, which their pixels fail).
pub fn frame_flags(ran_last_frame: bool, runs: bool, world_changed: bool) -> u32 {
    let history = ran_last_frame && runs && !world_changed;
    (if runs { DENOISE_ON } else { 0 }) | if history { DENOISE_HISTORY } else { 0 }
}

/// Its part of group 1 (`shaders/lib/frame.wgsl`, where the shading passes write through it).
pub const VIEW_BINDINGS: [GpuBinding; 4] = [
    GpuBinding::read_write("noisy"),
    GpuBinding::read_write("history"),
    GpuBinding::read_write("prev_history"),
    GpuBinding::read_write("wavelet"),
];

/// Its view part.
pub const VIEW_PART: ViewPartKind =
    ViewPartKind { bindings: &VIEW_BINDINGS, new: |device, pixels| Box::new(DenoiseView::new(device, pixels)) };

/// One view's denoiser buffers: the shading passes' noisy frame; per pixel two
/// texels of history (demodulated colour and length, luminance moments), this frame's and last frame's, two
/// buffers that swap roles each denoised frame (the temporal pass writes every pixel's), so last frame's is never
/// copied; the wavelet's two halves (colour and variance).
pub struct DenoiseView {
    noisy: Buffer,
    histories: [Buffer; 2],
    /// Which history this frame writes.
    current: AtomicUsize,
    wavelet: Buffer,
    /// Whether this frame runs the passes (set in prepare; last frame's until then).
    runs: bool,
}

impl DenoiseView {
    pub fn new(device: &RenderDevice, pixels: u64) -> Self {
        let buffer = |label: &'static str, texels: u64| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size: texels * pixels * DENOISE_TEXEL_BYTES,
                usage: BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        DenoiseView {
            noisy: buffer("glowbrick_denoise_noisy", 1),
            histories: [buffer("glowbrick_denoise_history_a", 2), buffer("glowbrick_denoise_history_b", 2)],
            current: AtomicUsize::new(0),
            wavelet: buffer("glowbrick_denoise_wavelet", 2),
            runs: false,
        }
    }
}

impl ViewPart for DenoiseView {
    fn resources(&self) -> Vec<BindingResource<'_>> {
        let current = self.current.load(Ordering::Relaxed);
        vec![
            self.noisy.as_entire_binding(),
            self.histories[current].as_entire_binding(),
            self.histories[current ^ 1].as_entire_binding(),
            self.wavelet.as_entire_binding(),
        ]
    }

    /// `FrameParams::denoise`, the `DENOISE_*` flags.
    fn begin_frame(&mut self, plan: &FramePlan, resized: bool, _: &RenderSettings, params: &mut FrameParams) {
        params.denoise = frame_flags(self.runs && !resized, plan.denoise, plan.changes.world);
        self.runs = plan.denoise;
    }

    /// On a denoised frame, last frame's history becomes the previous one.
    fn swap(&self) {
        if self.runs {
            self.current.fetch_xor(1, Ordering::Relaxed);
        }
    }

    fn parity(&self) -> usize {
        self.current.load(Ordering::Relaxed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The history holds only across consecutive denoised frames without an edit.
    #[test]
    fn the_history_restarts_after_an_edit_or_a_frame_without_the_denoiser() {
        assert_eq!(frame_flags(true, true, false), DENOISE_ON | DENOISE_HISTORY);
        assert_eq!(frame_flags(false, true, false), DENOISE_ON, "first frame");
        assert_eq!(frame_flags(true, true, true), DENOISE_ON, "an edit");
        assert_eq!(frame_flags(true, false, false), 0, "not running");
    }
}
