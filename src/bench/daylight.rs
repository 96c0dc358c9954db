//! The game's lighting bench (`glowbrick bench --daylight`): `lighting=full` (the sun's or moon's disk, the sky
//! and every lamp, with the GI cache as `play` runs it) at noon, dusk and night, against the CPU reference that
//! integrates the same lighting with diffuse bounces; and what the disk and the sky cost on top of ReSTIR over the
//! emitters alone, at 10^3 and 10^5 lamps. Writes `daylight.md`.

use super::reference_cache::{Reference, ReferenceCache};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::lights::daylight::Daylight;
use crate::reference::REFERENCE_BOUNCES;
use crate::reference::metrics::{Metrics, compare};
use crate::settings::RenderSettings;
use crate::world::recipe::{generated_world, load_scene};
use crate::world::{CameraView, VoxelWorld};
use bevy::math::UVec3;
use std::path::Path;
use std::time::Instant;

/// The times of day measured: noon, a low sun before sunset, and night (moon and lamps).
pub const TIMES: [(&str, f32); 3] = [("noon", 12.0), ("dusk", 17.5), ("night", 0.0)];
/// Frames for the GI cache to settle before accumulating, frames timed, frames averaged.
const SETTLE_FRAMES: u32 = 100;
const TIMED_FRAMES: u32 = 16;
const AVERAGED_FRAMES: u32 = 128;
/// The settings of the game's frame (as `play` starts): the default lighting with the GI cache.
const GAME_PAIRS: [&str; 2] = ["lighting=full", "gi=on"];

/// What `bench --daylight` runs.
#[derive(Clone, Debug)]
pub struct DaylightConfig {
    pub width: u32,
    pub height: u32,
    pub reference_spp: u32,
}

impl DaylightConfig {
    /// The bench at its own size, with `reference_spp` samples per pixel in the references.
    pub fn new(reference_spp: u32) -> Self {
        DaylightConfig { width: 160, height: 90, reference_spp }
    }
}

/// One scene at one time of day.
struct DaylightRow {
    scene: String,
    time: &'static str,
    hours: f32,
    frame_ms: f64,
    /// One frame, as a player sees it before anything accumulates.
    single: Metrics,
    /// `AVERAGED_FRAMES` frames accumulated.
    accumulated: Metrics,
    mean: f64,
    noise: f64,
}

/// The frame time of `lighting=full` against `lighting=emitters` on one many-light scene.
struct CostRow {
    scene: &'static str,
    lights: usize,
    full_ms: f64,
    emitters_ms: f64,
}

fn renderer(
    world: &VoxelWorld,
    view: &CameraView,
    config: &DaylightConfig,
    pairs: &[String],
) -> Result<HeadlessRenderer, String> {
    let settings = RenderSettings::default().with_pairs(pairs)?;
    let options = HeadlessOptions { width: config.width, height: config.height, settings, ..Default::default() };
    HeadlessRenderer::new(world.clone(), view, &options)
}

fn set_accumulate(r: &mut HeadlessRenderer, on: bool) {
    r.app_mut().world_mut().resource_mut::<RenderSettings>().accumulate = on;
}

/// Mean wall time of `frames` frames, in ms.
fn time_frames(r: &mut HeadlessRenderer, frames: u32) -> f64 {
    let start = Instant::now();
    for _ in 0..frames {
        r.step();
    }
    start.elapsed().as_secs_f64() * 1000.0 / frames.max(1) as f64
}

fn measure(
    scene: &str,
    (time, hours): (&'static str, f32),
    world: &VoxelWorld,
    view: &CameraView,
    config: &DaylightConfig,
) -> Result<DaylightRow, String> {
    let day = Some(Daylight::at(hours, true));
    let reference = Reference { bounces: REFERENCE_BOUNCES, daylight: day, lattice: None, indirect: false };
    let references = ReferenceCache::new(config.width, config.height, config.reference_spp);
    let truth = references.image(world, view, &reference)?;
    let noise = references.noise(world, view, &reference, &truth)?.mae;
    let mut pairs: Vec<String> = GAME_PAIRS.iter().map(|p| p.to_string()).collect();
    pairs.push(format!("time={hours}"));
    let mut r = renderer(world, view, config, &pairs)?;
    r.render(SETTLE_FRAMES)?;
    let frame_ms = time_frames(&mut r, TIMED_FRAMES);
    let single = compare(&r.render(1)?, &truth)?;
    set_accumulate(&mut r, true);
    let accumulated = compare(&r.render(AVERAGED_FRAMES)?, &truth)?;
    Ok(DaylightRow {
        scene: scene.to_string(),
        time,
        hours,
        frame_ms,
        single,
        accumulated,
        mean: truth.mean_luminance(),
        noise,
    })
}

fn measure_cost(scene: &'static str, config: &DaylightConfig) -> Result<CostRow, String> {
    let world = load_scene(scene).map_err(|e| e.to_string())?;
    let view = world.view(None).cloned().unwrap_or_else(|| world.overview());
    let lights = crate::lights::LightPool::from_world(&world).len();
    let ms = |lighting: &str| -> Result<f64, String> {
        let pairs = [format!("lighting={lighting}"), "time=12".to_string()];
        let mut r = renderer(&world, &view, config, &pairs)?;
        r.render(8)?;
        Ok(time_frames(&mut r, TIMED_FRAMES * 2))
    };
    // Interleaved twice, so a slow spell of the machine lands on both.
    let (e1, f1, e2, f2) = (ms("emitters")?, ms("full")?, ms("emitters")?, ms("full")?);
    Ok(CostRow { scene, lights, full_ms: (f1 + f2) / 2.0, emitters_ms: (e1 + e2) / 2.0 })
}

/// The scenes: the window room (sun and sky through a window, no lamps) and a generated world with lamps.
fn scenes() -> Result<Vec<(String, VoxelWorld, CameraView)>, String> {
    let room = load_scene("window-room").map_err(|e| e.to_string())?;
    let inside = room.view(Some("inside")).cloned().ok_or("window-room: no view 'inside'")?;
    let world = generated_world(3, UVec3::new(96, 48, 96)).map_err(|e| e.to_string())?;
    let start = world.view(Some("start")).cloned().ok_or("generated world: no view 'start'")?;
    Ok(vec![("window-room".into(), room, inside), ("generated (seed 3, 96x48x96)".into(), world, start)])
}

/// Runs the bench at the config's size, writes `daylight.md` into `out` and returns its text.
pub fn run_daylight_bench(config: &DaylightConfig, out: &Path) -> Result<String, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut rows = Vec::new();
    for (scene, world, view) in scenes()? {
        for time in TIMES {
            let row = measure(&scene, time, &world, &view, config)?;
            eprintln!(
                "daylight bench: {scene} {}: accumulated {} ({:.0} ms/frame)",
                time.0, row.accumulated, row.frame_ms
            );
            rows.push(row);
        }
    }
    let mut costs = Vec::new();
    for scene in ["lights-1k", "lights-100k"] {
        let row = measure_cost(scene, config)?;
        eprintln!("daylight bench: {scene}: full {:.1} ms, emitters {:.1} ms", row.full_ms, row.emitters_ms);
        costs.push(row);
    }
    let text = markdown(&rows, &costs, config);
    let path = out.join("daylight.md");
    std::fs::write(&path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(text)
}

fn markdown(rows: &[DaylightRow], costs: &[CostRow], config: &DaylightConfig) -> String {
    let mut text = format!(
        "# The game's lighting: sun, sky and lamps against the reference\n\n`glowbrick bench --daylight`: {}x{}, \
         `lighting=full gi=on` (as `play` starts), {SETTLE_FRAMES} frames for the GI cache to settle, \
         {TIMED_FRAMES} timed, then one frame and {AVERAGED_FRAMES} accumulated frames compared with a {}-spp CPU \
         reference of the same lighting with {REFERENCE_BOUNCES} diffuse bounces. Bias is the signed mean of \
         rendered minus reference luminance, also as a share of the reference's mean; the reference's own noise is \
         the MAE between it and one with another seed.\n\n\
         | scene | time | frame ms | one frame: MAE | relMSE | accumulated: MAE | relMSE | bias | bias % | \
         reference mean | reference noise (MAE) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
        config.width, config.height, config.reference_spp
    );
    for r in rows {
        text += &format!(
            "| {} | {} ({} h) | {:.1} | {:.5} | {:.4} | {:.5} | {:.5} | {:+.5} | {:+.2}% | {:.5} | {:.5} |\n",
            r.scene,
            r.time,
            r.hours,
            r.frame_ms,
            r.single.mae,
            r.single.relmse,
            r.accumulated.mae,
            r.accumulated.relmse,
            r.accumulated.bias,
            100.0 * r.accumulated.bias / r.mean.max(1e-12),
            r.mean,
            r.noise
        );
    }
    text += "\n## What the sun and the sky cost\n\nFrame time of `lighting=full` (ReSTIR over the lamps, one disk \
             sample and one sky ray per pixel; GI off) against `lighting=emitters` (ReSTIR alone), noon, the \
             scene's first view, interleaved runs averaged.\n\n| scene | lights | full ms | emitters ms | ratio |\n\
             |---|---|---|---|---|\n";
    for c in costs {
        text += &format!(
            "| {} | {} | {:.1} | {:.1} | {:.2} |\n",
            c.scene,
            c.lights,
            c.full_ms,
            c.emitters_ms,
            c.full_ms / c.emitters_ms.max(1e-9)
        );
    }
    text
}
