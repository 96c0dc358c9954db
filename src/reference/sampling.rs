//! Random numbers and sampling for the CPU reference: a PCG stream per (pixel, sample), cosine-weighted
//! hemisphere directions, and points on the faces of a light's cube that face the shading point (uniform in
//! area, or in solid angle for a face close to it).

use super::spherical_rect::SphericalRect;
use crate::lights::Light;
pub use crate::lights::daylight::frame;
use bevy::math::{IVec3, Vec3};

/// PCG32 (O'Neill), seeded per pixel and sample so renders are deterministic whatever the thread schedule.
#[derive(Clone, Debug)]
pub struct Pcg(u64);

impl Pcg {
    pub fn new(seed: u64, stream: u64) -> Self {
        let mut rng = Pcg(seed.wrapping_add(stream.wrapping_mul(0x9E37_79B9_7F4A_7C15)));
        rng.next_u32();
        rng
    }

    pub fn next_u32(&mut self) -> u32 {
        let old = self.0;
        self.0 = old.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        let xorshifted = (((old >> 18) ^ old) >> 27) as u32;
        xorshifted.rotate_right((old >> 59) as u32)
    }

    /// Uniform in [0, 1).
    pub fn next_f32(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
    }
}

/// A cosine-distributed direction around unit `n` (pdf = cos / pi).
pub fn cosine_direction(n: Vec3, u1: f32, u2: f32) -> Vec3 {
    let r = u1.sqrt();
    let phi = std::f32::consts::TAU * u2;
    let (t, b) = frame(n);
    (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).max(0.0).sqrt()).normalize()
}

/// A point on a light's surface: position, outward face normal, and the pdf of choosing it per unit area
/// (given the light was chosen).
#[derive(Clone, Copy, Debug)]
pub struct LightPoint {
    pub position: Vec3,
    pub normal: Vec3,
    pub pdf_area: f32,
}

/// Within this many face sizes of a face's centre, its point is drawn by solid angle instead of area. The GPU's
/// candidates switch at the same distance (shared through `render::gpu_types::shared_constants`).
pub const NEAR_FACE: u32 = 4;

/// Chooses uniformly one of the cube faces whose front side sees `p` and that touch air, then a point on it:
/// uniform in area, or uniform in the solid angle it subtends when `p` is near it (whose estimate stays bounded
/// where area sampling's cos cos / d^2 does not). Both are unbiased, and which one is used depends only on `p` and
/// the face (`near_by_solid_angle` false: always by area). A face that cannot see `p` or is buried contributes nothing, so leaving it out keeps the estimator
/// unbiased. `None` when `p` is inside the cube's slab on every axis (it is then inside the light).
pub fn sample_light_point(
    light: &Light,
    p: Vec3,
    near_by_solid_angle: bool,
    u_face: f32,
    u: f32,
    v: f32,
) -> Option<LightPoint> {
    let lo = light.min.as_vec3();
    let size = light.size as f32;
    let hi = lo + Vec3::splat(size);
    let mut faces = [(0usize, 0f32); 3];
    let mut count = 0;
    for axis in 0..3 {
        let exposed = |face: usize| light.faces & (1 << face) != 0;
        if p[axis] > hi[axis] && exposed(2 * axis) {
            faces[count] = (axis, 1.0);
            count += 1;
        } else if p[axis] < lo[axis] && exposed(2 * axis + 1) {
            faces[count] = (axis, -1.0);
            count += 1;
        }
    }
    if count == 0 {
        return None;
    }
    let (axis, sign) = faces[((u_face * count as f32) as usize).min(count - 1)];
    let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
    let mut corner = lo;
    corner[axis] = if sign > 0.0 { hi[axis] } else { lo[axis] };
    let mut normal = Vec3::ZERO;
    normal[axis] = sign;
    let (mut edge_a, mut edge_b) = (Vec3::ZERO, Vec3::ZERO);
    edge_a[a] = size;
    edge_b[b] = size;
    let centre = corner + 0.5 * (edge_a + edge_b);
    if near_by_solid_angle
        && p.distance(centre) < NEAR_FACE as f32 * size
        && let Some(rect) = SphericalRect::new(p, corner, edge_a, edge_b)
    {
        let position = rect.sample(u, v);
        let to_point = position - p;
        let d2 = to_point.length_squared() as f64;
        let cos_light = (-normal.dot(to_point)) as f64 / d2.sqrt();
        // The solid-angle density in area measure: cos / (d^2 x solid angle).
        let pdf_area = cos_light / (d2 * rect.solid_angle * count as f64);
        return Some(LightPoint { position, normal, pdf_area: pdf_area as f32 });
    }
    let mut position = corner;
    position[a] = lo[a] + u * size;
    position[b] = lo[b] + v * size;
    Some(LightPoint { position, normal, pdf_area: 1.0 / (count as f32 * size * size) })
}

/// Whether voxel `v` lies in the light's cube.
pub fn light_contains(light: &Light, v: IVec3) -> bool {
    v.cmpge(light.min).all() && v.cmplt(light.min + IVec3::splat(light.size)).all()
}
