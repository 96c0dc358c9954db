//! The frame plan: what this frame runs, decided once (`frame::plan_frame`, after the scene uploads and before
//! any technique prepares) and read by the view's preparation, the GI cache and both frame systems. A technique
//! reads here whether it runs and what changed; only `frame` decides.

use crate::settings::RENDER_SCALE_RANGE;
use bevy::prelude::*;

/// Runs after the frame plan is decided (the views' and the GI cache's preparation order themselves after it).
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct FramePlanned;

/// This frame's plan.
#[derive(Resource, Clone, Debug, PartialEq)]
pub struct FramePlan {
    /// The lighting passes' share of the output's pixels per axis (`upscale::frame_scale`); below 1 the upscaler
    /// brings their light to the output.
    pub render_scale: f32,
    /// Which of Voxel ReSTIR's passes run in every camera.
    pub restir: RestirPasses,
    /// The denoiser's passes run in every camera.
    pub denoise: bool,
    /// The GI cache's passes run (once, before the cameras).
    pub gi: bool,
    /// GI is on but a pass this frame runs is still compiling: the GI cache holds its schedule and the cameras
    /// draw nothing, rather than showing frames without GI or spending its warm-up on frames no camera drew.
    pub compiling: bool,
    /// What changed in the scene, as the histories see it.
    pub changes: SceneChanges,
}

impl Default for FramePlan {
    fn default() -> Self {
        FramePlan {
            render_scale: 1.0,
            restir: RestirPasses::default(),
            denoise: false,
            gi: false,
            compiling: false,
            changes: SceneChanges::default(),
        }
    }
}

impl FramePlan {
    /// Whether the lighting passes run below the output's resolution (and the upscaler runs).
    pub fn upscales(&self) -> bool {
        self.render_scale < 1.0
    }

    /// The lighting passes' pixels for a view of `output` pixels.
    pub fn render_size(&self, output: UVec2) -> UVec2 {
        render_size(output, self.render_scale)
    }
}

/// The lighting passes' pixels for `output` pixels at `scale`: rounded up, at least one, the output itself at 1.
pub fn render_size(output: UVec2, scale: f32) -> UVec2 {
    if scale >= 1.0 {
        return output;
    }
    let scaled = (output.as_vec2() * scale.max(RENDER_SCALE_RANGE.0)).ceil().as_uvec2();
    scaled.clamp(UVec2::ONE, output.max(UVec2::ONE))
}

/// Which of Voxel ReSTIR's passes a view's frame dispatches (`restir::dispatches`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct RestirPasses {
    /// The shading pass shades the image (`restir::shades`).
    pub shades: bool,
    /// The sampling passes run (`restir::samples`).
    pub samples: bool,
    /// The candidates read light tiles, so the tiles' pass runs with the sampling passes.
    pub tiles: bool,
}

/// What changed in the scene this frame, as the views' histories see it.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SceneChanges {
    /// The light pool changed (a lamp placed or removed).
    pub lights: bool,
    /// An edit changed the world's voxels or its lights.
    pub world: bool,
    /// Anything in the image changed without the camera moving, moving objects included.
    pub anything: bool,
    pub light_count: u32,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The render size rounds up and never reaches zero; scale 1 is the output itself.
    #[test]
    fn the_render_size_rounds_up_and_stays_within_the_output() {
        assert_eq!(render_size(UVec2::new(1280, 720), 1.0), UVec2::new(1280, 720));
        assert_eq!(render_size(UVec2::new(1280, 720), 0.5), UVec2::new(640, 360));
        assert_eq!(render_size(UVec2::new(1281, 721), 0.5), UVec2::new(641, 361));
        assert_eq!(render_size(UVec2::new(1920, 1080), 0.33), UVec2::new(634, 357));
        assert_eq!(render_size(UVec2::new(3, 1), 0.25), UVec2::new(1, 1));
        assert!(!FramePlan::default().upscales());
    }
}
