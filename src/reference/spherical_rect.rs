//! Uniform sampling of the solid angle an axis-aligned rectangle subtends from a point (the area-preserving
//! parametrisation of spherical rectangles, Ureña, Fajardo and King 2013). The CPU reference uses it for light
//! faces close to the shading point, where uniform area sampling has unbounded variance: its estimate carries
//! cos cos / d^2, which grows without bound beside a lamp lying on the floor. Drawn by solid angle, the estimate
//! is the radiance times the receiver's cosine times the solid angle, bounded by 2 pi.
//!
//! Computed in f64: the corner angles of a rectangle seen edge-on differ from pi by less than f32 resolves.

use bevy::math::{DVec3, Vec3};
use std::f64::consts::TAU;

/// A rectangle seen from `origin`, in the rectangle's own frame (x and y along its edges, z towards the side away
/// from the origin so the rectangle lies at z = z0 < 0).
pub struct SphericalRect {
    origin: DVec3,
    x: DVec3,
    y: DVec3,
    z: DVec3,
    z0: f64,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    b0: f64,
    b1: f64,
    k: f64,
    /// The solid angle, in steradians.
    pub solid_angle: f64,
}

impl SphericalRect {
    /// The rectangle with corner `corner` and orthogonal edges `edge_x`, `edge_y`, seen from `origin`; `None` when
    /// the origin lies in its plane or it subtends no measurable solid angle.
    pub fn new(origin: Vec3, corner: Vec3, edge_x: Vec3, edge_y: Vec3) -> Option<SphericalRect> {
        let origin = origin.as_dvec3();
        let (edge_x, edge_y) = (edge_x.as_dvec3(), edge_y.as_dvec3());
        let (length_x, length_y) = (edge_x.length(), edge_y.length());
        let (x, y) = (edge_x / length_x, edge_y / length_y);
        let mut z = x.cross(y);
        let d = corner.as_dvec3() - origin;
        let mut z0 = d.dot(z);
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        if z0.abs() < 1e-9 {
            return None;
        }
        let (x0, y0) = (d.dot(x), d.dot(y));
        let (x1, y1) = (x0 + length_x, y0 + length_y);
        // The normals of the four planes through the origin and one edge each.
        let n0 = DVec3::new(0.0, z0, -y0).normalize();
        let n1 = DVec3::new(-z0, 0.0, x1).normalize();
        let n2 = DVec3::new(0.0, -z0, y1).normalize();
        let n3 = DVec3::new(z0, 0.0, -x0).normalize();
        let angle = |a: DVec3, b: DVec3| (-a.dot(b)).clamp(-1.0, 1.0).acos();
        let (g0, g1, g2, g3) = (angle(n0, n1), angle(n1, n2), angle(n2, n3), angle(n3, n0));
        let k = TAU - g2 - g3;
        let solid_angle = g0 + g1 - k;
        // NaN fails this test too.
        if solid_angle.is_nan() || solid_angle <= 1e-12 {
            return None;
        }
        Some(SphericalRect { origin, x, y, z, z0, x0, x1, y0, y1, b0: n0.z, b1: n2.z, k, solid_angle })
    }

    /// The point of the rectangle in the direction drawn uniformly from its solid angle by (u, v) in [0, 1)^2.
    pub fn sample(&self, u: f32, v: f32) -> Vec3 {
        let (u, v) = (u as f64, v as f64);
        let au = u * self.solid_angle + self.k;
        let fu = (au.cos() * self.b0 - self.b1) / au.sin();
        let cu = (fu.signum() / (fu * fu + self.b0 * self.b0).sqrt()).clamp(-1.0, 1.0);
        let xu = (-(cu * self.z0) / (1.0 - cu * cu).max(1e-300).sqrt()).clamp(self.x0, self.x1);
        let d = (xu * xu + self.z0 * self.z0).sqrt();
        let h0 = self.y0 / (d * d + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d * d + self.y1 * self.y1).sqrt();
        let hv = h0 + v * (h1 - h0);
        let yv =
            if hv * hv < 1.0 - 1e-12 { (hv * d / (1.0 - hv * hv).sqrt()).clamp(self.y0, self.y1) } else { self.y1 };
        (self.origin + self.x * xu + self.y * yv + self.z * self.z0).as_vec3()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Solid angle of a rectangle a x b whose corner lies straight above the origin at height h (exact).
    fn corner_solid_angle(a: f64, b: f64, h: f64) -> f64 {
        (a * b / (h * (a * a + b * b + h * h).sqrt())).atan()
    }

    #[test]
    fn the_solid_angle_is_exact() {
        let rect = SphericalRect::new(Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0), Vec3::X * 3.0, Vec3::Y * 1.5).unwrap();
        let exact = corner_solid_angle(3.0, 1.5, 2.0);
        assert!((rect.solid_angle - exact).abs() < 1e-9, "{} vs {exact}", rect.solid_angle);
        // Seen from the other side, and from straight above the middle (four corner rectangles).
        let below =
            SphericalRect::new(Vec3::new(1.5, 0.75, 4.0), Vec3::new(0.0, 0.0, 2.0), Vec3::X * 3.0, Vec3::Y * 1.5);
        let four = 4.0 * corner_solid_angle(1.5, 0.75, 2.0);
        assert!((below.unwrap().solid_angle - four).abs() < 1e-9);
        assert!(SphericalRect::new(Vec3::new(0.0, 0.0, 2.0), Vec3::new(0.0, 0.0, 2.0), Vec3::X, Vec3::Y).is_none());
    }

    /// Samples lie on the rectangle and are uniform in solid angle: the fraction whose direction falls in a
    /// sub-rectangle matches that sub-rectangle's share of the solid angle, also seen nearly edge-on.
    #[test]
    fn samples_are_uniform_in_solid_angle_and_on_the_rectangle() {
        for (origin, height) in [(Vec3::ZERO, 2.0f32), (Vec3::new(0.2, 0.7, 0.0), 0.01)] {
            let corner = Vec3::new(0.0, 0.0, height);
            let rect = SphericalRect::new(origin, corner, Vec3::X, Vec3::Y).unwrap();
            let part = SphericalRect::new(origin, corner, Vec3::X * 0.5, Vec3::Y * 0.5).unwrap();
            let n = 200_000;
            let mut inside = 0usize;
            let mut rng = crate::reference::sampling::Pcg::new(3, 0);
            for _ in 0..n {
                let p = rect.sample(rng.next_f32(), rng.next_f32());
                assert!(
                    (p.z - height).abs() < 1e-4 && (-1e-4..=1.0001).contains(&p.x) && (-1e-4..=1.0001).contains(&p.y)
                );
                inside += (p.x < 0.5 && p.y < 0.5) as usize;
            }
            let share = part.solid_angle / rect.solid_angle;
            let measured = inside as f64 / n as f64;
            assert!((measured - share).abs() < 0.005, "height {height}: {measured} vs {share}");
        }
    }
}
