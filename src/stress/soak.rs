//! The soak (`glowbrick stress`): a headless run of the renderer. Every frame edits the world (lamps placed, broken and
//! recoloured, blocks placed), the camera jumps or teleports, and the settings cycle through the game's own frame
//! (its defaults, moving objects, the clock moving) and the extremes of ReSTIR and the GI cache; every frame's image
//! is read back and checked for non-finite pixels, and every tenth frame reads the reservoirs (`debug=reservoir`)
//! for non-finite fields, M and W ranges. Then a static phase (fixed camera, no
//! edits) measures how the mean luminance of a view drifts over time against the CPU reference of that view.

use super::memory::{MemorySample, MemoryTrack};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::LinearImage;
use crate::progress::Progress;
use crate::reference::sampling::Pcg;
use crate::reference::{ReferenceOptions, render_reference};
use crate::render::gpu_types::GpuCounter;
use crate::settings::{DebugView, RenderSettings};
use crate::world::events::EditRequest;
use crate::world::{CameraView, Edit, VoxelWorld};
use bevy::math::{IVec3, Vec3};
use bevy::render::renderer::RenderDevice;
use std::fmt;

/// How long and how big.
#[derive(Clone, Debug)]
pub struct StressConfig {
    pub scene: String,
    pub frames: u32,
    /// Frames of the static phase that measures drift.
    pub static_frames: u32,
    pub width: u32,
    pub height: u32,
    pub seed: u64,
}

impl StressConfig {
    pub fn full() -> Self {
        StressConfig { scene: "test-room".into(), frames: 5000, static_frames: 600, width: 96, height: 64, seed: 1 }
    }

    /// Long enough to soak every entry of the settings cycle once.
    pub fn quick() -> Self {
        let frames = CYCLE_FRAMES * SETTING_CYCLE.len() as u32;
        StressConfig { scene: "test-room".into(), frames, static_frames: 120, width: 64, height: 48, seed: 1 }
    }
}

/// What a run saw. Non-finite counts must be zero; drift must stay within the noise of the reference.
#[derive(Clone, Debug, Default)]
pub struct StressReport {
    pub frames: u32,
    pub edits: u32,
    pub lamps_placed: u32,
    pub lamps_recoloured: u32,
    pub broken: u32,
    pub camera_jumps: u32,
    pub settings_changes: u32,
    /// Frames rendered with the game's own settings (`Soaked::Game`).
    pub game_frames: u32,
    pub nonfinite_pixels: u64,
    pub reservoir_reads: u32,
    /// Reads taken while the world held no light (every lamp broken or buried): no ReSTIR pass ran.
    pub reads_without_lights: u32,
    pub nonfinite_reservoirs: u64,
    /// Reads with any non-finite reservoir, and the first: (frame, the settings then, pixels).
    pub bad_reservoir_reads: u32,
    pub first_bad_read: Option<(u32, String, u64)>,
    /// Counted on the GPU over the whole soak: reservoirs and GI estimates found non-finite and reset.
    pub reservoir_resets: u32,
    pub gi_resets: u32,
    pub max_m: f32,
    pub max_w: f32,
    pub min_w: f32,
    /// Static phase: mean luminance over its first and last quarter, and the CPU reference's.
    pub static_mean_start: f64,
    pub static_mean_end: f64,
    pub reference_mean: f64,
    /// Standard deviation of one static frame's mean luminance (the noise drift is judged against).
    pub frame_noise: f64,
    /// Resident and GPU bytes over the soak, a high per block of frames.
    pub memory: MemoryTrack,
}

impl StressReport {
    /// |end - start| of the static phase, relative to the reference mean.
    pub fn drift(&self) -> f64 {
        (self.static_mean_end - self.static_mean_start).abs() / self.reference_mean.max(1e-9)
    }

    /// Relative difference of the static phase's mean from the CPU reference.
    pub fn error_vs_reference(&self) -> f64 {
        let mean = 0.5 * (self.static_mean_start + self.static_mean_end);
        (mean - self.reference_mean) / self.reference_mean.max(1e-9)
    }
}

impl StressReport {
    /// Why the run failed, if it did: any non-finite value, memory that grows after warm-up, or a static view
    /// that drifts by more than 5% of the reference or sits more than 10% from it.
    pub fn failure(&self) -> Option<String> {
        if let Some(why) = self.memory.failure() {
            return Some(why);
        }
        if self.nonfinite_pixels > 0 || self.nonfinite_reservoirs > 0 || self.reservoir_resets > 0 || self.gi_resets > 0
        {
            return Some(format!(
                "{} non-finite pixels, {} non-finite reservoirs read, {} reservoirs and {} GI estimates reset on the GPU",
                self.nonfinite_pixels, self.nonfinite_reservoirs, self.reservoir_resets, self.gi_resets
            ));
        }
        if self.drift() > 0.05 {
            return Some(format!("the static view drifted by {:.1}%", 100.0 * self.drift()));
        }
        if self.error_vs_reference().abs() > 0.10 {
            return Some(format!("the static view is {:+.1}% from the reference", 100.0 * self.error_vs_reference()));
        }
        None
    }
}

impl fmt::Display for StressReport {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        writeln!(
            f,
            "frames {}: edits {} (lamps placed {}, recoloured {}, broken {}), camera jumps {}, settings changes {}",
            self.frames,
            self.edits,
            self.lamps_placed,
            self.lamps_recoloured,
            self.broken,
            self.camera_jumps,
            self.settings_changes
        )?;
        writeln!(
            f,
            "the game's frame (full lighting, GI cache, denoiser, objects, the clock moving): {} frames",
            self.game_frames
        )?;
        writeln!(f, "non-finite pixels: {}", self.nonfinite_pixels)?;
        writeln!(
            f,
            "non-finite values reset on the GPU (all frames, all passes): reservoirs {}, GI estimates {}",
            self.reservoir_resets, self.gi_resets
        )?;
        writeln!(
            f,
            "reservoirs: {} reads ({} with no light in the world), non-finite {}, max M {:.0}, W in [{:.3e}, {:.3e}]",
            self.reservoir_reads,
            self.reads_without_lights,
            self.nonfinite_reservoirs,
            self.max_m,
            self.min_w,
            self.max_w
        )?;
        if let Some((frame, settings, pixels)) = &self.first_bad_read {
            writeln!(
                f,
                "reads with a non-finite reservoir: {}; the first at frame {frame} ({pixels} pixels; settings {settings})",
                self.bad_reservoir_reads
            )?;
        }
        writeln!(f, "memory, the high of each {}-frame block:\n{}", super::memory::BLOCK_FRAMES, self.memory)?;
        write!(
            f,
            "static view: mean luminance {:.5} -> {:.5} (drift {:.2}% of the reference {:.5}; one frame's noise \
             {:.2}%), {:+.2}% from the reference",
            self.static_mean_start,
            self.static_mean_end,
            100.0 * self.drift(),
            self.reference_mean,
            100.0 * self.frame_noise / self.reference_mean.max(1e-9),
            100.0 * self.error_vs_reference()
        )
    }
}

/// One entry of the settings cycle.
#[derive(Clone, Copy, Debug)]
enum Soaked {
    /// What `play` renders: `RenderSettings::game()` (full lighting, the GI cache and the denoiser on), with the
    /// clock moving.
    Game,
    /// These pairs over `lighting=restir gi=on`.
    Restir(&'static [&'static str]),
}

impl fmt::Display for Soaked {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        match self {
            Soaked::Game => write!(f, "the game's frame"),
            Soaked::Restir(pairs) => write!(f, "[{}] over lighting=restir gi=on", pairs.join(" ")),
        }
    }
}

/// The settings the soak cycles through: the game's frame first (so even a short run soaks it), then the ReSTIR
/// defaults and the extremes of every range. The GI cache is on in all but one.
const SETTING_CYCLE: [Soaked; 11] = [
    Soaked::Game,
    Soaked::Restir(&[]),
    Soaked::Restir(&["gi=off"]),
    // The GI cache at its extremes (a new K also rebuilds its tables).
    Soaked::Restir(&["gi=on", "gi_cached_rays=4", "gi_update=1", "gi_alpha=1"]),
    Soaked::Restir(&["gi=on", "gi_cached_rays=128", "gi_update=64", "gi_alpha=0.001", "gi_filter=off"]),
    Soaked::Restir(&["candidates=1"]),
    Soaked::Restir(&["candidates=64", "taps=16", "radius=100"]),
    Soaked::Restir(&["radius=0"]),
    Soaked::Restir(&["reuse=unbiased", "taps=16"]),
    Soaked::Restir(&["sample=point", "temporal=off"]),
    Soaked::Restir(&["spatial=off", "pick=uniform"]),
];

/// Frames each entry of the cycle is soaked for.
const CYCLE_FRAMES: u32 = 30;

/// Hours the game's clock moves each frame of the game's entry: a whole day within its frames, so dawn, dusk and
/// night (the sun's and the moon's light, a sky that changes every frame) all come in a short run.
const CLOCK_STEP: f32 = 24.0 / CYCLE_FRAMES as f32 + 0.05;

fn settings(soaked: Soaked, debug: DebugView, hours: f32) -> Result<RenderSettings, String> {
    let mut s = match soaked {
        Soaked::Game => RenderSettings { time: hours, ..RenderSettings::game() },
        Soaked::Restir(pairs) => {
            let mut all = vec!["lighting=restir".to_string(), "gi=on".to_string()];
            all.extend(pairs.iter().map(|p| p.to_string()));
            RenderSettings::default().with_pairs(&all)?
        }
    };
    s.debug = debug;
    Ok(s)
}

/// A random point inside the world's air near the middle, and a random direction.
fn random_camera(world: &VoxelWorld, rng: &mut Pcg) -> CameraView {
    let size = world.grid.size().as_vec3();
    let origin = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * (size - 2.0) + 1.0;
    let direction = Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5);
    let direction = direction.try_normalize().unwrap_or(Vec3::Z);
    CameraView { name: "stress".into(), origin: origin.to_array(), direction: direction.to_array(), fov_deg: 60.0 }
}

/// Runs the soak on `config.scene` and returns what it saw.
pub fn run_stress(config: &StressConfig) -> Result<StressReport, String> {
    let mut world = crate::world::recipe::load_scene(&config.scene).map_err(|e| e.to_string())?;
    // A drifting lantern and a swinging block (the game's own objects) the whole time: every pass traces them,
    // the GI cache gives them their own table.
    let lantern = std::sync::Arc::new(crate::dynamic::model_for_world("lantern", &mut world)?);
    let block = std::sync::Arc::new(crate::dynamic::model_for_world("block", &mut world)?);
    let home = world.view(None).cloned().unwrap_or_else(|| world.overview());
    let lamps: Vec<u16> = (0..world.palette.id_count() as u16).filter(|&id| world.palette.is_emissive(id)).collect();
    let blocks: Vec<u16> = (1..world.palette.id_count() as u16).filter(|&id| !world.palette.is_emissive(id)).collect();
    let palette_ids = (lamps, blocks);
    if palette_ids.0.is_empty() {
        return Err(format!("scene {}: the soak needs an emissive material", config.scene));
    }
    let size = world.grid.size().as_ivec3();
    // The clock starts where the game's would: at the world's saved time of day, if it has one.
    let mut hours = RenderSettings::game().with_world_time(&world).time;
    let options = HeadlessOptions {
        width: config.width,
        height: config.height,
        settings: settings(SETTING_CYCLE[0], DebugView::None, hours)?,
        ..Default::default()
    };
    let mut renderer = HeadlessRenderer::new(world.clone(), &home, &options)?;
    let centre = world.grid.size().as_vec3() * 0.5;
    let drift = crate::dynamic::Motion::Drift { radius: centre.x * 0.5, period: 4.0 };
    crate::dynamic::spawn_object_in(renderer.app_mut().world_mut(), lantern, drift, centre)?;
    let swing = crate::dynamic::Motion::Swing { length: centre.y * 0.5, amplitude: 0.7, period: 5.0 };
    crate::dynamic::spawn_object_in(renderer.app_mut().world_mut(), block, swing, centre + Vec3::X * 3.0)?;
    let mut rng = Pcg::new(config.seed, 0x5747);
    let mut report = StressReport { min_w: f32::INFINITY, ..Default::default() };
    let mut placed: Vec<IVec3> = Vec::new();
    let mut camera = home.clone();

    let progress = Progress::new("stress", config.frames as u64);
    for frame in 0..config.frames {
        progress.advance(1);
        // Edits: every frame one or two, of every kind.
        for _ in 0..1 + (rng.next_u32() % 2) {
            let at = IVec3::new(
                (rng.next_u32() % size.x as u32) as i32,
                (rng.next_u32() % size.y as u32) as i32,
                (rng.next_u32() % size.z as u32) as i32,
            );
            let edit = random_edit(&mut rng, at, &palette_ids, &mut placed, &mut report);
            report.edits += 1;
            renderer.app_mut().world_mut().write_message(EditRequest::unrecorded(edit));
        }
        // Camera: teleports now and then, small jumps otherwise.
        if frame % 7 == 0 {
            camera = random_camera(&world, &mut rng);
            report.camera_jumps += 1;
        } else {
            let mut o = Vec3::from(camera.origin);
            o += Vec3::new(rng.next_f32() - 0.5, rng.next_f32() - 0.5, rng.next_f32() - 0.5) * 2.0;
            camera.origin = o.clamp(Vec3::ONE, size.as_vec3() - 1.0).to_array();
        }
        renderer.set_view(&camera);
        // Settings: the next entry every CYCLE_FRAMES frames; every tenth frame reads the reservoirs instead of the
        // image.
        let soaked = SETTING_CYCLE[(frame / CYCLE_FRAMES) as usize % SETTING_CYCLE.len()];
        if frame.is_multiple_of(CYCLE_FRAMES) {
            report.settings_changes += 1;
        }
        if matches!(soaked, Soaked::Game) {
            report.game_frames += 1;
            hours = crate::game::step_clock(hours, CLOCK_STEP);
        }
        let debug = if frame % 10 == 9 { DebugView::Reservoir } else { DebugView::None };
        *renderer.app_mut().world_mut().resource_mut::<RenderSettings>() = settings(soaked, debug, hours)?;
        let image = renderer.render(1)?;
        if debug == DebugView::Reservoir {
            let pool = renderer.app_mut().world().get_resource::<crate::lights::LightPool>();
            let no_lights = pool.is_some_and(|p| p.is_empty());
            count_reservoirs(&image, no_lights, (frame, soaked), &mut report);
        } else {
            report.nonfinite_pixels += image.non_finite_pixels() as u64;
        }
        report.frames += 1;
        let device = renderer.app_mut().world().get_resource::<RenderDevice>();
        report.memory.record(frame, MemorySample::now(device));
    }

    progress.finish();
    let counters = renderer.counters()?;
    report.reservoir_resets = counters[GpuCounter::ReservoirResets as usize];
    report.gi_resets = counters[GpuCounter::GiResets as usize];

    static_phase(&mut renderer, &home, config, hours, &mut report)?;
    if report.min_w == f32::INFINITY {
        report.min_w = 0.0;
    }
    Ok(report)
}

/// One random edit at `at`: a lamp placed, recoloured or broken, or a block placed or broken. `ids` are the
/// world's lamp materials and its other solid ones; `placed` the lamps placed so far.
fn random_edit(
    rng: &mut Pcg,
    at: IVec3,
    (lamps, blocks): &(Vec<u16>, Vec<u16>),
    placed: &mut Vec<IVec3>,
    report: &mut StressReport,
) -> Edit {
    match rng.next_u32() % 4 {
        0 => {
            report.lamps_placed += 1;
            placed.push(at);
            Edit::Place { at, material: lamps[rng.next_u32() as usize % lamps.len()] }
        }
        1 if !placed.is_empty() => {
            // Recolour a lamp placed earlier (same slot, new radiance) or another lamp material.
            report.lamps_recoloured += 1;
            let at = placed[rng.next_u32() as usize % placed.len()];
            Edit::Place { at, material: lamps[rng.next_u32() as usize % lamps.len()] }
        }
        2 if !placed.is_empty() => {
            report.broken += 1;
            let at = placed.swap_remove(rng.next_u32() as usize % placed.len());
            Edit::Break { at }
        }
        _ if !blocks.is_empty() => Edit::Place { at, material: blocks[rng.next_u32() as usize % blocks.len()] },
        _ => Edit::Break { at },
    }
}

/// Counts a reservoir read (the reservoir debug view's pixels: W, M, w_sum, a non-finite flag) of frame
/// `frame` under `soaked` into the report.
fn count_reservoirs(image: &LinearImage, no_lights: bool, (frame, soaked): (u32, Soaked), report: &mut StressReport) {
    report.reservoir_reads += 1;
    report.reads_without_lights += no_lights as u32;
    let before = report.nonfinite_reservoirs;
    for p in &image.pixels {
        let [w, m, w_sum, bad] = *p;
        report.nonfinite_reservoirs += (bad != 0.0 || !w.is_finite() || !w_sum.is_finite()) as u64;
        if m.is_finite() {
            report.max_m = report.max_m.max(m);
        }
        if w.is_finite() && w > 0.0 {
            report.max_w = report.max_w.max(w);
            report.min_w = report.min_w.min(w);
        }
    }
    let bad = report.nonfinite_reservoirs - before;
    if bad > 0 {
        report.bad_reservoir_reads += 1;
        report.first_bad_read.get_or_insert_with(|| (frame, soaked.to_string(), bad));
    }
}

/// The static phase: the home view of the world as the soak left it, no edits, unbiased reuse (so the reference
/// comparison measures drift and error, not the biased variant's known darkening); its drift, frame noise and
/// the reference's mean into the report.
fn static_phase(
    renderer: &mut HeadlessRenderer,
    home: &CameraView,
    config: &StressConfig,
    hours: f32,
    report: &mut StressReport,
) -> Result<(), String> {
    renderer.set_view(home);
    // The reference is direct light only, so the GI cache is off here.
    *renderer.app_mut().world_mut().resource_mut::<RenderSettings>() =
        settings(Soaked::Restir(&["reuse=unbiased", "gi=off"]), DebugView::None, hours)?;
    renderer.render(8)?;
    let mut means = Vec::with_capacity(config.static_frames as usize);
    for _ in 0..config.static_frames.max(8) {
        let image = renderer.render(1)?;
        report.nonfinite_pixels += image.non_finite_pixels() as u64;
        means.push(image.mean_luminance());
    }
    let quarter = (means.len() / 4).max(1);
    let average = |m: &[f64]| m.iter().sum::<f64>() / m.len().max(1) as f64;
    report.static_mean_start = average(&means[..quarter]);
    report.static_mean_end = average(&means[means.len() - quarter..]);
    let all = average(&means);
    report.frame_noise = (means.iter().map(|m| (m - all).powi(2)).sum::<f64>() / means.len() as f64).sqrt();
    let final_world = renderer.app_mut().world().resource::<VoxelWorld>().clone();
    let reference = render_reference(
        &final_world,
        home,
        &ReferenceOptions { width: config.width, height: config.height, spp: 256, ..Default::default() },
    )?;
    report.reference_mean = reference.image.mean_luminance();
    Ok(())
}
