//! Camera math shared by the GPU renderer and the CPU reference: a camera's transform from a named view, its
//! `world_from_clip` as Bevy's view uniform computes it, and the primary ray through a pixel centre (the same
//! formula as `primary_ray_dir` in `shaders/primary.wgsl`).

use super::{CameraView, Ray};
use bevy::math::{Mat4, UVec2, Vec2, Vec3, Vec4};
use bevy::transform::components::Transform;

/// The transform of a camera at `view` (y up; a view looking straight up or down uses +z as up).
pub fn view_transform(view: &CameraView) -> Transform {
    let dir = view.direction();
    let up = if dir.cross(Vec3::Y).length_squared() < 1e-8 { Vec3::Z } else { Vec3::Y };
    Transform::from_translation(view.origin()).looking_to(dir, up)
}

/// The near plane of Bevy's default perspective projection, which the voxel camera uses (`render::camera`
/// checks that the two agree).
pub const NEAR_PLANE: f32 = 0.1;

/// `world_from_clip` of a perspective camera, as Bevy's view uniform computes it.
pub fn world_from_clip(transform: &Transform, fov_y: f32, width: u32, height: u32) -> Mat4 {
    let clip_from_view = Mat4::perspective_infinite_reverse_rh(fov_y, width as f32 / height as f32, NEAR_PLANE);
    transform.to_matrix() * clip_from_view.inverse()
}

/// The primary ray through the centre of `pixel` (y down) of a `width` x `height` image.
pub fn camera_ray(world_from_clip: Mat4, origin: Vec3, pixel: UVec2, width: u32, height: u32) -> Ray {
    let uv = (pixel.as_vec2() + 0.5) / Vec2::new(width as f32, height as f32);
    let ndc = Vec2::new(uv.x * 2.0 - 1.0, 1.0 - uv.y * 2.0);
    // Depth 0 of the reverse-Z infinite projection is the point at infinity (w = 0): the product is the direction,
    // free of the cancellation that a near-plane point minus a camera far from the origin suffers.
    Ray::new(origin, (world_from_clip * Vec4::new(ndc.x, ndc.y, 0.0, 1.0)).truncate())
}
