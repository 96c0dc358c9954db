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
//! accumulates NEE frames for the time one default ReSTIR frame takes: the equal-time comparison (`equal_time.rs`).

use super::convergence::{CurvePoint, CurveSpec, METHODS, equal_time_table, measure_curve};
use super::equal_time::{EQUAL_TIME_TRIALS, EqualTimeRow, equal_time_markdown, expected_errors, measure_equal_time};
use super::reference_cache::{Reference, ReferenceCache};
use super::{PassTimes, load_bench_scene, pass_times, plot, same_hit};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::LinearImage;
use crate::progress::Progress;
use crate::reference::flip::{Encoding, flip};
use crate::reference::metrics::{Metrics, compare};
use crate::settings::RenderSettings;
use crate::world::{CameraView, VoxelWorld};
use std::path::Path;
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
pub const EQUAL_TIME_TO: &str = "restir";

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

/// How big and how long the sweep runs.
#[derive(Clone, Debug)]
pub struct SweepConfig {
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
}

impl SweepConfig {
    pub fn full() -> Self {
        SweepConfig {
            width: 320,
            height: 180,
            warmup_frames: 16,
            timed_frames: 64,
            reference_spp: 2048,
            curve_frames: 64,
            camera: None,
            only: Vec::new(),
        }
    }

    /// A small, fast run for CI.
    pub fn quick() -> Self {
        SweepConfig {
            width: 96,
            height: 64,
            warmup_frames: 4,
            timed_frames: 8,
            reference_spp: 256,
            curve_frames: 16,
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

/// The thesis' 30 px spatial radius at 1600 wide, scaled to the bench's image.
fn radius_pair(config: &SweepConfig) -> String {
    format!("radius={}", (30.0 * config.width as f32 / 1600.0).round().max(2.0))
}

/// Renders one scene under one setting and measures it: the frame time, the passes' GPU times and the `frames`
/// single frames that follow the timed ones (at least one; the first is the setting's row).
fn measure(
    world: &VoxelWorld,
    view: &CameraView,
    setting: &BenchSetting,
    config: &SweepConfig,
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

/// Everything a sweep measured, over all scenes.
#[derive(Default)]
struct SweepResults {
    rows: Vec<BenchRow>,
    curves: Vec<CurvePoint>,
    noise: Vec<(String, Metrics)>,
    equal_time: Vec<EqualTimeRow>,
}

/// One scene of the sweep: its world, view, reference and the pixels the GPU's and the CPU's camera rays hit
/// alike.
struct SweepScene<'a> {
    name: &'a str,
    world: VoxelWorld,
    view: CameraView,
    reference: LinearImage,
    keep: Vec<bool>,
    config: &'a SweepConfig,
    progress: &'a Progress,
}

/// The settings `config.only` keeps (all when empty).
fn chosen_settings(config: &SweepConfig) -> impl Iterator<Item = &'static BenchSetting> + '_ {
    SETTINGS.iter().filter(|s| config.only.is_empty() || config.only.iter().any(|o| o == s.name))
}

/// Runs every scene x setting and writes the three outputs to `out`.
pub fn run_bench(scenes: &[String], config: &SweepConfig, out: &Path) -> Result<Vec<BenchRow>, String> {
    if let Some(unknown) = config.only.iter().find(|o| !SETTINGS.iter().any(|s| s.name == o.as_str())) {
        let names: Vec<&str> = SETTINGS.iter().map(|s| s.name).collect();
        return Err(format!("unknown bench setting '{unknown}' (valid: {})", names.join(", ")));
    }
    // Every scene is checked before anything is written (a typo in the last name must not cost a long run).
    for name in scenes {
        load_bench_scene(name)?;
    }
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut results = SweepResults::default();
    let progress = Progress::new("bench", (scenes.len() * chosen_settings(config).count()) as u64);
    let references = ReferenceCache::new(config.width, config.height, config.reference_spp);
    for name in scenes {
        let world = load_bench_scene(name)?;
        let view = config.camera.clone().or_else(|| world.view(None).cloned()).unwrap_or_else(|| world.overview());
        let reference = references.image(&world, &view, &Reference::direct())?;
        results.noise.push((name.clone(), references.noise(&world, &view, &Reference::direct(), &reference)?));
        let keep = same_hit::same_hit_pixels(&world, &view, config.width, config.height)?;
        let scene = SweepScene { name, world, view, reference, keep, config, progress: &progress };
        scene.run(&mut results, out)?;
    }
    progress.finish();
    let SweepResults { mut rows, curves, noise, equal_time } = results;
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

impl SweepScene<'_> {
    /// The scene's settings, its equal-time row and its convergence curves, added to `results`.
    fn run(&self, results: &mut SweepResults, out: &Path) -> Result<(), String> {
        let first = results.rows.len();
        let restir_expected = self.measure_settings(&mut results.rows, out)?;
        let times: Vec<(String, f64)> = results.rows[first..].iter().map(|r| (r.setting.clone(), r.frame_ms)).collect();
        let time_of = |setting: &str| times.iter().find(|(s, _)| s == setting).map(|&(_, ms)| ms);
        if let (Some(nee_ms), Some(budget_ms)) = (time_of("nee-power"), time_of(EQUAL_TIME_TO)) {
            self.equal_time(results, nee_ms, budget_ms, restir_expected)?;
        }
        for method in METHODS {
            let Some(frame_ms) = time_of(method.setting) else { continue };
            let config = self.config;
            let pairs: Vec<String> =
                std::iter::once(radius_pair(config)).chain(method.pairs.iter().map(|p| p.to_string())).collect();
            let spec = CurveSpec {
                name: method.name,
                pairs: &pairs,
                frame_ms,
                size: (config.width, config.height),
                frames: config.curve_frames,
            };
            let points = measure_curve(&self.world, &self.view, &spec, &self.reference, self.name)?;
            self.progress.println(&format!(
                "bench: {} {} accumulated: relMSE {}",
                self.name,
                method.name,
                points.iter().map(|p| format!("{:.2e}@{}", p.metrics.relmse, p.frames)).collect::<Vec<_>>().join(" ")
            ));
            results.curves.extend(points);
        }
        Ok(())
    }

    /// One row per chosen setting, and the strip (reference | NEE | ReSTIR | FLIP); the expected errors of the
    /// setting NEE is held to at equal time, when it ran.
    fn measure_settings(&self, rows: &mut Vec<BenchRow>, out: &Path) -> Result<Option<(Metrics, Metrics)>, String> {
        let (name, reference) = (self.name, &self.reference);
        let mut strip = vec![reference.clone()];
        let mut restir_expected = None;
        for setting in chosen_settings(self.config) {
            // The setting NEE is held to at equal time: its expected one-frame error over several frames.
            let frames = if setting.name == EQUAL_TIME_TO { EQUAL_TIME_TRIALS } else { 1 };
            let (frame_ms, passes, images) = measure(&self.world, &self.view, setting, self.config, frames)?;
            if setting.name == EQUAL_TIME_TO {
                restir_expected = Some(expected_errors(&images, reference, &self.keep)?);
            }
            let image = images.into_iter().next().ok_or("no frame rendered")?;
            let metrics = compare(&image, reference)?;
            let flip = flip(&image, Encoding::Linear, reference, Encoding::Linear)?;
            self.progress.println(&format!(
                "bench: {name} {}: {frame_ms:.2} ms/frame, {metrics} flip={:.4}",
                setting.name, flip.mean
            ));
            self.progress.advance(1);
            if setting.name == "nee-power" {
                strip.push(image);
            } else if setting.name == EQUAL_TIME_TO {
                strip.extend([image, flip.map]);
            }
            let gpu_ms = (!passes.is_empty()).then(|| passes.iter().map(|(_, ms)| ms).sum());
            let (scene, setting, flip) = (name.to_string(), setting.name.to_string(), flip.mean);
            rows.push(BenchRow { scene, setting, frames: 1, frame_ms, gpu_ms, passes, metrics, flip });
        }
        if strip.len() == 4 {
            plot::write_strip(&strip, &out.join(format!("strip-{name}.png")))?;
        }
        Ok(restir_expected)
    }

    /// NEE accumulated for the time one ReSTIR frame takes: its row, and the equal-time table's row when
    /// ReSTIR's expected errors are known.
    fn equal_time(
        &self,
        results: &mut SweepResults,
        nee_ms: f64,
        budget_ms: f64,
        restir_expected: Option<(Metrics, Metrics)>,
    ) -> Result<(), String> {
        let name = self.name;
        let nee =
            measure_equal_time(&self.world, &self.view, self.config, &self.reference, nee_ms, budget_ms, &self.keep)?;
        let frames = nee.frames;
        self.progress.println(&format!(
            "bench: {name} nee-equal-time ({frames} frames): {}; mean of {EQUAL_TIME_TRIALS}: {}",
            nee.first, nee.expected
        ));
        results.rows.push(BenchRow {
            scene: name.to_string(),
            setting: format!("nee-equal-time ({frames} frames)"),
            frames,
            frame_ms: nee_ms * frames as f64,
            gpu_ms: None,
            passes: Vec::new(),
            metrics: nee.first,
            flip: nee.flip,
        });
        if let Some((restir, restir_kept)) = restir_expected {
            let hit_alike = self.keep.iter().filter(|k| **k).count();
            self.progress.println(&format!(
                "bench: {name} equal time over the {hit_alike} pixels hit alike: NEE {}, ReSTIR {}",
                nee.expected_kept, restir_kept
            ));
            results.equal_time.push(EqualTimeRow {
                scene: name.to_string(),
                nee_frames: frames,
                nee: nee.expected,
                restir,
                nee_kept: nee.expected_kept,
                restir_kept,
                left_out: self.keep.len() - hit_alike,
            });
        }
        Ok(())
    }
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
    config: &SweepConfig,
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
