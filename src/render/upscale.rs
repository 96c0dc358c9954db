//! The upscaler: below render scale 1 the lighting passes (Voxel ReSTIR, the GI resolve, the denoiser) shade a
//! render size of `render_scale` of the output's pixels per axis, and this brings their light to the output
//! (`shaders/upscale/upscale.wgsl`). The primary pass still traces every output pixel into an output-resolution
//! G-buffer (crisp voxel edges, per-voxel albedo and an exact same-plane test, for a tenth of the frame), then:
//!
//! 1. `pick` (render pixels): each render pixel takes the texel of one output pixel of its footprint, jittered
//!    frame to frame on raw frames (`jitter`; at the footprint's centre under the denoiser), into the lighting
//!    passes' G-buffer, so they light exact hit points of the
//!    output's rays and over frames every output pixel is lit by one of its own; it touches the GI cache's
//!    entries there (where the shading reads them), which the primary pass then leaves alone.
//! 2. `main` (output pixels, last): demodulated light gathered from render pixels on the output pixel's own
//!    voxel-face plane (bilinear on the plane), or, where no render pixel of the 5x5 lies on it (a face narrower
//!    than a render pixel, seen past an edge), the GI cache's entry of its own voxel face, touched there; on raw
//!    frames accumulated over frames at the output's resolution (reprojected, TAAU's weights by each sample's
//!    distance); plus the sun's (or moon's) disk lit at the output
//!    pixel itself: the shading pass leaves the disk out below scale 1 and hands on its sample's visibility, and
//!    where the render pixels on the plane around an output pixel disagree (a shadow edge, a penumbra) the output
//!    pixel traces a shadow ray of its own, blended into a visibility history at the output's resolution, so a
//!    hard shadow is as sharp as native's (docs/bench/upscale.md); remodulated by full-resolution albedo and
//!    emission, the highlight drawn.
//!
//! Its texels (the output's G-buffer, its two histories) are regions of the view's G-buffers, which swap every frame;
//! its per-view state (`UpscaleView`) is whether its history holds.
//! At render scale 1 neither pass runs and every lighting pass runs at the output's pixels as before.

use super::gpu_types::{FrameParams, UPSCALE_HISTORY, UPSCALE_ON};
use super::pass::{Dispatch, VoxelPass};
use super::plan::FramePlan;
use super::view::{ViewPart, ViewPartKind};
use crate::settings::{DebugView, RENDER_SCALE_RANGE, RenderScale, RenderSettings};
use bevy::prelude::Resource;
use bevy::render::extract_resource::ExtractResource;
use bevy::render::render_resource::BindingResource;

/// The passes in dispatch order: `pick` after the primary pass, `main` last.
pub const PASSES: [VoxelPass; 2] = [
    VoxelPass {
        name: "glowbrick_upscale_pick",
        shader: "upscale/upscale.wgsl",
        entry_point: "pick",
        dispatch: Dispatch::Pixels,
    },
    VoxelPass {
        name: "glowbrick_upscale",
        shader: "upscale/upscale.wgsl",
        entry_point: "main",
        dispatch: Dispatch::OutputPixels,
    },
];

/// GPU-time names of the passes, in dispatch order.
pub const UPSCALE_PASS_NAMES: [&str; 2] = [PASSES[0].name, PASSES[1].name];

/// The scale the game's dynamic resolution chose (`game::dynamic_resolution`), read where `render_scale=auto`.
#[derive(Resource, ExtractResource, Clone, Copy, Debug, PartialEq)]
pub struct RenderScaleInForce(pub f32);

/// The render scale this frame runs at: the setting's, or with `auto` the dynamic resolution's (1 without one).
/// Only lit views that Voxel ReSTIR shades run below 1: the debug views and the modes the primary pass shades
/// itself (NEE, the sun-only look) stay at the output's pixels.
pub fn frame_scale(settings: &RenderSettings, in_force: Option<RenderScaleInForce>, restir_shades: bool) -> f32 {
    let scale = match settings.render_scale {
        RenderScale::Fixed(scale) => scale,
        RenderScale::Auto => in_force.map_or(1.0, |r| r.0),
    };
    if restir_shades && settings.debug == DebugView::None {
        scale.clamp(RENDER_SCALE_RANGE.0, RENDER_SCALE_RANGE.1)
    } else {
        1.0
    }
}

/// Where a render pixel takes its output pixel while the denoiser runs: its footprint's centre, every frame. The
/// denoiser's temporal pass reprojects to the nearest render pixel, so with a moving sample its history mixed
/// points up to a render pixel apart and blurred shadow edges (docs/bench/upscale.md).
pub const FOOTPRINT_CENTRE: [f32; 2] = [0.5, 0.5];

/// Where in its footprint each render pixel takes its output pixel on frame `frame` of raw (undenoised) frames:
/// the Halton (2, 3) points, 16 of them in turn, so the footprint is covered evenly within a second of frames.
pub fn jitter(frame: u32) -> [f32; 2] {
    let index = frame % 16 + 1;
    [radical_inverse(index, 2), radical_inverse(index, 3)]
}

fn radical_inverse(mut index: u32, base: u32) -> f32 {
    let mut result = 0.0;
    let mut digit = 1.0 / base as f32;
    while index > 0 {
        result += (index % base) as f32 * digit;
        index /= base;
        digit /= base as f32;
    }
    result
}

/// `FrameParams::upscale` for a frame: `UPSCALE_ON` when the lighting passes run below the output's pixels,
/// `UPSCALE_HISTORY` when last frame's upscaled history may be reused: last frame upscaled too and no edit changed
/// the world or its lights (as the denoiser's rule).
pub fn frame_flags(ran_last_frame: bool, runs: bool, world_changed: bool) -> u32 {
    let history = ran_last_frame && runs && !world_changed;
    (if runs { UPSCALE_ON } else { 0 }) | if history { UPSCALE_HISTORY } else { 0 }
}

/// Its view part: no buffers of its own (its texels are regions of the G-buffers, `GBUFFER_REGIONS`), only when
/// its history holds.
pub const VIEW_PART: ViewPartKind = ViewPartKind { bindings: &[], new: |_, _| Box::new(UpscaleView::default()) };

/// Whether a view's last frame was upscaled (its history then holds).
#[derive(Default)]
pub struct UpscaleView {
    /// Whether this frame upscales (set in prepare; last frame's until then).
    runs: bool,
}

impl ViewPart for UpscaleView {
    fn resources(&self) -> Vec<BindingResource<'_>> {
        Vec::new()
    }

    /// `FrameParams::upscale` (the `UPSCALE_*` flags) and the jitter. Its history is at the output's resolution,
    /// so a change of render size keeps it.
    fn begin_frame(&mut self, plan: &FramePlan, _: bool, _: &RenderSettings, params: &mut FrameParams) {
        let runs = plan.upscales();
        params.upscale = frame_flags(self.runs, runs, plan.changes.world);
        params.jitter = if runs && !plan.denoise { jitter(params.frame) } else { FOOTPRINT_CENTRE };
        self.runs = runs;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The jitter stays inside the footprint and its 16 points cover each quarter of it.
    #[test]
    fn the_jitter_covers_the_footprint() {
        let points: Vec<[f32; 2]> = (0..16).map(jitter).collect();
        assert!(points.iter().flatten().all(|&v| (0.0..1.0).contains(&v)));
        for quarter in 0..4 {
            let (x, y) = ((quarter % 2) as f32 * 0.5, (quarter / 2) as f32 * 0.5);
            let inside = points.iter().filter(|p| (x..x + 0.5).contains(&p[0]) && (y..y + 0.5).contains(&p[1]));
            assert!(inside.count() >= 3, "quarter {quarter}: {points:?}");
        }
        assert_eq!(jitter(0), [0.5, 1.0 / 3.0]);
        assert_eq!(jitter(16), jitter(0));
    }

    /// Only lit views that ReSTIR shades run below 1; `auto` reads the dynamic resolution's choice.
    #[test]
    fn only_lit_restir_views_run_below_the_output_resolution() {
        let settings = |pairs: &[&str]| {
            RenderSettings::default().with_pairs(&pairs.iter().map(|p| p.to_string()).collect::<Vec<_>>()).unwrap()
        };
        assert_eq!(frame_scale(&settings(&[]), None, true), 1.0);
        assert_eq!(frame_scale(&settings(&["render_scale=0.5"]), None, true), 0.5);
        assert_eq!(frame_scale(&settings(&["render_scale=0.5"]), None, false), 1.0, "the primary pass shades");
        assert_eq!(frame_scale(&settings(&["render_scale=0.5", "debug=albedo"]), None, true), 1.0);
        assert_eq!(frame_scale(&settings(&["render_scale=auto"]), None, true), 1.0);
        assert_eq!(frame_scale(&settings(&["render_scale=auto"]), Some(RenderScaleInForce(0.6)), true), 0.6);
        assert_eq!(frame_scale(&settings(&["render_scale=auto"]), Some(RenderScaleInForce(0.1)), true), 0.25);
    }

    /// The history holds only across consecutive upscaled frames without an edit.
    #[test]
    fn the_history_restarts_after_an_edit_or_a_native_frame() {
        assert_eq!(frame_flags(true, true, false), UPSCALE_ON | UPSCALE_HISTORY);
        assert_eq!(frame_flags(false, true, false), UPSCALE_ON);
        assert_eq!(frame_flags(true, true, true), UPSCALE_ON);
        assert_eq!(frame_flags(true, false, false), 0);
    }
}
