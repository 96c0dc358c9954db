//! The CPU ground truth: the same world, traversal and light pool as the GPU, integrated with many samples.
//!
//! - Primary rays go through pixel centres, exactly as `shaders/primary.wgsl` casts them, so reference and GPU
//!   images agree on geometry pixel for pixel and errors measure lighting only.
//! - Direct light: next-event estimation over the light pool (power alias table), a uniform point on a cube
//!   face that sees the shading point, one shadow ray: visible when the first hit lies in the light's cube.
//! - Indirect light (`bounces` > 0): cosine-sampled diffuse bounces with next-event estimation at every vertex;
//!   emission is counted only at the camera hit and through next-event estimation, never twice.
//! - Lighting is emitters only (the thesis' convention: no sky); a primary miss is black.
//! - Deterministic: each (pixel, sample) has its own random stream, whatever the thread schedule (rayon rows).

pub mod metrics;
pub mod sampling;

use crate::image_io::LinearImage;
use crate::lights::{AliasTable, LightPool};
use crate::world::traversal::RAY_OFFSET;
use crate::world::{CameraView, Ray, VoxelWorld, trace};
use crate::world::{camera_ray, view_transform, world_from_clip};
use bevy::math::{UVec2, Vec3};
use rayon::prelude::*;
use sampling::{Pcg, cosine_direction, light_contains, sample_light_point};
use std::time::{Duration, Instant};

/// How to integrate.
#[derive(Clone, Debug)]
pub struct ReferenceOptions {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel to reach.
    pub spp: u32,
    /// Diffuse bounces after the camera hit (0 = direct light only).
    pub bounces: u32,
    pub seed: u64,
    /// Stop early (after a whole batch of samples) when this much time has passed.
    pub time_budget: Option<Duration>,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions { width: 320, height: 180, spp: 256, bounces: 0, seed: 1, time_budget: None }
    }
}

/// A finished reference and how much work went into it.
#[derive(Clone, Debug)]
pub struct Reference {
    pub image: LinearImage,
    pub spp: u32,
    pub elapsed: Duration,
}

/// What the integrator needs besides the world: the lights and their sampling table.
pub struct Scene<'a> {
    pub world: &'a VoxelWorld,
    pub pool: &'a LightPool,
    pub alias: &'a AliasTable,
}

impl Scene<'_> {
    /// One next-event-estimation sample of the radiance reflected towards the viewer at `p` (face normal `n`,
    /// diffuse `albedo`): Le * (albedo / pi) * cos * cos_l / d^2 / pdf, or zero when occluded.
    pub fn direct_sample(&self, p: Vec3, n: Vec3, albedo: [f32; 3], rng: &mut Pcg) -> Vec3 {
        let Some((slot, pick_pdf)) = self.alias.sample(rng.next_f32(), rng.next_f32()) else { return Vec3::ZERO };
        let Some((Some(light), _)) = self.pool.slot(slot) else { return Vec3::ZERO };
        let Some(point) = sample_light_point(light, p, rng.next_f32(), rng.next_f32(), rng.next_f32()) else {
            return Vec3::ZERO;
        };
        let to_light = point.position - p;
        let d2 = to_light.length_squared();
        if d2 <= 1e-12 {
            return Vec3::ZERO;
        }
        let d = d2.sqrt();
        let wi = to_light / d;
        let cos_surface = n.dot(wi);
        let cos_light = -point.normal.dot(wi);
        if cos_surface <= 0.0 || cos_light <= 0.0 {
            return Vec3::ZERO;
        }
        let origin = p + n * RAY_OFFSET;
        let hit = trace(&self.world.grid, &Ray::new(origin, point.position - origin), d + 1.0);
        if !hit.is_some_and(|h| light_contains(light, h.voxel)) {
            return Vec3::ZERO;
        }
        let pdf = pick_pdf * point.pdf_area;
        let geometry = cos_surface * cos_light / d2 / pdf.max(1e-30);
        Vec3::from(albedo) * Vec3::from(light.radiance) * (geometry / std::f32::consts::PI)
    }

    /// One path sample of the radiance arriving along `ray`.
    pub fn path_sample(&self, ray: Ray, bounces: u32, rng: &mut Pcg) -> Vec3 {
        let Some(hit) = trace(&self.world.grid, &ray, f32::INFINITY) else { return Vec3::ZERO };
        let Some(material) = self.world.palette.get(hit.material) else { return Vec3::ZERO };
        let mut radiance = Vec3::from(material.radiance());
        let mut throughput = Vec3::ONE;
        let (mut p, mut n, mut albedo) = (ray.at(hit.distance), hit.face.normal().as_vec3(), material.albedo);
        for bounce in 0..=bounces {
            radiance += throughput * self.direct_sample(p, n, albedo, rng);
            if bounce == bounces {
                break;
            }
            // Cosine sampling cancels cos / pi against the pdf: the throughput picks up the albedo.
            throughput *= Vec3::from(albedo);
            let dir = cosine_direction(n, rng.next_f32(), rng.next_f32());
            let next = Ray::new(p + n * RAY_OFFSET, dir);
            let Some(h) = trace(&self.world.grid, &next, f32::INFINITY) else { break };
            let Some(m) = self.world.palette.get(h.material) else { break };
            (p, n, albedo) = (next.at(h.distance), h.face.normal().as_vec3(), m.albedo);
        }
        radiance
    }
}

/// Renders the reference image of `world` from `view`.
pub fn render_reference(
    world: &VoxelWorld,
    view: &CameraView,
    options: &ReferenceOptions,
) -> Result<Reference, String> {
    let (w, h) = (options.width, options.height);
    if w == 0 || h == 0 || w > 8192 || h > 8192 {
        return Err(format!("image size {w}x{h} must be within 1..=8192 on each side"));
    }
    if options.spp == 0 || options.bounces > 64 {
        return Err(format!("spp {} must be at least 1 and bounces {} at most 64", options.spp, options.bounces));
    }
    // A zero field of view or a zero direction would give a silently black image.
    if let Some(problem) = view.problem() {
        return Err(problem);
    }
    let start = Instant::now();
    let mut pool = LightPool::from_world(world);
    let alias = pool.alias().clone();
    let scene = Scene { world, pool: &pool, alias: &alias };
    let transform = view_transform(view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), w, h);
    let mut sum = vec![Vec3::ZERO; (w * h) as usize];
    let mut done = 0u32;
    // Batches of samples, so a time budget can stop between them.
    while done < options.spp {
        let batch = (options.spp - done).min(16.max(done / 4));
        sum.par_chunks_mut(w as usize).enumerate().for_each(|(y, row)| {
            for (x, acc) in row.iter_mut().enumerate() {
                let pixel = y as u64 * w as u64 + x as u64;
                let ray = camera_ray(m, transform.translation, UVec2::new(x as u32, y as u32), w, h);
                for s in done..done + batch {
                    let mut rng = Pcg::new(options.seed, pixel * 0x1_0000_0000 + s as u64);
                    *acc += scene.path_sample(ray, options.bounces, &mut rng);
                }
            }
        });
        done += batch;
        if options.time_budget.is_some_and(|budget| start.elapsed() >= budget) {
            break;
        }
    }
    let pixels = sum.iter().map(|s| (*s / done as f32).extend(1.0).to_array()).collect();
    Ok(Reference { image: LinearImage { width: w, height: h, pixels }, spp: done, elapsed: start.elapsed() })
}
