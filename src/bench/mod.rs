//! Run time against error (`glowbrick bench`): every scene x setting is rendered headless with a fixed camera;
//! the bench records the frame time and the primary pass's GPU time (timestamp queries, where the adapter has
//! them) and the error (MAE, MSE, relMSE, bias, FLIP) of one frame against the CPU reference, cached under the
//! target folder, and the reference's own noise (a second reference with another seed). Then the convergence
//! curves (`convergence.rs`): error against cumulative time as frames accumulate, per method. It writes
//! `results.csv`, `report.md`, `plot.svg` (the curves, log-log, one panel per scene) and per scene an image strip
//! `strip-SCENE.png` (reference | NEE | ReSTIR | ReSTIR's FLIP map, one frame each).
//!
//! Settings: the next-event-estimation baseline (one light sample per pixel, power or uniform picking) and Voxel
//! ReSTIR with M_init in {1, 8, 16, 32}, point vs area samples, reuse off, unbiased vs biased, uniform candidates.
//! The spatial radius scales with the image (the thesis' 30 px at 1600 wide). Last per scene, `nee-equal-time`
//! accumulates NEE frames for the time one default ReSTIR frame takes: the equal-time comparison.

pub mod convergence;
pub mod daylight;
pub mod denoise;
pub mod gi;
pub mod gi_scale;
pub mod motion;
pub mod plot;
pub mod same_hit;
pub mod thesis;

use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::{LinearImage, read_image, write_image};
use crate::lights::daylight::Daylight;
use crate::progress::Progress;
use crate::reference::flip::{Encoding, flip};
use crate::reference::metrics::{Metrics, compare};
use crate::reference::{ReferenceOptions, render_reference};
use crate::render::primary::PRIMARY_PASS_NAME;
use crate::render::restir::RESTIR_PASS_NAMES;
use crate::settings::RenderSettings;
use crate::world::format::world_to_string;
use crate::world::scene::load_scene;
use crate::world::{CameraView, VoxelWorld};
use convergence::{CurvePoint, CurveSpec, METHODS, equal_time_table, measure_curve};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A named group of `--set` pairs.
#[derive(Clone, Debug)]
pub struct BenchSetting {
    pub name: &'static str,
    pub pairs: &'static [&'static str],
}

/// The settings benchmarked today.
pub const SETTINGS: &[BenchSetting] = &[
    BenchSetting { name: "nee-power", pairs: &["lighting=nee", "pick=power"] },
    BenchSetting { name: "nee-uniform", pairs: &["lighting=nee", "pick=uniform"] },
    BenchSetting { name: "restir", pairs: &["lighting=restir"] },
    BenchSetting { name: "restir-m1", pairs: &["lighting=restir", "candidates=1"] },
    BenchSetting { name: "restir-m8", pairs: &["lighting=restir", "candidates=8"] },
    BenchSetting { name: "restir-m16", pairs: &["lighting=restir", "candidates=16"] },
    BenchSetting { name: "restir-point", pairs: &["lighting=restir", "sample=point"] },
    BenchSetting { name: "restir-no-reuse", pairs: &["lighting=restir", "temporal=off", "spatial=off"] },
    BenchSetting { name: "restir-temporal-only", pairs: &["lighting=restir", "spatial=off"] },
    BenchSetting { name: "restir-biased", pairs: &["lighting=restir", "reuse=biased"] },
    BenchSetting { name: "restir-unbiased", pairs: &["lighting=restir", "reuse=unbiased"] },
    BenchSetting { name: "restir-uniform", pairs: &["lighting=restir", "pick=uniform"] },
    BenchSetting { name: "restir-no-local", pairs: &["lighting=restir", "local_lights=off"] },
];

/// The setting whose frame time sets the NEE frame budget of the equal-time row.
pub(crate) const EQUAL_TIME_TO: &str = "restir";

/// Scenes of a full run and of `--quick`. `thesis-NAME` is the thesis' own `NAME.vx` at its first camera view
/// (`load_bench_scene`): scenes nobody here built or tuned on.
pub const ALL_SCENES: &[&str] = &[
    "cornell",
    "letters",
    "apartments",
    "mountain",
    "window-room",
    "lights-100k",
    "lamp-checkerboard",
    "thesis-letters",
    "thesis-cornellbox",
];
pub const QUICK_SCENES: &[&str] = &["cornell", "letters"];

/// How big and how long.
#[derive(Clone, Debug)]
pub struct BenchConfig {
    pub width: u32,
    pub height: u32,
    /// Frames rendered before timing (pipelines, caches).
    pub warmup_frames: u32,
    /// Frames timed.
    pub timed_frames: u32,
    pub reference_spp: u32,
    /// Frames of the longest convergence point (curves read 1, 2, 4, ... up to it).
    pub curve_frames: u32,
    /// A camera for every scene instead of each scene's first view.
    pub camera: Option<CameraView>,
    /// Only these settings (by name); empty: all.
    pub only: Vec<String>,
    /// `--gi --game-sizes` and `--denoise --cost`: the sizes of their tables (empty: each one's default).
    pub game_sizes: Vec<(u32, u32)>,
    /// `--denoise --seeds N`: independent realisations (the `seed` setting 0..N) each measure averages.
    pub seeds: u32,
    /// `--denoise --set KEY=VALUE`: settings on top of each measure's own (e.g. `gi_qmc=off` to compare).
    pub settings: Vec<String>,
    /// `--denoise --lattice N`: the one-frame measure's reference and errors at every n-th pixel in each
    /// direction only (`Reference::lattice`; 1: every pixel), so a game's size stays affordable.
    pub lattice: u32,
    /// `--denoise --scenes A,B`: only these of its one-frame scenes (empty: all four).
    pub scenes: Vec<String>,
}

/// A reference lattice (`Reference::lattice`) must be at least 1 and leave at least 4 pixels each way.
pub fn check_lattice(lattice: u32, width: u32, height: u32) -> Result<(), String> {
    let most = width.min(height) / 4;
    if lattice == 0 || lattice > most {
        return Err(format!("--lattice {lattice} must be within 1..={most}"));
    }
    Ok(())
}

impl BenchConfig {
    pub fn full() -> Self {
        BenchConfig {
            width: 320,
            height: 180,
            warmup_frames: 16,
            timed_frames: 64,
            reference_spp: 2048,
            curve_frames: 64,
            camera: None,
            only: Vec::new(),
            game_sizes: Vec::new(),
            seeds: 1,
            settings: Vec::new(),
            lattice: 1,
            scenes: Vec::new(),
        }
    }

    pub fn quick() -> Self {
        BenchConfig {
            width: 96,
            height: 64,
            warmup_frames: 4,
            timed_frames: 8,
            reference_spp: 256,
            curve_frames: 16,
            camera: None,
            only: Vec::new(),
            game_sizes: Vec::new(),
            seeds: 1,
            settings: Vec::new(),
            lattice: 1,
            scenes: Vec::new(),
        }
    }
}

/// One scene x setting.
#[derive(Clone, Debug)]
pub struct BenchRow {
    pub scene: String,
    pub setting: String,
    /// Frames in the image (1, or the accumulated frames of a curve point or the equal-time row).
    pub frames: u32,
    pub frame_ms: f64,
    pub gpu_ms: Option<f64>,
    /// GPU ms of each voxel pass that ran (primary, then the ReSTIR passes).
    pub passes: PassTimes,
    pub metrics: Metrics,
    /// Mean LDR-FLIP against the reference.
    pub flip: f64,
}

/// Where references are cached: `$GLOWBRICK_CACHE`, else `$CARGO_TARGET_DIR/glowbrick-reference`, else
/// `target/glowbrick-reference` in the crate.
pub fn cache_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os("GLOWBRICK_CACHE") {
        return PathBuf::from(dir);
    }
    let target = std::env::var_os("CARGO_TARGET_DIR")
        .map(PathBuf::from)
        .unwrap_or_else(|| Path::new(env!("CARGO_MANIFEST_DIR")).join("target"));
    target.join("glowbrick-reference")
}

/// FNV-1a, stable across runs and platforms (the cache key must not change between builds).
fn fnv1a(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325u64, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

/// The direct-light reference of a scene view, computed once and cached by world, view, size and spp.
pub fn cached_reference(world: &VoxelWorld, view: &CameraView, config: &BenchConfig) -> Result<LinearImage, String> {
    cached_path_reference(world, view, config, 0)
}

/// The reference's own noise: a reference with another seed (also cached) measured against the cached one, the
/// way a rendered frame is (its MAE is the noise the bench states; its fireflies are the count a frame's are held
/// to).
pub fn reference_noise(
    world: &VoxelWorld,
    view: &CameraView,
    config: &BenchConfig,
    reference: &LinearImage,
) -> Result<Metrics, String> {
    reference_noise_of(world, view, config, &Reference::default(), reference)
}

/// A bench scene by name: a bundled recipe (`assets/scenes/NAME.ron`) or `thesis-NAME`, the thesis' `NAME.vx`
/// from `../shared/scenes/thesis` (or the tests' copy).
pub fn load_bench_scene(name: &str) -> Result<VoxelWorld, String> {
    match name.strip_prefix("thesis-") {
        Some(stem) => {
            let path = thesis::thesis_scene(&format!("{stem}.vx"))?;
            crate::world::source::load_path(&path).map_err(|e| e.to_string())
        }
        None => load_scene(name).map_err(|e| e.to_string()),
    }
}

/// The noise of the reference `what` (already rendered as `image`): MAE against one with another seed.
pub fn reference_noise_of(
    world: &VoxelWorld,
    view: &CameraView,
    config: &BenchConfig,
    what: &Reference,
    image: &LinearImage,
) -> Result<Metrics, String> {
    let other = cached_seeded_reference(world, view, config, what, 2)?;
    compare(&other, image)
}

/// A reference of twice the samples, the mean of the two seeds' (each cached), and its own noise: MAE and relMSE
/// between the two halved and quartered (the mean's error has half the standard deviation of each).
pub fn two_seed_reference(
    world: &VoxelWorld,
    view: &CameraView,
    config: &BenchConfig,
    what: &Reference,
) -> Result<(LinearImage, Metrics), String> {
    let first = cached_reference_of(world, view, config, what)?;
    let second = cached_seeded_reference(world, view, config, what, 2)?;
    let between = compare(&first, &second)?;
    let noise = Metrics { mae: between.mae / 2.0, mse: between.mse / 4.0, relmse: between.relmse / 4.0, ..between };
    Ok((LinearImage::mean_of(&[first, second]), noise))
}

/// The reference with `bounces` diffuse bounces (0: direct light), cached like `cached_reference`.
pub fn cached_path_reference(
    world: &VoxelWorld,
    view: &CameraView,
    config: &BenchConfig,
    bounces: u32,
) -> Result<LinearImage, String> {
    cached_reference_of(world, view, config, &Reference { bounces, ..Reference::default() })
}

/// Which light a reference integrates: emitters only (the default) or with a sun or moon and sky, and how many
/// diffuse bounces.
#[derive(Clone, Debug, Default)]
pub struct Reference {
    pub bounces: u32,
    pub daylight: Option<Daylight>,
    /// Only every n-th pixel of the bench's image in each direction (`ReferenceOptions::lattice`), or all.
    pub lattice: Option<u32>,
}

/// The reference `what`, computed once and cached by world, view, size, spp and lighting.
pub fn cached_reference_of(
    world: &VoxelWorld,
    view: &CameraView,
    config: &BenchConfig,
    what: &Reference,
) -> Result<LinearImage, String> {
    cached_seeded_reference(world, view, config, what, 1)
}

pub fn cached_seeded_reference(
    world: &VoxelWorld,
    view: &CameraView,
    config: &BenchConfig,
    what: &Reference,
    seed: u64,
) -> Result<LinearImage, String> {
    let bounces = what.bounces;
    let mut light = if bounces == 0 { "direct".to_string() } else { format!("{bounces}bounces") };
    if let Some(day) = &what.daylight {
        light += &format!("|{day:?}");
    }
    let defaults = ReferenceOptions::default();
    let step = what.lattice.unwrap_or(1);
    if let Some(step) = what.lattice {
        light += &format!("|lattice{step}");
    }
    // The estimator's version is part of the key: a cached image from another estimator is not reused.
    let key = format!(
        "{}|{:?}|{}x{}|{}spp|{light}|seed{seed}|ris{}|v{}",
        world_to_string(world),
        view,
        config.width,
        config.height,
        config.reference_spp,
        defaults.candidates,
        crate::reference::ESTIMATOR_VERSION
    );
    let path = cache_dir().join(format!("{:016x}.exr", fnv1a(key.as_bytes())));
    if let Ok(image) = read_image(&path)
        && (image.width, image.height) == (config.width / step, config.height / step)
    {
        return Ok(image);
    }
    let options = ReferenceOptions {
        width: config.width,
        height: config.height,
        spp: config.reference_spp,
        bounces,
        seed,
        daylight: what.daylight,
        lattice: step,
        ..defaults
    };
    let reference = render_reference(world, view, &options)?;
    std::fs::create_dir_all(cache_dir()).map_err(|e| format!("{}: {e}", cache_dir().display()))?;
    write_image(&reference.image, &path)?;
    eprintln!(
        "bench: reference {} in {:.1} s ({} spp, {:.2} Mrays/s)",
        path.display(),
        reference.elapsed.as_secs_f64(),
        reference.spp,
        reference.rays_per_second() / 1e6
    );
    Ok(reference.image)
}

/// The thesis' 30 px spatial radius at 1600 wide, scaled to the bench's image.
fn radius_pair(config: &BenchConfig) -> String {
    format!("radius={}", (30.0 * config.width as f32 / 1600.0).round().max(2.0))
}

/// GPU ms per pass that ran, by pass name.
pub type PassTimes = Vec<(&'static str, f64)>;

/// Renders one scene under one setting and measures it: the frame time, the passes' GPU times and the `frames`
/// single frames that follow the timed ones (at least one; the first is the setting's row).
fn measure(
    world: &VoxelWorld,
    view: &CameraView,
    setting: &BenchSetting,
    config: &BenchConfig,
    frames: u32,
) -> Result<(f64, PassTimes, Vec<LinearImage>), String> {
    let mut pairs: Vec<String> = setting.pairs.iter().map(|p| p.to_string()).collect();
    pairs.insert(0, radius_pair(config));
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width: config.width, height: config.height, settings, ..Default::default() };
    let mut renderer = HeadlessRenderer::new(world.clone(), view, &options)?;
    renderer.render(config.warmup_frames.max(1))?;
    let start = Instant::now();
    for _ in 0..config.timed_frames {
        renderer.step();
    }
    let frame_ms = start.elapsed().as_secs_f64() * 1000.0 / config.timed_frames.max(1) as f64;
    let passes = pass_times(&renderer);
    Ok((frame_ms, passes, renderer.render_sequence(frames.max(1), |_, _| {})?))
}

/// GPU time of each voxel pass that ran (the primary pass, and the ReSTIR passes when they ran).
pub(crate) fn pass_times(renderer: &HeadlessRenderer) -> PassTimes {
    std::iter::once(PRIMARY_PASS_NAME)
        .chain(RESTIR_PASS_NAMES)
        .filter_map(|name| renderer.gpu_pass_ms(name).map(|ms| (name, ms)))
        .collect()
}

/// GPU time of the direct-light frame (the passes `pass_times` reads), or None without timestamps.
pub(crate) fn direct_light_ms(renderer: &HeadlessRenderer) -> Option<f64> {
    let times = pass_times(renderer);
    (!times.is_empty()).then(|| times.iter().map(|(_, ms)| ms).sum())
}

/// Independent draws the equal-time comparison averages. One accumulation's relMSE is heavy-tailed: NEE's on
/// `letters` read 0.83, 0.22, 0.10, 0.19, 0.20 at 3, 6, 10, 18, 34 frames of one run (a rare firefly moves it 5x),
/// so one draw made the ReSTIR / NEE ratio read 4x in one run and 14x in another. The mean of several draws
/// estimates the expected error a player gets.
pub(crate) const EQUAL_TIME_TRIALS: u32 = 8;

/// The mean of several measurements; fireflies are the most any one had.
pub(crate) fn mean_metrics(all: &[Metrics]) -> Metrics {
    let n = all.len().max(1) as f64;
    let mean = |f: fn(&Metrics) -> f64| all.iter().map(f).sum::<f64>() / n;
    Metrics {
        mae: mean(|m| m.mae),
        mse: mean(|m| m.mse),
        relmse: mean(|m| m.relmse),
        bias: mean(|m| m.bias),
        fireflies: all.iter().map(|m| m.fireflies).max().unwrap_or(0),
    }
}

/// The mean error of `images` against `reference`, over all pixels and over the pixels of `keep`.
fn expected_errors(
    images: &[LinearImage],
    reference: &LinearImage,
    keep: &[bool],
) -> Result<(Metrics, Metrics), String> {
    let kept_reference = same_hit::kept(reference, keep);
    let mut all = Vec::new();
    let mut kept = Vec::new();
    for image in images {
        all.push(compare(image, reference)?);
        kept.push(compare(&same_hit::kept(image, keep), &kept_reference)?);
    }
    Ok((mean_metrics(&all), mean_metrics(&kept)))
}

/// NEE at the time one ReSTIR frame takes: as many NEE frames as fit in `budget_ms` of NEE frame time, averaged;
/// `EQUAL_TIME_TRIALS` such averages of successive frames (independent: every frame draws its own numbers).
struct EqualTime {
    frames: u32,
    /// The first average (the row of the table) and its FLIP.
    first: Metrics,
    flip: f64,
    /// The mean error over the trials, over all pixels and over the pixels of `keep`.
    expected: Metrics,
    expected_kept: Metrics,
}

fn measure_equal_time(
    world: &VoxelWorld,
    view: &CameraView,
    config: &BenchConfig,
    reference: &LinearImage,
    nee_frame_ms: f64,
    budget_ms: f64,
    keep: &[bool],
) -> Result<EqualTime, String> {
    let frames = (budget_ms / nee_frame_ms.max(1e-3)).round().clamp(1.0, 512.0) as u32;
    let pairs = ["lighting=nee", "pick=power"].map(String::from);
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width: config.width, height: config.height, settings, ..Default::default() };
    let mut renderer = HeadlessRenderer::new(world.clone(), view, &options)?;
    // Warm up as the timed settings do: a sequence read from a new renderer's first frame caught a frame with
    // no light yet (the first 6-frame average on apartments read -17% of the mean).
    renderer.render(config.warmup_frames.max(1))?;
    let images = renderer.render_sequence(frames * EQUAL_TIME_TRIALS, |_, _| {})?;
    let averages: Vec<LinearImage> = images.chunks(frames as usize).map(LinearImage::mean_of).collect();
    let first = compare(&averages[0], reference)?;
    let flip = flip(&averages[0], Encoding::Linear, reference, Encoding::Linear)?.mean;
    let (expected, expected_kept) = expected_errors(&averages, reference, keep)?;
    Ok(EqualTime { frames, first, flip, expected, expected_kept })
}

/// One scene's equal-time comparison for the report: ReSTIR's expected one-frame error (the mean over
/// `EQUAL_TIME_TRIALS` successive frames) against NEE's expected error at the same time.
struct EqualTimeRow {
    scene: String,
    nee_frames: u32,
    nee: Metrics,
    restir: Metrics,
    /// The same over the pixels whose camera ray hits the same voxel face on the GPU and the CPU
    /// (`same_hit`), and how many pixels that leaves out.
    nee_kept: Metrics,
    restir_kept: Metrics,
    left_out: usize,
}

/// Runs every scene x setting and writes the three outputs to `out`.
pub fn run_bench(scenes: &[String], config: &BenchConfig, out: &Path) -> Result<Vec<BenchRow>, String> {
    if let Some(unknown) = config.only.iter().find(|o| !SETTINGS.iter().any(|s| s.name == o.as_str())) {
        let names: Vec<&str> = SETTINGS.iter().map(|s| s.name).collect();
        return Err(format!("unknown bench setting '{unknown}' (valid: {})", names.join(", ")));
    }
    // Every scene is checked before anything is written (a typo in the last name must not cost a long run).
    for name in scenes {
        load_bench_scene(name)?;
    }
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut rows = Vec::new();
    let mut curves: Vec<CurvePoint> = Vec::new();
    let mut noise: Vec<(String, Metrics)> = Vec::new();
    let mut equal_time: Vec<EqualTimeRow> = Vec::new();
    let chosen = SETTINGS.iter().filter(|s| config.only.is_empty() || config.only.iter().any(|o| o == s.name)).count();
    let progress = Progress::new("bench", (scenes.len() * chosen) as u64);
    for name in scenes {
        let world = load_bench_scene(name)?;
        let view = config.camera.clone().or_else(|| world.view(None).cloned()).unwrap_or_else(|| world.overview());
        let reference = cached_reference(&world, &view, config)?;
        noise.push((name.clone(), reference_noise(&world, &view, config, &reference)?));
        let first = rows.len();
        let mut strip = vec![reference.clone()];
        let mut restir_expected = None;
        let keep = same_hit::same_hit_pixels(&world, &view, config.width, config.height)?;
        for setting in SETTINGS.iter().filter(|s| config.only.is_empty() || config.only.iter().any(|o| o == s.name)) {
            // The setting NEE is held to at equal time: its expected one-frame error over several frames.
            let frames = if setting.name == EQUAL_TIME_TO { EQUAL_TIME_TRIALS } else { 1 };
            let (frame_ms, passes, images) = measure(&world, &view, setting, config, frames)?;
            if setting.name == EQUAL_TIME_TO {
                restir_expected = Some(expected_errors(&images, &reference, &keep)?);
            }
            let image = images.into_iter().next().ok_or("no frame rendered")?;
            let metrics = compare(&image, &reference)?;
            let flip = flip(&image, Encoding::Linear, &reference, Encoding::Linear)?;
            progress.println(&format!(
                "bench: {name} {}: {frame_ms:.2} ms/frame, {metrics} flip={:.4}",
                setting.name, flip.mean
            ));
            progress.advance(1);
            if setting.name == "nee-power" {
                strip.push(image);
            } else if setting.name == EQUAL_TIME_TO {
                strip.extend([image, flip.map]);
            }
            let gpu_ms = (!passes.is_empty()).then(|| passes.iter().map(|(_, ms)| ms).sum());
            let setting = setting.name.to_string();
            let flip = flip.mean;
            rows.push(BenchRow { scene: name.clone(), setting, frames: 1, frame_ms, gpu_ms, passes, metrics, flip });
        }
        if strip.len() == 4 {
            plot::write_strip(&strip, &out.join(format!("strip-{name}.png")))?;
        }
        let times: Vec<(String, f64)> = rows[first..].iter().map(|r| (r.setting.clone(), r.frame_ms)).collect();
        let time_of = |setting: &str| times.iter().find(|(s, _)| s == setting).map(|&(_, ms)| ms);
        if let (Some(nee_ms), Some(budget_ms)) = (time_of("nee-power"), time_of(EQUAL_TIME_TO)) {
            let nee = measure_equal_time(&world, &view, config, &reference, nee_ms, budget_ms, &keep)?;
            let frames = nee.frames;
            progress.println(&format!(
                "bench: {name} nee-equal-time ({frames} frames): {}; mean of {EQUAL_TIME_TRIALS}: {}",
                nee.first, nee.expected
            ));
            rows.push(BenchRow {
                scene: name.clone(),
                setting: format!("nee-equal-time ({frames} frames)"),
                frames,
                frame_ms: nee_ms * frames as f64,
                gpu_ms: None,
                passes: Vec::new(),
                metrics: nee.first,
                flip: nee.flip,
            });
            if let Some((restir, restir_kept)) = restir_expected {
                progress.println(&format!(
                    "bench: {name} equal time over the {} pixels hit alike: NEE {}, ReSTIR {}",
                    keep.iter().filter(|k| **k).count(),
                    nee.expected_kept,
                    restir_kept
                ));
                equal_time.push(EqualTimeRow {
                    scene: name.clone(),
                    nee_frames: frames,
                    nee: nee.expected,
                    restir,
                    nee_kept: nee.expected_kept,
                    restir_kept,
                    left_out: keep.iter().filter(|k| !**k).count(),
                });
            }
        }
        for method in METHODS {
            let Some(frame_ms) = time_of(method.setting) else { continue };
            let pairs: Vec<String> =
                std::iter::once(radius_pair(config)).chain(method.pairs.iter().map(|p| p.to_string())).collect();
            let spec = CurveSpec { name: method.name, pairs: &pairs, frame_ms };
            let points = measure_curve(&world, &view, &spec, config, &reference, name)?;
            progress.println(&format!(
                "bench: {name} {} accumulated: relMSE {}",
                method.name,
                points.iter().map(|p| format!("{:.2e}@{}", p.metrics.relmse, p.frames)).collect::<Vec<_>>().join(" ")
            ));
            curves.extend(points);
        }
    }
    progress.finish();
    for p in &curves {
        rows.push(BenchRow {
            scene: p.scene.clone(),
            setting: format!("{} accumulated", p.method),
            frames: p.frames,
            frame_ms: p.ms,
            gpu_ms: None,
            passes: Vec::new(),
            metrics: p.metrics,
            flip: p.flip,
        });
    }
    write_csv(&rows, &out.join("results.csv"))?;
    write_markdown(&rows, &curves, &noise, &equal_time, config, &out.join("report.md"))?;
    plot::write_plot(&rows, &curves, &out.join("plot.svg"))?;
    Ok(rows)
}

/// The expected equal-time comparison: the ratio of the mean errors, each over `EQUAL_TIME_TRIALS` draws.
fn equal_time_markdown(rows: &[EqualTimeRow]) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let mut text = format!(
        "\n## Equal time, expected\n\nReSTIR's one-frame error averaged over {EQUAL_TIME_TRIALS} successive frames \
         (`{EQUAL_TIME_TO}`, after the timed ones) against NEE averaged over the frames that fit in one ReSTIR \
         frame's time, itself averaged over {EQUAL_TIME_TRIALS} such accumulations of successive frames. One draw \
         of either is heavy-tailed (a rare firefly moves NEE's relMSE several times over); the table above has one \
         draw each. The last columns measure the same over the pixels whose camera ray hits the same voxel face \
         on the GPU and the CPU (`src/bench/same_hit.rs`: a lamp one voxel thick seen edge-on is a lamp in one \
         image and a wall in the other).\n\n| scene | NEE frames | relMSE NEE | relMSE ReSTIR | ratio | MAE NEE | \
         MAE ReSTIR | ratio | bias ReSTIR | most fireflies in one ReSTIR frame | pixels hit differently | relMSE \
         NEE, same hits | relMSE ReSTIR, same hits | ratio |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n"
    );
    for r in rows {
        text += &format!(
            "| {} | {} | {:.5} | {:.5} | {:.1}x | {:.5} | {:.5} | {:.1}x | {:+.6} | {} | {} | {:.5} | {:.5} | {:.1}x |\n",
            r.scene,
            r.nee_frames,
            r.nee.relmse,
            r.restir.relmse,
            r.nee.relmse / r.restir.relmse.max(1e-12),
            r.nee.mae,
            r.restir.mae,
            r.nee.mae / r.restir.mae.max(1e-12),
            r.restir.bias,
            r.restir.fireflies,
            r.left_out,
            r.nee_kept.relmse,
            r.restir_kept.relmse,
            r.nee_kept.relmse / r.restir_kept.relmse.max(1e-12),
        );
    }
    text
}

fn gpu_text(ms: Option<f64>) -> String {
    ms.map_or("n/a".to_string(), |v| format!("{v:.3}"))
}

/// A row's cells, in the column order of both outputs.
fn cells(r: &BenchRow) -> [String; 11] {
    let m = r.metrics;
    [
        r.scene.clone(),
        r.setting.clone(),
        r.frames.to_string(),
        format!("{:.3}", r.frame_ms),
        gpu_text(r.gpu_ms),
        format!("{:.6}", m.mae),
        format!("{:.6}", m.mse),
        format!("{:.6}", m.relmse),
        format!("{:+.6}", m.bias),
        format!("{:.4}", r.flip),
        m.fireflies.to_string(),
    ]
}

fn write_csv(rows: &[BenchRow], path: &Path) -> Result<(), String> {
    let mut text = String::from("scene,setting,frames,frame_ms,gpu_ms,mae,mse,relmse,bias,flip,fireflies\n");
    for r in rows {
        text += &(cells(r).join(",") + "\n");
    }
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_markdown(
    rows: &[BenchRow],
    curves: &[CurvePoint],
    noise: &[(String, Metrics)],
    equal_time: &[EqualTimeRow],
    config: &BenchConfig,
    path: &Path,
) -> Result<(), String> {
    let noise_text: Vec<String> =
        noise.iter().map(|(scene, m)| format!("{scene} {:.5} ({} fireflies)", m.mae, m.fireflies)).collect();
    let mut text = format!(
        "# Run time against error\n\n{}x{}, one frame (no accumulation; ReSTIR with the temporal history of the \
         frames before it) against a {}-spp direct-light CPU reference; frame time averaged over {} frames after {} \
         warm-up frames. `GPU ms` is the timestamp-query time of the voxel passes that ran (primary, plus the three \
         ReSTIR passes; n/a where the adapter has no timestamps). `nee-equal-time` accumulates NEE frames for the \
         frame time of `restir` (its frame ms is the total). FLIP is the mean LDR-FLIP (0: identical). Fireflies: \
         pixels above 100x the reference's luminance plus 1 (after the warm-up and timed frames of a still camera).\n\n\
         The reference's own noise (MAE between two references with different seeds, and the fireflies of the \
         second against the first by the same rule): {}.\n\n\
         | scene | setting | frames | frame ms | GPU ms | MAE | MSE | relMSE | bias | FLIP | fireflies |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
        config.width,
        config.height,
        config.reference_spp,
        config.timed_frames,
        config.warmup_frames,
        noise_text.join(", ")
    );
    for r in rows.iter().filter(|r| !r.setting.ends_with(" accumulated")) {
        text += &format!("| {} |\n", cells(r).join(" | "));
    }
    text += &equal_time_markdown(equal_time);
    text += &format!(
        "\n## Convergence\n\nA static camera accumulating frames (`accumulate=on`): the error read at about 1, 2, 4, \
         ... {} frames (the readback lands a frame or two after the goal; `frames` is the real count), at frames x \
         the method's frame time from the table above. ![convergence](plot.svg)\n\n\
         Equal time, read off the curves: each method's relMSE at the time NEE took for its last point, and the time \
         it needs to reach NEE's last relMSE (log-log interpolation; \"beyond the curve\" where it does not get \
         there within its points). A biased method levels off at its bias.\n\n{}\n\
         | scene | method | frames | ms | MAE | relMSE | bias | FLIP |\n|---|---|---|---|---|---|---|---|\n",
        config.curve_frames,
        equal_time_table(curves)
    );
    for p in curves {
        text += &format!(
            "| {} | {} | {} | {:.1} | {:.6} | {:.6} | {:+.6} | {:.4} |\n",
            p.scene, p.method, p.frames, p.ms, p.metrics.mae, p.metrics.relmse, p.metrics.bias, p.flip
        );
    }
    text += "\n## Image strips\n\nOne frame each: reference | NEE | ReSTIR | ReSTIR's FLIP map (magma: black is no \
             visible difference, yellow the most).\n\n";
    for (scene, _) in noise {
        text += &format!("![{scene}](strip-{scene}.png)\n\n");
    }
    text += "\n## GPU time per pass (ms)\n\n| scene | setting | passes |\n|---|---|---|\n";
    for r in rows.iter().filter(|r| !r.passes.is_empty()) {
        let passes: Vec<String> =
            r.passes.iter().map(|(name, ms)| format!("{} {ms:.2}", name.trim_start_matches("glowbrick_"))).collect();
        text += &format!("| {} | {} | {} |\n", r.scene, r.setting, passes.join(", "));
    }
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}
