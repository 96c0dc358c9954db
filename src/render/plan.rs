//! The frame plan: what this frame runs, decided once (`frame::plan_frame`, after the scene uploads and before
//! any technique prepares) and read by the view's preparation, the GI cache and both frame systems. A technique
//! reads here whether it runs and what changed; only `frame` decides.

use bevy::prelude::*;

/// Runs after the frame plan is decided (the views' and the GI cache's preparation order themselves after it).
#[derive(SystemSet, Debug, Clone, PartialEq, Eq, Hash)]
pub struct FramePlanned;

/// This frame's plan.
#[derive(Resource, Clone, Debug, Default, PartialEq)]
pub struct FramePlan {
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
