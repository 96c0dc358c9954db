//! Cameras: the component that enables voxel rendering, placement from a named view, and the CPU version of the
//! primary ray (the same formula as `primary_ray_dir` in `shaders/primary.wgsl`).

use crate::world::{CameraView, Ray};
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

/// The transform of a camera at `view` (y up; a view looking straight up or down uses +z as up).
pub fn view_transform(view: &CameraView) -> Transform {
    let dir = view.direction();
    let up = if dir.cross(Vec3::Y).length_squared() < 1e-8 { Vec3::Z } else { Vec3::Y };
    Transform::from_translation(view.origin()).looking_to(dir, up)
}

/// `world_from_clip` of a perspective camera, as Bevy's view uniform computes it.
pub fn world_from_clip(transform: &Transform, fov_y: f32, width: u32, height: u32) -> Mat4 {
    let projection = PerspectiveProjection { fov: fov_y, aspect_ratio: width as f32 / height as f32, ..default() };
    let clip_from_view =
        Mat4::perspective_infinite_reverse_rh(projection.fov, projection.aspect_ratio, projection.near);
    transform.to_matrix() * clip_from_view.inverse()
}

/// The primary ray through the centre of `pixel` (y down) of a `width` x `height` image.
pub fn camera_ray(world_from_clip: Mat4, origin: Vec3, pixel: UVec2, width: u32, height: u32) -> Ray {
    let uv = (pixel.as_vec2() + 0.5) / Vec2::new(width as f32, height as f32);
    let ndc = Vec2::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    let p = world_from_clip * Vec4::new(ndc.x, ndc.y, 1.0, 1.0);
    Ray::new(origin, p.truncate() / p.w - origin)
}
