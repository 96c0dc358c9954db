//! Run time against error (`glowbrick bench`): every scene x setting is rendered headless with a fixed camera;
//! the bench records the frame time and the primary pass's GPU time (timestamp queries, where the adapter has
//! them) and the error of one frame against the CPU reference, cached under the target folder. It writes
//! `results.csv`, `report.md` and `plot.png` (error against frame time, one panel per scene).
//!
//! Settings: the next-event-estimation baseline (one light sample per pixel, power or uniform picking) and Voxel
//! ReSTIR with M_init in {1, 8, 16, 32}, point vs area samples, reuse off, unbiased vs biased, uniform candidates.
//! The spatial radius scales with the image (the thesis' 30 px at 1600 wide). Last per scene, `nee-equal-time`
//! accumulates NEE frames for the time one default ReSTIR frame takes: the equal-time comparison.

pub mod gi;
pub mod plot;
pub mod thesis;

use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::{LinearImage, read_image, write_image};
use crate::reference::metrics::{Metrics, compare};
use crate::reference::{ReferenceOptions, render_reference};
use crate::render::primary::PRIMARY_PASS_NAME;
use crate::render::restir::RESTIR_PASS_NAMES;
use crate::settings::RenderSettings;
use crate::world::format::world_to_string;
use crate::world::scene::load_scene;
use crate::world::{CameraView, VoxelWorld};
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
    BenchSetting { name: "restir-unbiased", pairs: &["lighting=restir", "reuse=unbiased"] },
    BenchSetting { name: "restir-uniform", pairs: &["lighting=restir", "pick=uniform"] },
];

/// The setting whose frame time sets the NEE frame budget of the equal-time row.
const EQUAL_TIME_TO: &str = "restir";

/// Scenes of a full run and of `--quick`.
pub const ALL_SCENES: &[&str] = &["cornell", "letters", "apartments", "mountain", "window-room"];
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
    /// A camera for every scene instead of each scene's first view.
    pub camera: Option<CameraView>,
    /// Only these settings (by name); empty: all.
    pub only: Vec<String>,
}

impl BenchConfig {
    pub fn full() -> Self {
        BenchConfig {
            width: 320,
            height: 180,
            warmup_frames: 16,
            timed_frames: 64,
            reference_spp: 2048,
            camera: None,
            only: Vec::new(),
        }
    }

    pub fn quick() -> Self {
        BenchConfig {
            width: 96,
            height: 64,
            warmup_frames: 4,
            timed_frames: 8,
            reference_spp: 256,
            camera: None,
            only: Vec::new(),
        }
    }
}

/// One scene x setting.
#[derive(Clone, Debug)]
pub struct BenchRow {
    pub scene: String,
    pub setting: String,
    pub frame_ms: f64,
    pub gpu_ms: Option<f64>,
    /// GPU ms of each voxel pass that ran (primary, then the ReSTIR passes).
    pub passes: PassTimes,
    pub metrics: Metrics,
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

/// The reference with `bounces` diffuse bounces (0: direct light), cached like `cached_reference`.
pub fn cached_path_reference(
    world: &VoxelWorld,
    view: &CameraView,
    config: &BenchConfig,
    bounces: u32,
) -> Result<LinearImage, String> {
    let light = if bounces == 0 { "direct".to_string() } else { format!("{bounces}bounces") };
    let key = format!(
        "{}|{:?}|{}x{}|{}spp|{light}",
        world_to_string(world),
        view,
        config.width,
        config.height,
        config.reference_spp
    );
    let path = cache_dir().join(format!("{:016x}.exr", fnv1a(key.as_bytes())));
    if let Ok(image) = read_image(&path)
        && (image.width, image.height) == (config.width, config.height)
    {
        return Ok(image);
    }
    let options = ReferenceOptions {
        width: config.width,
        height: config.height,
        spp: config.reference_spp,
        bounces,
        ..Default::default()
    };
    let reference = render_reference(world, view, &options)?;
    std::fs::create_dir_all(cache_dir()).map_err(|e| format!("{}: {e}", cache_dir().display()))?;
    write_image(&reference.image, &path)?;
    eprintln!(
        "bench: reference {} in {:.1} s ({} spp)",
        path.display(),
        reference.elapsed.as_secs_f64(),
        reference.spp
    );
    Ok(reference.image)
}

/// GPU ms per pass that ran, by pass name.
pub type PassTimes = Vec<(&'static str, f64)>;

/// Renders one scene under one setting and measures it.
fn measure(
    world: &VoxelWorld,
    view: &CameraView,
    setting: &BenchSetting,
    config: &BenchConfig,
    reference: &LinearImage,
) -> Result<(f64, PassTimes, Metrics), String> {
    let mut pairs: Vec<String> = setting.pairs.iter().map(|p| p.to_string()).collect();
    // The thesis' 30 px radius at 1600 wide, scaled to this image.
    pairs.insert(0, format!("radius={}", (30.0 * config.width as f32 / 1600.0).round().max(2.0)));
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
    let image = renderer.render(1)?;
    Ok((frame_ms, passes, compare(&image, reference)?))
}

/// GPU time of each voxel pass that ran (the primary pass, and the ReSTIR passes when they ran).
pub(crate) fn pass_times(renderer: &HeadlessRenderer) -> PassTimes {
    std::iter::once(PRIMARY_PASS_NAME)
        .chain(RESTIR_PASS_NAMES)
        .filter_map(|name| renderer.gpu_pass_ms(name).map(|ms| (name, ms)))
        .collect()
}

/// NEE accumulated over as many frames as fit in `budget_ms` of NEE frame time: (frames, frame ms, metrics).
fn measure_equal_time(
    world: &VoxelWorld,
    view: &CameraView,
    config: &BenchConfig,
    reference: &LinearImage,
    nee_frame_ms: f64,
    budget_ms: f64,
) -> Result<(u32, Metrics), String> {
    let frames = (budget_ms / nee_frame_ms.max(1e-3)).round().clamp(1.0, 4096.0) as u32;
    let pairs = ["lighting=nee", "pick=power", "accumulate=on"].map(String::from);
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width: config.width, height: config.height, settings, ..Default::default() };
    let mut renderer = HeadlessRenderer::new(world.clone(), view, &options)?;
    let image = renderer.render(frames)?;
    Ok((frames, compare(&image, reference)?))
}

/// Runs every scene x setting and writes the three outputs to `out`.
pub fn run_bench(scenes: &[String], config: &BenchConfig, out: &Path) -> Result<Vec<BenchRow>, String> {
    if let Some(unknown) = config.only.iter().find(|o| !SETTINGS.iter().any(|s| s.name == o.as_str())) {
        let names: Vec<&str> = SETTINGS.iter().map(|s| s.name).collect();
        return Err(format!("unknown bench setting '{unknown}' (valid: {})", names.join(", ")));
    }
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut rows = Vec::new();
    for name in scenes {
        let world = load_scene(name).map_err(|e| e.to_string())?;
        let view = config.camera.clone().or_else(|| world.view(None).cloned()).unwrap_or_else(|| world.overview());
        let reference = cached_reference(&world, &view, config)?;
        let first = rows.len();
        for setting in SETTINGS.iter().filter(|s| config.only.is_empty() || config.only.iter().any(|o| o == s.name)) {
            let (frame_ms, passes, metrics) = measure(&world, &view, setting, config, &reference)?;
            eprintln!("bench: {name} {}: {frame_ms:.2} ms/frame, {metrics}", setting.name);
            let gpu_ms = (!passes.is_empty()).then(|| passes.iter().map(|(_, ms)| ms).sum());
            let setting = setting.name.to_string();
            rows.push(BenchRow { scene: name.clone(), setting, frame_ms, gpu_ms, passes, metrics });
        }
        let time_of = |setting: &str| rows[first..].iter().find(|r| r.setting == setting).map(|r| r.frame_ms);
        if let (Some(nee_ms), Some(budget_ms)) = (time_of("nee-power"), time_of(EQUAL_TIME_TO)) {
            let (frames, metrics) = measure_equal_time(&world, &view, config, &reference, nee_ms, budget_ms)?;
            eprintln!("bench: {name} nee-equal-time ({frames} frames): {metrics}");
            rows.push(BenchRow {
                scene: name.clone(),
                setting: format!("nee-equal-time ({frames} frames)"),
                frame_ms: nee_ms * frames as f64,
                gpu_ms: None,
                passes: Vec::new(),
                metrics,
            });
        }
    }
    write_csv(&rows, &out.join("results.csv"))?;
    write_markdown(&rows, config, &out.join("report.md"))?;
    plot::write_plot(&rows, &out.join("plot.png"))?;
    Ok(rows)
}

fn gpu_text(ms: Option<f64>) -> String {
    ms.map_or("n/a".to_string(), |v| format!("{v:.3}"))
}

/// A row's cells, in the column order of both outputs.
fn cells(r: &BenchRow) -> [String; 8] {
    let m = r.metrics;
    [
        r.scene.clone(),
        r.setting.clone(),
        format!("{:.3}", r.frame_ms),
        gpu_text(r.gpu_ms),
        format!("{:.6}", m.mae),
        format!("{:.6}", m.mse),
        format!("{:.6}", m.relmse),
        format!("{:+.6}", m.bias),
    ]
}

fn write_csv(rows: &[BenchRow], path: &Path) -> Result<(), String> {
    let mut text = String::from("scene,setting,frame_ms,gpu_ms,mae,mse,relmse,bias\n");
    for r in rows {
        text += &(cells(r).join(",") + "\n");
    }
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_markdown(rows: &[BenchRow], config: &BenchConfig, path: &Path) -> Result<(), String> {
    let mut text = format!(
        "# Run time against error\n\n{}x{}, one frame (no accumulation; ReSTIR with the temporal history of the \
         frames before it) against a {}-spp direct-light CPU reference; frame time averaged over {} frames after {} \
         warm-up frames. `GPU ms` is the timestamp-query time of the voxel passes that ran (primary, plus the three \
         ReSTIR passes; n/a where the adapter has no timestamps). `nee-equal-time` accumulates NEE frames for the \
         frame time of `restir` (its frame ms is the total).\n\n\
         | scene | setting | frame ms | GPU ms | MAE | MSE | relMSE | bias |\n|---|---|---|---|---|---|---|---|\n",
        config.width, config.height, config.reference_spp, config.timed_frames, config.warmup_frames
    );
    for r in rows {
        text += &format!("| {} |\n", cells(r).join(" | "));
    }
    text += "\n## GPU time per pass (ms)\n\n| scene | setting | passes |\n|---|---|---|\n";
    for r in rows.iter().filter(|r| !r.passes.is_empty()) {
        let passes: Vec<String> =
            r.passes.iter().map(|(name, ms)| format!("{} {ms:.2}", name.trim_start_matches("glowbrick_"))).collect();
        text += &format!("| {} | {} | {} |\n", r.scene, r.setting, passes.join(", "));
    }
    text += "\n![error against frame time](plot.png)\n";
    std::fs::write(path, text).map_err(|e| format!("{}: {e}", path.display()))
}
