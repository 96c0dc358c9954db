//! Voxel ReSTIR direct lighting (seed 000, DESIGN.md "Voxel ReSTIR"): three compute passes per camera after the
//! primary pass has written the G-buffer: candidates + temporal reuse (`shaders/restir/initial.wgsl`), spatial
//! reuse (`spatial.wgsl`) and shading (`shade.wgsl`); `common.wgsl` holds the reservoir and the resampling steps.
//! None of them runs when the scene has no lights (or ReSTIR is not the lighting mode): the primary pass then
//! shows emission alone, and the skipped passes record no GPU time. `frame::view_frame` dispatches them.

use super::frame::{Dispatch, VoxelPass};

/// The passes in dispatch order.
pub const PASSES: [VoxelPass; 3] = [
    VoxelPass {
        name: "glowbrick_restir_initial",
        shader: "restir/initial.wgsl",
        entry_point: "main",
        dispatch: Dispatch::Pixels,
    },
    VoxelPass {
        name: "glowbrick_restir_spatial",
        shader: "restir/spatial.wgsl",
        entry_point: "main",
        dispatch: Dispatch::Pixels,
    },
    VoxelPass {
        name: "glowbrick_restir_shade",
        shader: "restir/shade.wgsl",
        entry_point: "main",
        dispatch: Dispatch::Pixels,
    },
];

/// GPU-time names of the three passes, in dispatch order.
pub const RESTIR_PASS_NAMES: [&str; 3] = [PASSES[0].name, PASSES[1].name, PASSES[2].name];
