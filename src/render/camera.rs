//! The component that enables voxel rendering on a camera, and the bundle a voxel camera needs. The camera math
//! itself (transform from a view, primary rays) is in `world::camera`, where the CPU reference uses it too.

use crate::world::{CameraView, view_transform};
use bevy::prelude::*;
use bevy::render::extract_component::ExtractComponent;

/// Marks a camera rendered by the voxel passes. Spawn it with `voxel_camera_bundle` (HDR, no MSAA, storage
/// usage on the main texture).
#[derive(Component, Clone, Copy, Default, ExtractComponent)]
pub struct VoxelCamera;

/// The components a voxel camera needs, placed at `view`.
pub fn voxel_camera_bundle(view: &CameraView) -> impl Bundle {
    use bevy::camera::{CameraMainTextureUsages, Hdr};
    use bevy::render::render_resource::TextureUsages;
    (
        Camera3d::default(),
        Hdr,
        Msaa::Off,
        CameraMainTextureUsages::default().with(TextureUsages::STORAGE_BINDING),
        Projection::Perspective(PerspectiveProjection { fov: view.fov_deg.to_radians(), ..default() }),
        view_transform(view),
        VoxelCamera,
    )
}

#[cfg(test)]
mod tests {
    /// The CPU camera math (`world::camera`) assumes the voxel camera's near plane.
    #[test]
    fn the_cpu_camera_uses_the_voxel_cameras_near_plane() {
        assert_eq!(bevy::prelude::PerspectiveProjection::default().near, crate::world::camera::NEAR_PLANE);
    }
}
