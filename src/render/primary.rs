//! The primary-ray pass (`shaders/primary.wgsl`): one ray per pixel through the brick grid and the moving
//! objects, writing the G-buffer (hit point and packed surface: face, material, object id) that every later pass
//! reads, touching the GI cache entries the camera sees, and lighting the hit itself (sun and sky, or one
//! next-event-estimation sample of the light pool) unless Voxel ReSTIR shades it. Also the debug views.

use super::frame::{Dispatch, VoxelPass};

pub const PRIMARY: VoxelPass =
    VoxelPass { name: "glowbrick_primary", shader: "primary.wgsl", entry_point: "main", dispatch: Dispatch::Pixels };

/// The name the pass's GPU time is recorded under.
pub const PRIMARY_PASS_NAME: &str = PRIMARY.name;
