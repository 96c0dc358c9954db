//! The CPU ground truth: the same world, traversal and light pool as the GPU, integrated with many samples.
//!
//! - Primary rays go through pixel centres, exactly as `shaders/primary.wgsl` casts them, so reference and GPU
//!   images agree on geometry pixel for pixel and errors measure lighting only. The camera hit is traced once per
//!   pixel, not once per sample.
//! - Direct light: resampled importance sampling (Talbot 2005) over `candidates` lights, half drawn by power (alias
//!   table) and half uniformly from the lights near the shading point (`nearby`), each weighed by the mixture's
//!   density, at a point of a cube face that sees the shading point (uniform in area, or in solid angle for a
//!   near face, `spherical_rect`), with the unshadowed contribution as the target; one shadow ray for the chosen
//!   one (visible when the first hit lies in the light's cube). Unbiased because the target is non-zero wherever
//!   the shadowed contribution is and the power pick reaches every light; on 10^3-10^6 lights it spends the
//!   shadow ray on a light that is near and facing, not on one picked by power alone.
//! - Indirect light (`bounces` > 0): cosine-sampled diffuse bounces with next-event estimation at every vertex,
//!   Russian roulette from the third bounce on (unbiased; the bounce count is a cap, not a cost);
//!   emission is counted only at the camera hit and through next-event estimation, never twice.
//! - Lighting is the emitters only (the thesis' convention: a primary miss is black), or with `daylight` also the
//!   sun's (or moon's) disk, by one shadow ray to a uniform direction of its cone at every vertex, and the sky,
//!   reached by the cosine-sampled ray that leaves each vertex (with `bounces` 0 too: that ray is the sky's
//!   direct light); a primary miss sees the sky and the disk. Each light is counted by one strategy only.
//! - Moving objects a world saves are drawn where they are at their saved phase (`objects`): they block camera,
//!   shadow and bounce rays, and their emissive voxels, which are not in the light pool, are found by the
//!   cosine-sampled rays.
//! - Deterministic: each (pixel, sample) has its own random stream, whatever the thread schedule (rayon rows).

pub mod flip;
pub mod metrics;
pub mod nearby;
pub mod objects;
pub mod sampling;
pub mod spherical_rect;

use crate::colour::luminance;
use crate::image_io::LinearImage;
use crate::lights::daylight::Daylight;
use crate::lights::{AliasTable, Light, LightPool};
use crate::progress::Progress;
use crate::world::traversal::RAY_OFFSET;
use crate::world::{CameraView, Hit, Ray, VoxelWorld, trace};
use crate::world::{camera_ray, view_transform, world_from_clip};
use bevy::math::{UVec2, Vec3};
use nearby::{NearbyLights, Neighbourhood};
use objects::ReferenceObjects;
use rayon::prelude::*;
use sampling::{Pcg, cosine_direction, light_contains, sample_light_point};
use std::time::{Duration, Instant};

/// Changes whenever the estimator changes what a given seed draws, so cached references are not reused across
/// estimators (2: near faces by solid angle, half the candidates from the nearby lights; 3: camera rays from the
/// point at infinity, `world::camera_ray`; 4: Russian roulette from the third bounce).
pub const ESTIMATOR_VERSION: u32 = 4;

/// Diffuse bounces of the references the benches hold the GI cache to: it sums every bounce through its own
/// entries, and 8 bounces miss a measurable part of the window room's light (docs/bench/why.md). Russian
/// roulette makes the deep bounces cheap.
pub const REFERENCE_BOUNCES: u32 = 32;

/// How to integrate.
#[derive(Clone, Debug)]
pub struct ReferenceOptions {
    pub width: u32,
    pub height: u32,
    /// Samples per pixel to reach.
    pub spp: u32,
    /// Diffuse bounces after the camera hit (0 = direct light only).
    pub bounces: u32,
    /// Only the light that reaches the camera hit by bouncing (the GI cache's share, `debug=indirect`): no
    /// emission seen straight on, no direct light or disk at the camera hit; the sky the camera hit's own ray
    /// finds counts, as the cache's rays bring it. The samples drawn are those of the full image, so the full
    /// image minus this one is its direct light, sample for sample.
    pub indirect_only: bool,
    pub seed: u64,
    /// Lights resampled per shadow ray (1 = plain next-event estimation by power, uniform points on the faces:
    /// the GPU's NEE).
    pub candidates: u32,
    /// Stop early (after a whole batch of samples) when this much time has passed.
    pub time_budget: Option<Duration>,
    /// Show a progress bar (or periodic lines) on stderr.
    pub show_progress: bool,
    /// The sun or moon and the sky (`lighting=full`), or `None` for the emitters only.
    pub daylight: Option<Daylight>,
    /// Integrate only every `lattice`-th pixel of the `width` x `height` image in each direction (the pixel at
    /// `lattice * i + lattice / 2`), giving a `width / lattice` x `height / lattice` image whose pixels equal the
    /// full reference's at those points, sample for sample: an unbiased estimate of a full-size image's error at
    /// 1 / lattice^2 of its cost. 1: every pixel.
    pub lattice: u32,
}

impl Default for ReferenceOptions {
    fn default() -> Self {
        ReferenceOptions {
            width: 320,
            height: 180,
            spp: 256,
            bounces: 0,
            indirect_only: false,
            seed: 1,
            candidates: 16,
            time_budget: None,
            show_progress: false,
            daylight: None,
            lattice: 1,
        }
    }
}

/// A finished reference and how much work went into it.
#[derive(Clone, Debug)]
pub struct Reference {
    pub image: LinearImage,
    pub spp: u32,
    pub elapsed: Duration,
    /// Rays traced (camera, shadow and bounce rays), for the throughput the bench reports.
    pub rays: u64,
}

impl Reference {
    /// Rays traced per second of wall time.
    pub fn rays_per_second(&self) -> f64 {
        self.rays as f64 / self.elapsed.as_secs_f64().max(1e-9)
    }
}

/// What the camera ray hit: traced once per pixel and shared by all of its samples.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub position: Vec3,
    pub normal: Vec3,
    pub albedo: [f32; 3],
    pub emission: Vec3,
    /// On a moving object: its emission is not in the light pool, so a bounce ray that finds it counts it.
    pub on_object: bool,
}

/// A light candidate for resampling: where on which light, and its unshadowed contribution (without albedo / pi).
struct Candidate<'l> {
    light: &'l Light,
    point: Vec3,
    distance: f32,
    unshadowed: Vec3,
    target: f32,
}

/// What the integrator needs besides the world: the lights and their sampling table.
pub struct Scene<'a> {
    pub world: &'a VoxelWorld,
    pub pool: &'a LightPool,
    pub alias: &'a AliasTable,
    pub objects: &'a ReferenceObjects,
    /// The lights by place, for the candidates drawn near the shading point.
    pub nearby: &'a NearbyLights,
}

/// The light pool as the reference samples it: the pool, its alias table (power picks) and the lights by place.
pub struct ReferenceLights {
    pub pool: LightPool,
    pub alias: AliasTable,
    pub nearby: NearbyLights,
}

impl ReferenceLights {
    pub fn of(world: &VoxelWorld) -> ReferenceLights {
        let mut pool = LightPool::from_world(world);
        let alias = pool.alias().clone();
        let nearby = NearbyLights::of(&pool, &alias);
        ReferenceLights { pool, alias, nearby }
    }
}

impl<'a> Scene<'a> {
    pub fn new(world: &'a VoxelWorld, lights: &'a ReferenceLights, objects: &'a ReferenceObjects) -> Scene<'a> {
        Scene { world, pool: &lights.pool, alias: &lights.alias, objects, nearby: &lights.nearby }
    }
}

impl Scene<'_> {
    /// One estimate of the direct light reflected towards the viewer at `p` (face normal `n`, diffuse `albedo`),
    /// by resampling `candidates` power-drawn lights and tracing one shadow ray. `rays` counts the shadow ray.
    pub fn direct_sample(
        &self,
        p: Vec3,
        n: Vec3,
        albedo: [f32; 3],
        candidates: u32,
        rng: &mut Pcg,
        rays: &mut u64,
    ) -> Vec3 {
        self.direct_sample_near(p, n, albedo, candidates, &self.neighbourhood(p, candidates), rng, rays)
    }

    /// The lights near `p` that `candidates` resampled candidates draw from (none for plain NEE): the same for
    /// every sample at `p`, so a pixel's samples share one look-up.
    pub fn neighbourhood(&self, p: Vec3, candidates: u32) -> Neighbourhood<'_> {
        if candidates <= 1 { Neighbourhood::EMPTY } else { self.nearby.around(p) }
    }

    /// `direct_sample` with the lights near `p` already looked up (`neighbourhood`).
    #[allow(clippy::too_many_arguments)]
    fn direct_sample_near(
        &self,
        p: Vec3,
        n: Vec3,
        albedo: [f32; 3],
        candidates: u32,
        around: &Neighbourhood,
        rng: &mut Pcg,
        rays: &mut u64,
    ) -> Vec3 {
        let candidates = candidates.max(1);
        // One candidate is plain next-event estimation, the GPU's NEE: a light by power, a uniform point on a face.
        let plain = candidates == 1;
        let mut chosen: Option<Candidate> = None;
        let mut weight_sum = 0.0f32;
        for _ in 0..candidates {
            // Every draw takes the same numbers whatever happens, so streams stay aligned across settings.
            let r_column = rng.next_u32();
            let u = [rng.next_f32(), rng.next_f32(), rng.next_f32(), rng.next_f32(), rng.next_f32()];
            let u_choose = rng.next_f32();
            let Some((candidate, pdf)) = self.candidate(p, n, around, !plain, r_column, u) else { continue };
            let weight = candidate.target / pdf;
            if !(weight.is_finite() && weight > 0.0) {
                continue;
            }
            weight_sum += weight;
            if u_choose * weight_sum < weight {
                chosen = Some(candidate);
            }
        }
        let Some(chosen) = chosen else { return Vec3::ZERO };
        *rays += 1;
        let origin = p + n * RAY_OFFSET;
        let hit = self.first_hit(&Ray::new(origin, chosen.point - origin), chosen.distance + 1.0);
        if !hit.is_some_and(|(h, on_object)| !on_object && light_contains(chosen.light, h.voxel)) {
            return Vec3::ZERO;
        }
        // f / p_hat x (sum of weights / M): the RIS estimator's unbiased contribution weight.
        let contribution_weight = weight_sum / (candidates as f32 * chosen.target);
        Vec3::from(albedo) * chosen.unshadowed * (contribution_weight / std::f32::consts::PI)
    }

    /// One light at a point of a face that sees `p`, with its pdf (per unit area) and its unshadowed
    /// contribution; `None` when it cannot light `p`. The light is drawn by power, or (half the time, when any
    /// lies near) uniformly from `around`; its pdf is the mixture's. `u`: the pick within the alias column, the
    /// face, the point on it, and the choice between the two picks.
    fn candidate(
        &self,
        p: Vec3,
        n: Vec3,
        around: &Neighbourhood,
        near_by_solid_angle: bool,
        r_column: u32,
        u: [f32; 5],
    ) -> Option<(Candidate<'_>, f32)> {
        let near_share = if around.is_empty() { 0.0 } else { 0.5 };
        // A power pick's chance comes with it; a near pick looks it up.
        let (slot, power_pdf) = if u[4] < near_share {
            let slot = around.pick(r_column)?;
            (slot, self.nearby.power_pdf(slot))
        } else {
            self.alias.sample(r_column, u[0])?
        };
        let (Some(light), _) = self.pool.slot(slot)? else { return None };
        let pick_pdf = (1.0 - near_share) * power_pdf + near_share * around.pdf(light.min);
        let point = sample_light_point(light, p, near_by_solid_angle, u[1], u[2], u[3])?;
        let to_light = point.position - p;
        let d2 = to_light.length_squared();
        if d2 <= 1e-12 {
            return None;
        }
        let distance = d2.sqrt();
        let wi = to_light / distance;
        let (cos_surface, cos_light) = (n.dot(wi), -point.normal.dot(wi));
        if cos_surface <= 0.0 || cos_light <= 0.0 {
            return None;
        }
        let unshadowed = Vec3::from(light.radiance) * (cos_surface * cos_light / d2);
        let target = luminance(unshadowed.to_array());
        let candidate = Candidate { light, point: point.position, distance, unshadowed, target };
        Some((candidate, pick_pdf * point.pdf_area))
    }

    /// The first voxel the ray meets, of the world or of a moving object (`true`).
    fn first_hit(&self, ray: &Ray, max_distance: f32) -> Option<(Hit, bool)> {
        let world = trace(&self.world.grid, ray, max_distance);
        match self.objects.trace(ray, world.map_or(max_distance, |h| h.distance)) {
            Some(object) => Some((object, true)),
            None => world.map(|h| (h, false)),
        }
    }

    /// What the ray hits, or `None` for a miss (black: no sky in the reference).
    pub fn surface(&self, ray: &Ray) -> Option<SurfaceHit> {
        let (hit, on_object) = self.first_hit(ray, f32::INFINITY)?;
        let material = self.objects.material(self.world, hit.material)?;
        Some(SurfaceHit {
            position: ray.at(hit.distance),
            normal: hit.face.normal().as_vec3(),
            // Moving objects' voxels are in their own coordinates: flat colours, as on the GPU.
            albedo: if on_object { material.albedo } else { self.world.voxel_albedo(material, hit.voxel) },
            emission: Vec3::from(material.radiance()),
            on_object,
        })
    }

    /// One sample of the light the disk of `day` gives a diffuse surface at `p`: a uniform direction of its cone
    /// (pdf 1 / solid angle, cancelling the radiance's) and one shadow ray. `shaders/lib/lights.wgsl`
    /// `disk_sample` is the same.
    pub fn disk_sample(
        &self,
        day: &Daylight,
        p: Vec3,
        n: Vec3,
        albedo: [f32; 3],
        rng: &mut Pcg,
        rays: &mut u64,
    ) -> Vec3 {
        let dir = day.disk_direction(rng.next_f32(), rng.next_f32());
        let cos_surface = n.dot(dir);
        if !day.disk_on() || cos_surface <= 0.0 {
            return Vec3::ZERO;
        }
        *rays += 1;
        if self.first_hit(&Ray::new(p + n * RAY_OFFSET, dir), f32::INFINITY).is_some() {
            return Vec3::ZERO;
        }
        Vec3::from(albedo) * day.disk * cos_surface
    }

    /// One path sample of the radiance leaving the camera hit `first` towards the camera.
    pub fn path_sample(&self, first: &SurfaceHit, options: &ReferenceOptions, rng: &mut Pcg, rays: &mut u64) -> Vec3 {
        let around = self.neighbourhood(first.position, options.candidates);
        self.path_sample_near(first, &around, options, rng, rays)
    }

    /// `path_sample` with the lights near the camera hit already looked up (`neighbourhood`).
    pub fn path_sample_near(
        &self,
        first: &SurfaceHit,
        first_around: &Neighbourhood,
        options: &ReferenceOptions,
        rng: &mut Pcg,
        rays: &mut u64,
    ) -> Vec3 {
        // What the camera hit's own light (emission, direct, disk) counts for: nothing in the indirect image.
        let own = if options.indirect_only { 0.0 } else { 1.0 };
        let mut radiance = first.emission * own;
        let mut throughput = Vec3::ONE;
        let (mut p, mut n, mut albedo) = (first.position, first.normal, first.albedo);
        for bounce in 0..=options.bounces {
            let weight = if bounce == 0 { throughput * own } else { throughput };
            let direct = if bounce == 0 {
                self.direct_sample_near(p, n, albedo, options.candidates, first_around, rng, rays)
            } else {
                self.direct_sample(p, n, albedo, options.candidates, rng, rays)
            };
            radiance += weight * direct;
            if let Some(day) = &options.daylight {
                radiance += weight * self.disk_sample(day, p, n, albedo, rng, rays);
            }
            let last = bounce == options.bounces;
            // Without a sky (or a glowing object) the last vertex's ray could only find emitters that next-event
            // estimation counts.
            if last && options.daylight.is_none() && !self.objects.emissive() {
                break;
            }
            // Cosine sampling cancels cos / pi against the pdf: the throughput picks up the albedo.
            throughput *= Vec3::from(albedo);
            // Russian roulette past the first bounces: a path goes on with the probability of its throughput and
            // weighs what it finds by its inverse (unbiased), so a reference with every bounce that matters (32)
            // costs about what one with 8 did, and the GI cache, which sums every bounce, meets a fair truth.
            // (Not at the last vertex: its ray only looks for the sky or a glowing object.)
            if bounce >= ROULETTE_FROM && !last {
                let survive = throughput.max_element().min(1.0);
                if rng.next_f32() >= survive {
                    break;
                }
                throughput /= survive;
            }
            let dir = cosine_direction(n, rng.next_f32(), rng.next_f32());
            *rays += 1;
            match self.surface(&Ray::new(p + n * RAY_OFFSET, dir)) {
                None => {
                    if let Some(day) = &options.daylight {
                        radiance += throughput * day.sky(dir);
                    }
                    break;
                }
                Some(next) => {
                    if next.on_object {
                        radiance += throughput * next.emission;
                    }
                    if last {
                        break;
                    }
                    (p, n, albedo) = (next.position, next.normal, next.albedo);
                }
            }
        }
        radiance
    }
}

/// Path vertices before Russian roulette may end a path: the first bounces carry most of the indirect light and
/// always go on.
const ROULETTE_FROM: u32 = 2;

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
    if !(1..=4096).contains(&options.candidates) {
        return Err(format!("candidates {} must be within 1..=4096", options.candidates));
    }
    let step = options.lattice;
    if step == 0 || step > w.min(h) {
        return Err(format!("lattice {step} must be within 1..={} for a {w}x{h} image", w.min(h)));
    }
    // A zero field of view or a zero direction would give a silently black image.
    if let Some(problem) = view.problem() {
        return Err(problem);
    }
    let start = Instant::now();
    let lights = ReferenceLights::of(world);
    let objects = ReferenceObjects::of(world)?;
    let scene = Scene::new(world, &lights, &objects);
    let transform = view_transform(view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), w, h);
    // The pixels integrated (all of them, or the lattice's), as pixels of the full image.
    let (out_w, out_h) = (w / step, h / step);
    let full_pixel = |x: u32, y: u32| UVec2::new(x * step + step / 2, y * step + step / 2);
    // Camera hits once per pixel: every sample of a pixel shades the same point. A miss sees the background.
    // (Not the bounced light of the indirect image.)
    let background = |ray: &Ray| match options.daylight {
        Some(day) if !options.indirect_only => day.background(ray.dir),
        _ => Vec3::ZERO,
    };
    let (hits, backgrounds): (Vec<Option<SurfaceHit>>, Vec<Vec3>) = (0..out_w * out_h)
        .into_par_iter()
        .map(|i| {
            let ray = camera_ray(m, transform.translation, full_pixel(i % out_w, i / out_w), w, h);
            (scene.surface(&ray), background(&ray))
        })
        .unzip();
    let mut rays = (out_w * out_h) as u64;
    let mut sum = vec![Vec3::ZERO; (out_w * out_h) as usize];
    let mut done = 0u32;
    // Rows x samples; a time budget ends it early (the bar then stops short).
    let total = options.spp as u64 * out_h as u64;
    let progress = if options.show_progress { Progress::new("reference", total) } else { Progress::hidden(total) };
    // Batches of samples, so a time budget can stop between them.
    while done < options.spp {
        let batch = (options.spp - done).min(16.max(done / 4));
        rays += sum
            .par_chunks_mut(out_w as usize)
            .zip(hits.par_chunks(out_w as usize))
            .enumerate()
            .map(|(y, (row, row_hits))| {
                let mut row_rays = 0u64;
                for (x, (acc, hit)) in row.iter_mut().zip(row_hits).enumerate() {
                    let Some(hit) = hit else { continue };
                    // The full image's pixel index keys the random stream, so a lattice pixel draws its samples.
                    let at = full_pixel(x as u32, y as u32);
                    let pixel = at.y as u64 * w as u64 + at.x as u64;
                    // The lights near the hit, looked up once for the batch's samples.
                    let around = scene.neighbourhood(hit.position, options.candidates);
                    for s in done..done + batch {
                        let mut rng = Pcg::new(options.seed, pixel * 0x1_0000_0000 + s as u64);
                        *acc += scene.path_sample_near(hit, &around, options, &mut rng, &mut row_rays);
                    }
                }
                progress.advance(batch as u64);
                row_rays
            })
            .sum::<u64>();
        done += batch;
        if options.time_budget.is_some_and(|budget| start.elapsed() >= budget) {
            break;
        }
    }
    progress.finish();
    let pixels = sum
        .iter()
        .zip(&hits)
        .zip(&backgrounds)
        .map(|((s, hit), background)| if hit.is_some() { *s / done as f32 } else { *background }.extend(1.0).to_array())
        .collect();
    let image = LinearImage { width: out_w, height: out_h, pixels };
    Ok(Reference { image, spp: done, elapsed: start.elapsed(), rays })
}
