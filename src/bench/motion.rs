//! Ghosting under motion (`glowbrick bench --denoise`, and alone with `--motion`): a scripted camera path inside
//! the cornell box while a block slides across the view, raw and denoised, every frame against its own CPU
//! reference (the block where that frame has it: the reference draws saved objects). Direct light only
//! (`lighting=restir gi=off`, references without bounces): a converged per-frame reference with bounces costs
//! minutes a frame on 2 cores.
//!
//! Besides the whole frame, the **trail**: pixels the block covered (seen from this frame's camera) in one of the
//! previous frames but not now. A ghost is history that still shows the block there; its signed error is the
//! ghost's strength, and split by the frames since the block left a pixel (its **age**), how long it lasts.

use crate::colour::luminance;
use crate::dynamic::{DynamicObject, Motion, ObjectClock, model_for_world, spawn_object_in};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::{LinearImage, write_image};
use crate::reference::metrics::{Metrics, compare};
use crate::reference::objects::ReferenceObjects;
use crate::reference::{ReferenceOptions, render_reference};
use crate::settings::RenderSettings;
use crate::world::objects::{SavedMotion, SavedObject};
use crate::world::recipe::load_scene;
use crate::world::{CameraView, VoxelWorld, camera_ray, trace, view_transform, world_from_clip};
use bevy::math::{UVec2, Vec3};
use std::sync::Arc;

/// Frames before the path starts (camera and block still), frames along it, frames a trail remembers.
const SETTLE_FRAMES: u32 = 24;
const PATH_FRAMES: u32 = 32;
const TRAIL_FRAMES: u32 = 8;
/// A trail age whose mean signed error over the path passes this share of the reference there still shows a
/// ghost; the ghost's length is the oldest such age.
pub const GHOST_THRESHOLD: f64 = 0.03;
/// The block's motion: back and forth along x, 24 voxels each way in 1 s; one frame is 1/60 s of it.
const ANCHOR: Vec3 = Vec3::new(54.0, 58.0, 34.0);
const SLIDE: Vec3 = Vec3::new(24.0, 0.0, 0.0);
const PERIOD: f32 = 2.0;
const FRAME_SECONDS: f32 = 1.0 / 60.0;
const LIGHTING: [&str; 2] = ["lighting=restir", "gi=off"];

/// One frame of the path: raw and denoised against its reference, over the whole frame and over the trail.
pub struct MotionFrame {
    pub frame: u32,
    pub raw: Metrics,
    pub denoised: Metrics,
    pub trail_pixels: usize,
    /// The reference's mean luminance over the trail.
    pub trail_mean: f64,
    pub raw_trail: Option<Metrics>,
    pub denoised_trail: Option<Metrics>,
    /// The block itself (its pixels now): the denoiser follows it by its motion vector.
    pub block_pixels: usize,
    pub block_mean: f64,
    pub raw_block: Option<Metrics>,
    pub denoised_block: Option<Metrics>,
    /// The trail by age (index 0: the block left these pixels 1 frame ago, up to `TRAIL_FRAMES`).
    pub trail_by_age: Vec<TrailAge>,
}

/// The trail pixels of one age in one frame: how many, and the luminance sums of the reference and of the raw
/// and denoised frames' signed errors there.
#[derive(Clone, Copy, Default, Debug)]
pub struct TrailAge {
    pub pixels: usize,
    pub reference: f64,
    pub raw_error: f64,
    pub denoised_error: f64,
}

/// The whole path, and the last still frame before it as the baseline.
pub struct MotionRun {
    pub size: (u32, u32),
    pub spp: u32,
    pub still_raw: Metrics,
    pub still_denoised: Metrics,
    pub frames: Vec<MotionFrame>,
    /// MAE between two references of the first path frame with different seeds.
    pub reference_noise: f64,
    pub mean: f64,
    /// Path frames `SNAPSHOT_FRAMES`: raw, denoised and reference images, for the report's folder.
    pub snapshots: Vec<(u32, [LinearImage; 3])>,
}

/// The path frames whose images the bench keeps.
pub const SNAPSHOT_FRAMES: [u32; 4] = [8, 16, 24, PATH_FRAMES - 1];

/// The camera of path frame `k` (frames before the path: `k` = 0): a strafe along +x of 0.25 voxels and a turn
/// of 0.3 degrees a frame.
fn camera(base: &CameraView, k: u32) -> CameraView {
    let yaw = (0.3f32 * k as f32).to_radians();
    let d = Vec3::from(base.direction);
    let direction = Vec3::new(d.x * yaw.cos() + d.z * yaw.sin(), d.y, d.z * yaw.cos() - d.x * yaw.sin());
    let origin = Vec3::from(base.origin) + Vec3::X * 0.25 * k as f32;
    CameraView { name: format!("path-{k}"), origin: origin.to_array(), direction: direction.to_array(), ..base.clone() }
}

fn block_age(k: u32) -> f32 {
    k as f32 * FRAME_SECONDS
}

/// The world as the reference sees it at path frame `k`: the block saved at that frame's phase.
fn world_at(world: &VoxelWorld, k: u32) -> VoxelWorld {
    let mut w = world.clone();
    let motion = SavedMotion::Slide { offset: SLIDE.into(), period: PERIOD };
    w.objects = Some(vec![SavedObject { model: "block".into(), motion, anchor: ANCHOR.into(), age: block_age(k) }]);
    w
}

/// The rendered sequence of one setting: settle frames, then the path. Returns the last still frame and the path.
fn render_path(
    world: &VoxelWorld,
    base: &CameraView,
    size: (u32, u32),
    denoise: &str,
    extra: &[String],
) -> Result<(LinearImage, Vec<LinearImage>), String> {
    let pairs: Vec<String> =
        LIGHTING.iter().chain(&[denoise]).map(|p| p.to_string()).chain(extra.iter().cloned()).collect();
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width: size.0, height: size.1, settings, ..Default::default() };
    let mut world = world.clone();
    let block = Arc::new(model_for_world("block", &mut world)?);
    let mut r = HeadlessRenderer::new(world, base, &options)?;
    // The bench sets each frame's phase itself.
    r.app_mut().world_mut().resource_mut::<ObjectClock>().step = 0.0;
    spawn_object_in(r.app_mut().world_mut(), block, Motion::Slide { offset: SLIDE, period: PERIOD }, ANCHOR)?;
    let mut frames = r.render_sequence(SETTLE_FRAMES + PATH_FRAMES, |n, r| {
        let k = n.saturating_sub(SETTLE_FRAMES);
        r.set_view(&camera(base, k));
        let app = r.app_mut().world_mut();
        let mut objects = app.query::<&mut DynamicObject>();
        for mut object in objects.iter_mut(app) {
            object.age = block_age(k);
        }
    })?;
    let path = frames.split_off(SETTLE_FRAMES as usize);
    Ok((frames.pop().ok_or("no settle frame")?, path))
}

/// Two masks of `view` at path frame `k`: the block's pixels now, and its trail by age (j where the block of frame
/// `k - j`, j = 1..TRAIL_FRAMES, was in front of the world, the smallest such j, and the block of frame `k` is not;
/// 0 off the trail).
fn block_masks(
    world: &VoxelWorld,
    view: &CameraView,
    size: (u32, u32),
    k: u32,
) -> Result<(Vec<bool>, Vec<u32>), String> {
    let (w, h) = size;
    let transform = view_transform(view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), w, h);
    let blocks: Vec<ReferenceObjects> = (k.saturating_sub(TRAIL_FRAMES)..=k)
        .map(|f| ReferenceObjects::of(&world_at(world, f)))
        .collect::<Result<_, _>>()?;
    let (now, before) = blocks.split_last().ok_or("no frames")?;
    let (mut on_block, mut age) = (Vec::new(), Vec::new());
    for i in 0..w * h {
        let ray = camera_ray(m, transform.translation, UVec2::new(i % w, i / w), w, h);
        let limit = trace(&world.grid, &ray, f32::INFINITY).map_or(f32::INFINITY, |hit| hit.distance);
        let seen = now.trace(&ray, limit).is_some();
        on_block.push(seen);
        let left = before.iter().rev().position(|b| b.trace(&ray, limit).is_some()).map_or(0, |j| j as u32 + 1);
        age.push(if seen { 0 } else { left });
    }
    Ok((on_block, age))
}

/// Sums over the trail's pixels of each age (1..=TRAIL_FRAMES).
fn trail_by_age(age: &[u32], raw: &LinearImage, denoised: &LinearImage, truth: &LinearImage) -> Vec<TrailAge> {
    let lum = |p: &[f32; 4]| luminance([p[0], p[1], p[2]]) as f64;
    let mut ages = vec![TrailAge::default(); TRAIL_FRAMES as usize];
    for (i, a) in age.iter().enumerate().filter(|(_, a)| **a > 0) {
        let t = lum(&truth.pixels[i]);
        let slot = &mut ages[*a as usize - 1];
        slot.pixels += 1;
        slot.reference += t;
        slot.raw_error += lum(&raw.pixels[i]) - t;
        slot.denoised_error += lum(&denoised.pixels[i]) - t;
    }
    ages
}

/// The path's trail by age, summed over its frames: per age, pixels a frame and the raw and denoised mean signed
/// errors as shares of the reference there.
pub fn ghost_by_age(frames: &[MotionFrame]) -> Vec<(f64, f64, f64)> {
    (0..TRAIL_FRAMES as usize)
        .map(|a| {
            let sum = frames.iter().fold(TrailAge::default(), |s, f| {
                let t = f.trail_by_age[a];
                TrailAge {
                    pixels: s.pixels + t.pixels,
                    reference: s.reference + t.reference,
                    raw_error: s.raw_error + t.raw_error,
                    denoised_error: s.denoised_error + t.denoised_error,
                }
            });
            let r = sum.reference.max(1e-12);
            (sum.pixels as f64 / frames.len().max(1) as f64, sum.raw_error / r, sum.denoised_error / r)
        })
        .collect()
}

/// The ghost's length in frames: the oldest trail age whose mean signed error passes `GHOST_THRESHOLD` of the
/// reference there (0: none does).
pub fn ghost_length(errors_by_age: impl Iterator<Item = f64>) -> u32 {
    errors_by_age.enumerate().filter(|(_, e)| e.abs() > GHOST_THRESHOLD).map(|(a, _)| a as u32 + 1).max().unwrap_or(0)
}

fn masked(image: &LinearImage, keep: &[bool]) -> LinearImage {
    let pixels: Vec<[f32; 4]> = image.pixels.iter().zip(keep).filter(|(_, k)| **k).map(|(p, _)| *p).collect();
    LinearImage { width: pixels.len() as u32, height: 1, pixels }
}

/// Runs the path raw and denoised at `size` and compares every frame with its reference of `reference_spp`
/// samples per pixel; `extra` settings on top of the path's own (`--set`, e.g. `render_scale=0.5`).
pub fn run_motion(size: (u32, u32), reference_spp: u32, extra: &[String]) -> Result<MotionRun, String> {
    let world = load_scene("cornell").map_err(|e| e.to_string())?;
    let base = world.view(Some("inside")).cloned().ok_or("cornell: no view 'inside'")?;
    let (still_raw, raw) = render_path(&world, &base, size, "denoise=off", extra)?;
    let (still_denoised, denoised) = render_path(&world, &base, size, "denoise=on", extra)?;
    let options = |seed| ReferenceOptions {
        width: size.0,
        height: size.1,
        spp: reference_spp,
        bounces: 0,
        seed,
        ..Default::default()
    };
    let reference = |k: u32, seed: u64| -> Result<LinearImage, String> {
        Ok(render_reference(&world_at(&world, k), &camera(&base, k), &options(seed))?.image)
    };
    let still_truth = reference(0, 1)?;
    let reference_noise = compare(&reference(0, 2)?, &still_truth)?.mae;
    let mut frames = Vec::new();
    let mut snapshots = Vec::new();
    for k in 0..PATH_FRAMES {
        let truth = if k == 0 { still_truth.clone() } else { reference(k, 1)? };
        let (block, age) = block_masks(&world, &camera(&base, k), size, k)?;
        let keep: Vec<bool> = age.iter().map(|a| *a > 0).collect();
        let trail_pixels = keep.iter().filter(|k| **k).count();
        let over = |image: &LinearImage, mask: &[bool]| -> Result<Option<Metrics>, String> {
            if !mask.contains(&true) {
                return Ok(None);
            }
            compare(&masked(image, mask), &masked(&truth, mask)).map(Some)
        };
        let on_trail = |image: &LinearImage| over(image, &keep);
        let (r, d) = (&raw[k as usize], &denoised[k as usize]);
        if SNAPSHOT_FRAMES.contains(&k) {
            snapshots.push((k, [r.clone(), d.clone(), truth.clone()]));
        }
        frames.push(MotionFrame {
            frame: k,
            raw: compare(r, &truth)?,
            denoised: compare(d, &truth)?,
            trail_pixels,
            trail_mean: if trail_pixels == 0 { 0.0 } else { masked(&truth, &keep).mean_luminance() },
            raw_trail: on_trail(r)?,
            denoised_trail: on_trail(d)?,
            block_pixels: block.iter().filter(|b| **b).count(),
            block_mean: if block.contains(&true) { masked(&truth, &block).mean_luminance() } else { 0.0 },
            raw_block: over(r, &block)?,
            denoised_block: over(d, &block)?,
            trail_by_age: trail_by_age(&age, r, d, &truth),
        });
        eprintln!("motion bench: frame {k}: raw {} / denoised {}", frames[k as usize].raw, frames[k as usize].denoised);
    }
    Ok(MotionRun {
        size,
        spp: reference_spp,
        still_raw: compare(&still_raw, &still_truth)?,
        still_denoised: compare(&still_denoised, &still_truth)?,
        frames,
        reference_noise,
        mean: still_truth.mean_luminance(),
        snapshots,
    })
}

/// Writes the snapshots into `out` as `motion-K-raw.exr`, `-denoised.exr` and `-reference.exr` (linear, for
/// `glowbrick compare`) and one PNG strip a frame, raw | denoised | reference.
pub fn write_snapshots(run: &MotionRun, out: &std::path::Path) -> Result<(), String> {
    for (k, images) in &run.snapshots {
        for (image, name) in images.iter().zip(["raw", "denoised", "reference"]) {
            write_image(image, &out.join(format!("motion-{k}-{name}.exr")))?;
        }
        write_image(&side_by_side(images), &out.join(format!("motion-{k}.png")))?;
    }
    Ok(())
}

/// Images of one size next to each other.
fn side_by_side(images: &[LinearImage]) -> LinearImage {
    let (w, h) = (images[0].width, images[0].height);
    let mut pixels = Vec::with_capacity((w * h) as usize * images.len());
    for y in 0..h {
        for image in images {
            pixels.extend_from_slice(&image.pixels[(y * w) as usize..((y + 1) * w) as usize]);
        }
    }
    LinearImage { width: w * images.len() as u32, height: h, pixels }
}

fn mean_of(frames: &[MotionFrame], f: impl Fn(&MotionFrame) -> Option<f64>) -> f64 {
    let values: Vec<f64> = frames.iter().filter_map(f).collect();
    values.iter().sum::<f64>() / values.len().max(1) as f64
}

/// The value of largest magnitude (signed).
fn largest(frames: &[MotionFrame], f: impl Fn(&MotionFrame) -> Option<f64>) -> f64 {
    frames.iter().filter_map(f).fold(0.0, |a, b| if b.abs() > a.abs() { b } else { a })
}

/// A table row over one region of every frame (pixels, raw and denoised metrics there), averaged over the path.
fn region_row(
    f: &[MotionFrame],
    name: &str,
    region: impl Fn(&MotionFrame) -> (usize, Option<Metrics>, Option<Metrics>),
) -> String {
    let pixels = mean_of(f, |m| Some(region(m).0 as f64));
    let raw = |pick: fn(Metrics) -> f64| mean_of(f, |m| region(m).1.map(pick));
    let denoised = |pick: fn(Metrics) -> f64| mean_of(f, |m| region(m).2.map(pick));
    format!(
        "| path, {name} (mean {pixels:.0} a frame) | {:.4} | {:.4} | {:.1}x | {:.5} | {:.5} |\n",
        raw(|t| t.relmse),
        denoised(|t| t.relmse),
        raw(|t| t.relmse) / denoised(|t| t.relmse).max(1e-12),
        raw(|t| t.mae),
        denoised(|t| t.mae)
    )
}

/// The markdown section.
pub fn motion_markdown(run: &MotionRun) -> String {
    let f = &run.frames;
    let mut text = format!(
        "\n## Ghosting under motion\n\ncornell `inside`, {}x{}, `lighting=restir gi=off` (direct light: a \
         converged reference with bounces for every frame of a path would take minutes a frame). {SETTLE_FRAMES} \
         still frames, then {PATH_FRAMES} frames in which the camera strafes 0.25 voxels and turns 0.3 degrees a \
         frame while a 3-voxel block slides 0.4 voxels a frame across the view. Every frame against its own \
         {}-spp reference with the block where that frame has it (reference noise, MAE between two seeds: \
         {:.5}; mean luminance {:.4}). **Trail**: pixels the block covered in one of the {TRAIL_FRAMES} frames \
         before, seen from this frame's camera, and not now; its bias is a ghost's strength.\n\n\
         | | raw relMSE | denoised relMSE | raw / denoised | raw MAE | denoised MAE |\n|---|---|---|---|---|---|\n",
        run.size.0, run.size.1, run.spp, run.reference_noise, run.mean
    );
    text += &format!(
        "| last still frame | {:.4} | {:.4} | {:.1}x | {:.5} | {:.5} |\n",
        run.still_raw.relmse,
        run.still_denoised.relmse,
        run.still_raw.relmse / run.still_denoised.relmse.max(1e-12),
        run.still_raw.mae,
        run.still_denoised.mae
    );
    let (raw, den) = (mean_of(f, |m| Some(m.raw.relmse)), mean_of(f, |m| Some(m.denoised.relmse)));
    text += &format!(
        "| path, mean of {} frames | {raw:.4} | {den:.4} | {:.1}x | {:.5} | {:.5} |\n",
        f.len(),
        raw / den.max(1e-12),
        mean_of(f, |m| Some(m.raw.mae)),
        mean_of(f, |m| Some(m.denoised.mae))
    );
    text += &region_row(f, "trail pixels", |m| (m.trail_pixels, m.raw_trail, m.denoised_trail));
    text += &region_row(f, "the block's pixels", |m| (m.block_pixels, m.raw_block, m.denoised_block));
    let block_mean = mean_of(f, |m| (m.block_pixels > 0).then_some(m.block_mean));
    text += &format!(
        "\nOn the block (reference mean {block_mean:.4}), the mean signed error of the frames: raw {:+.2}%, denoised \
         {:+.2}% of it.\n",
        100.0 * mean_of(f, |m| m.raw_block.map(|t| t.bias)) / block_mean.max(1e-12),
        100.0 * mean_of(f, |m| m.denoised_block.map(|t| t.bias)) / block_mean.max(1e-12)
    );
    let trail_mean = mean_of(f, |m| (m.trail_pixels > 0).then_some(m.trail_mean));
    let trail_bias = |pick: fn(&MotionFrame) -> Option<Metrics>| mean_of(f, |m| pick(m).map(|t| t.bias));
    text += &format!(
        "\nOver the trail (reference mean {trail_mean:.4}), the mean signed error of the frames: raw {:+.2}%, \
         denoised {:+.2}% of it; the largest in one frame: raw {:+.2}%, denoised {:+.2}%.\n",
        100.0 * trail_bias(|m| m.raw_trail) / trail_mean.max(1e-12),
        100.0 * trail_bias(|m| m.denoised_trail) / trail_mean.max(1e-12),
        100.0 * largest(f, |m| m.raw_trail.map(|t| t.bias / m.trail_mean.max(1e-12))),
        100.0 * largest(f, |m| m.denoised_trail.map(|t| t.bias / m.trail_mean.max(1e-12)))
    );
    let ages = ghost_by_age(f);
    text += &format!(
        "\nThe trail by age (frames since the block left the pixel), over the path: the mean signed error as a share \
         of the reference there. The ghost's length is the oldest age past {:.0}%: raw {} frames, denoised {} \
         frames.\n\n| age | pixels a frame | raw | denoised |\n|---|---|---|---|\n",
        100.0 * GHOST_THRESHOLD,
        ghost_length(ages.iter().map(|a| a.1)),
        ghost_length(ages.iter().map(|a| a.2))
    );
    for (a, (pixels, raw, denoised)) in ages.iter().enumerate() {
        text += &format!("| {} | {pixels:.1} | {:+.2}% | {:+.2}% |\n", a + 1, 100.0 * raw, 100.0 * denoised);
    }
    text += "\nFrame by frame (every fourth): bias is the signed mean error, over the frame and over the trail.\n\n\
             | frame | raw relMSE | denoised relMSE | raw bias | denoised bias | trail pixels | trail bias raw | \
             trail bias denoised |\n|---|---|---|---|---|---|---|---|\n";
    let bias = |m: Option<Metrics>| m.map_or("-".to_string(), |m| format!("{:+.5}", m.bias));
    for m in f.iter().filter(|m| m.frame % 4 == 0 || m.frame + 1 == PATH_FRAMES) {
        text += &format!(
            "| {} | {:.4} | {:.4} | {:+.5} | {:+.5} | {} | {} | {} |\n",
            m.frame,
            m.raw.relmse,
            m.denoised.relmse,
            m.raw.bias,
            m.denoised.bias,
            m.trail_pixels,
            bias(m.raw_trail),
            bias(m.denoised_trail)
        );
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The ghost's length is the oldest age past the threshold, whichever sign, even after a quiet age.
    #[test]
    fn the_ghost_length_is_the_oldest_age_past_the_threshold() {
        assert_eq!(ghost_length([0.01, -0.02, 0.0].into_iter()), 0);
        assert_eq!(ghost_length([0.2, 0.05, 0.01, 0.0].into_iter()), 2);
        assert_eq!(ghost_length([0.2, 0.01, -0.04, 0.0, 0.0].into_iter()), 3);
    }

    /// Trail pixels are summed into their age's slot; pixels off the trail are not counted.
    #[test]
    fn trail_sums_go_to_their_age() {
        let image = |v: f32| LinearImage { width: 3, height: 1, pixels: vec![[v, v, v, 1.0]; 3] };
        let ages = trail_by_age(&[0, 1, 3], &image(2.0), &image(1.5), &image(1.0));
        assert_eq!(ages.len(), TRAIL_FRAMES as usize);
        assert_eq!((ages[0].pixels, ages[1].pixels, ages[2].pixels), (1, 0, 1));
        assert!((ages[2].reference - 1.0).abs() < 1e-6 && (ages[2].raw_error - 1.0).abs() < 1e-6);
        assert!((ages[0].denoised_error - 0.5).abs() < 1e-6);
    }
}
