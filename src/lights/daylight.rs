//! The sky over a day: where the sun (or, at night, the moon) stands at `time=H`, how strong and what colour
//! its disk and the sky are. One model for the GPU frame (`render::scene::lights::scene_lighting` uploads it) and
//! the CPU reference (which integrates it), so both light the same world the same way.
//!
//! - The disk is a small cone of directions (`DISK_RADIUS`) of constant radiance: shadows are soft, and a
//!   surface facing it receives `pi * disk` irradiance, so a diffuse albedo `a` reflects `a * disk * cos`.
//! - The sky is a gradient from its horizon colour to its zenith colour (`sky`), below the disk's light.
//! - The sun's path: it rises at 6:00 towards -X, culminates at 12:00 at `90 - LATITUDE_DEG` degrees above
//!   +Z, and sets at 18:00 towards +X. The moon stands opposite the sun.

use bevy::math::Vec3;

/// Angular radius of the sun's and the moon's disk, in radians (the real sun's is 0.0047; a larger disk gives
/// the softer shadows a blocky world reads better with).
pub const DISK_RADIUS: f32 = 0.012;
/// How far the sun's path is tilted from the zenith, in degrees (noon elevation is 90 minus this).
const LATITUDE_DEG: f32 = 35.0;
/// The noon sun's `disk` (the old fixed sun's strength, so daytime images keep their exposure).
const NOON_SUN: Vec3 = Vec3::new(1.1, 1.0, 0.9);
/// The sun's colour at the horizon (what is left after the long path through the air).
const LOW_SUN: Vec3 = Vec3::new(1.0, 0.42, 0.12);
/// The moon's `disk`: about 1/40 of the sun's, a little blue.
const MOON: Vec3 = Vec3::new(0.018, 0.022, 0.032);
const DAY_ZENITH: Vec3 = Vec3::new(0.35, 0.55, 0.95);
const DAY_HORIZON: Vec3 = Vec3::new(0.75, 0.82, 0.9);
const DUSK_ZENITH: Vec3 = Vec3::new(0.10, 0.13, 0.32);
const DUSK_HORIZON: Vec3 = Vec3::new(0.55, 0.30, 0.14);
const NIGHT_ZENITH: Vec3 = Vec3::new(0.002, 0.003, 0.008);
const NIGHT_HORIZON: Vec3 = Vec3::new(0.004, 0.005, 0.010);

/// The time of day a new world starts at, in hours (mid-morning: long enough shadows to read the shapes).
pub const DEFAULT_HOURS: f32 = 10.0;

/// The sun or moon disk and the sky at one time of day.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Daylight {
    /// Unit direction towards the disk (the sun by day, the moon by night).
    pub direction: Vec3,
    /// The disk's irradiance on a surface facing it, over pi (zero when it is off or below the horizon).
    pub disk: Vec3,
    /// `1 - cos(DISK_RADIUS)`: the disk's cone (its solid angle over 2 pi).
    pub cone: f32,
    pub zenith: Vec3,
    pub horizon: Vec3,
}

fn smoothstep(edge0: f32, edge1: f32, x: f32) -> f32 {
    let t = ((x - edge0) / (edge1 - edge0)).clamp(0.0, 1.0);
    t * t * (3.0 - 2.0 * t)
}

/// The unit direction towards the sun at `hours` (0-24; wraps).
pub fn sun_direction(hours: f32) -> Vec3 {
    let angle = (hours.rem_euclid(24.0) - 12.0) / 24.0 * std::f32::consts::TAU;
    let tilt = LATITUDE_DEG.to_radians();
    Vec3::new(angle.sin(), angle.cos() * tilt.cos(), angle.cos() * tilt.sin())
}

impl Daylight {
    /// The sky at `hours`; `disk_on` false leaves the disk dark (the sky stays).
    pub fn at(hours: f32, disk_on: bool) -> Daylight {
        let sun = sun_direction(hours);
        let elevation = sun.y;
        // The sun reddens as it nears the horizon and fades out over its last few degrees; the moon fades in
        // as it rises, so the light never jumps.
        let (direction, disk) = if elevation >= 0.0 {
            let colour = LOW_SUN.lerp(NOON_SUN, smoothstep(0.0, 0.4, elevation));
            (sun, colour * smoothstep(0.0, 0.08, elevation))
        } else {
            (-sun, MOON * smoothstep(0.0, 0.08, -elevation))
        };
        let (zenith, horizon) = if elevation >= 0.0 {
            let t = smoothstep(0.0, 0.35, elevation);
            (DUSK_ZENITH.lerp(DAY_ZENITH, t), DUSK_HORIZON.lerp(DAY_HORIZON, t))
        } else {
            let t = smoothstep(-0.25, 0.0, elevation);
            (NIGHT_ZENITH.lerp(DUSK_ZENITH, t), NIGHT_HORIZON.lerp(DUSK_HORIZON, t))
        };
        // 1 - cos r without the cancellation of computing cos r first.
        let cone = 2.0 * (DISK_RADIUS * 0.5).sin().powi(2);
        Daylight { direction, disk: if disk_on { disk } else { Vec3::ZERO }, cone, zenith, horizon }
    }

    /// Sky radiance in direction `dir` (not counting the disk); `shaders/lib/lights.wgsl` `sky` is the same.
    pub fn sky(&self, dir: Vec3) -> Vec3 {
        let up = (dir.y * 0.5 + 0.5).clamp(0.0, 1.0);
        self.horizon.lerp(self.zenith, up)
    }

    /// Radiance of the disk itself seen along `dir` (a camera ray that misses everything): irradiance over the
    /// cone's solid angle, `pi * disk / (2 pi cone)`.
    pub fn disk_radiance(&self, dir: Vec3) -> Vec3 {
        if dir.dot(self.direction) >= 1.0 - self.cone { self.disk / (2.0 * self.cone) } else { Vec3::ZERO }
    }

    /// What a camera ray that leaves the world sees along `dir`.
    pub fn background(&self, dir: Vec3) -> Vec3 {
        self.sky(dir) + self.disk_radiance(dir)
    }

    /// A direction uniformly within the disk's cone (`u1`, `u2` uniform in [0, 1)).
    pub fn disk_direction(&self, u1: f32, u2: f32) -> Vec3 {
        let cos_theta = 1.0 - u1 * self.cone;
        let sin_theta = (1.0 - cos_theta * cos_theta).max(0.0).sqrt();
        let phi = std::f32::consts::TAU * u2;
        let (t, b) = frame(self.direction);
        (t * (sin_theta * phi.cos()) + b * (sin_theta * phi.sin()) + self.direction * cos_theta).normalize()
    }

    /// Whether the disk gives any light.
    pub fn disk_on(&self) -> bool {
        self.disk.max_element() > 0.0
    }
}

/// An orthonormal frame around unit `n` (Duff et al. 2017); `shaders/lib/lights.wgsl` `frame_of` is the same.
pub fn frame(n: Vec3) -> (Vec3, Vec3) {
    let sign = 1f32.copysign(n.z);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    (Vec3::new(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), Vec3::new(b, sign + n.y * n.y * a, -n.y))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_sun_rises_culminates_and_sets_on_time() {
        assert!(sun_direction(6.0).y.abs() < 1e-6 && sun_direction(18.0).y.abs() < 1e-6);
        assert!((sun_direction(12.0).y - (90f32 - LATITUDE_DEG).to_radians().sin()).abs() < 1e-6);
        assert!(sun_direction(0.0).y < -0.8 && sun_direction(24.0) == sun_direction(0.0));
        assert!(sun_direction(7.0).x < 0.0 && sun_direction(17.0).x > 0.0);
    }

    #[test]
    fn noon_keeps_the_old_sun_and_night_has_a_dim_moon_opposite() {
        let noon = Daylight::at(12.0, true);
        assert_eq!(noon.disk, NOON_SUN);
        assert_eq!(noon.zenith, DAY_ZENITH);
        let night = Daylight::at(0.0, true);
        assert!(night.direction.y > 0.8 && night.disk == MOON);
        assert!(night.sky(Vec3::Y).max_element() < 0.01);
        // Dusk: a low red sun and an orange horizon.
        let dusk = Daylight::at(17.5, true);
        assert!(dusk.disk.x > 2.0 * dusk.disk.z && dusk.disk.x > 0.5);
        assert!(dusk.horizon.x > dusk.horizon.z);
        assert_eq!(Daylight::at(12.0, false).disk, Vec3::ZERO);
    }

    #[test]
    fn the_light_changes_continuously_through_sunset() {
        let mut previous = Daylight::at(16.0, true);
        for step in 1..=400 {
            let now = Daylight::at(16.0 + step as f32 * 0.01, true);
            assert!((now.disk - previous.disk).abs().max_element() < 0.05, "disk jumps at step {step}");
            assert!((now.zenith - previous.zenith).abs().max_element() < 0.02, "sky jumps at step {step}");
            previous = now;
        }
    }

    #[test]
    fn disk_directions_fill_the_cone_and_the_disk_has_the_stated_irradiance() {
        let d = Daylight::at(10.0, true);
        let cos_r = DISK_RADIUS.cos();
        let mut mean = Vec3::ZERO;
        for i in 0..1000 {
            let dir = d.disk_direction((i as f32 + 0.5) / 1000.0, (i as f32 * 0.618_034).fract());
            assert!((dir.length() - 1.0).abs() < 1e-5 && dir.dot(d.direction) >= cos_r - 1e-6);
            mean += dir;
        }
        assert!((mean / 1000.0).normalize().dot(d.direction) > 0.999_999);
        // Radiance x solid angle = pi x disk.
        let solid_angle = std::f32::consts::TAU * (1.0 - cos_r);
        let irradiance = d.disk_radiance(d.direction) * solid_angle;
        assert!((irradiance - d.disk * std::f32::consts::PI).abs().max_element() < 1e-3 * d.disk.max_element());
        assert_eq!(d.disk_radiance(-d.direction), Vec3::ZERO);
    }
}
