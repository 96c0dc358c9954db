//! The upscaler's error at each render scale (`glowbrick bench --denoise --upscale`): the game's denoised frame
//! (`lighting=full gi=on denoise=on`) on the frame profile's scenes (the bundled rooms, the generated world at
//! noon and at night, the thesis' letters), at render scales 1, 0.75, 0.5, 0.33 and 0.25, frame `MEASURED_FRAME`
//! against a 32-bounce CPU reference at the output's resolution: relMSE, FLIP and bias, with the reference's own
//! noise beside them, and the GPU time of the frame. Then the equal-time view: each scale's relMSE at native's GPU
//! time, and a scale that spends its saving on more ReSTIR candidates (`SPENT`), measured.
//! Writes `upscale-frame.md`.

use super::denoise::DenoiseConfig;
use super::frame::{CASES, FrameCase, case_world};
use super::mean_metrics;
use super::reference_cache::{Reference, ReferenceCache};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::LinearImage;
use crate::reference::REFERENCE_BOUNCES;
use crate::reference::flip::{Encoding, flip};
use crate::reference::metrics::{Metrics, compare};
use crate::render::adapter::adapter_name;
use crate::render::frame::all_passes;
use crate::settings::RenderSettings;
use crate::world::{CameraView, VoxelWorld};
use std::time::Instant;

/// The render scales measured, native first.
pub const SCALES: [f32; 5] = [1.0, 0.75, 0.5, 0.33, 0.25];
/// The frame measured: the denoiser's history is full by then; the GI cache is still in its warm-up.
pub const MEASURED_FRAME: u32 = 32;
/// Frames before the measured one whose GPU time is averaged with it.
const TIMED_FRAMES: u32 = 4;
/// The equal-time try: a render scale that spends the time it saves on more of Voxel ReSTIR's candidates.
pub const SPENT: (f32, &str) = (0.5, "candidates=64");

/// One render scale of one scene.
#[derive(Clone, Debug)]
pub struct ScaleRow {
    pub scale: f32,
    /// The settings on top of the game's frame that this row adds (the equal-time try's), or none.
    pub spent: Option<&'static str>,
    pub metrics: Metrics,
    pub flip: f64,
    /// GPU ms of the frame's passes (mean of the last `TIMED_FRAMES`), None without timestamps.
    pub gpu_ms: Option<f64>,
    pub wall_ms: f64,
}

/// One scene: its reference's mean and own noise, and its rows.
#[derive(Clone, Debug)]
pub struct UpscaleScene {
    pub label: &'static str,
    pub mean: f64,
    pub noise: Metrics,
    pub rows: Vec<ScaleRow>,
}

/// The scenes `--scenes` names among the frame profile's (all where none is named), or an error naming the
/// valid ones.
pub fn pick_scenes(names: &[String]) -> Result<Vec<FrameCase>, String> {
    if let Some(unknown) = names.iter().find(|n| !CASES.iter().any(|c| c.label == n.as_str())) {
        let valid: Vec<&str> = CASES.iter().map(|c| c.label).collect();
        return Err(format!("--upscale has no scene '{unknown}' (valid: {})", valid.join(", ")));
    }
    Ok(CASES.into_iter().filter(|c| names.is_empty() || names.iter().any(|n| n == c.label)).collect())
}

fn settings_for(case: &FrameCase, scale: f32, spent: Option<&str>, extra: &[String]) -> Result<RenderSettings, String> {
    let pairs: Vec<String> = case
        .settings
        .iter()
        .map(|p| p.to_string())
        .chain([format!("render_scale={scale}")])
        .chain(spent.map(str::to_string))
        .chain(extra.iter().cloned())
        .collect();
    RenderSettings::game().with_pairs(&pairs)
}

/// One realisation of a row (the `seed` setting): frame `MEASURED_FRAME`'s metrics and FLIP, and the GPU and
/// wall ms of its last `TIMED_FRAMES` frames.
struct Realisation {
    metrics: Metrics,
    flip: f64,
    gpu_ms: Option<f64>,
    wall_ms: f64,
}

fn realise(
    (world, view): (&VoxelWorld, &CameraView),
    mut settings: RenderSettings,
    seed: u32,
    config: &DenoiseConfig,
    truth: &LinearImage,
) -> Result<Realisation, String> {
    settings.set(&format!("seed={seed}"))?;
    let options = HeadlessOptions { width: config.width, height: config.height, settings, ..Default::default() };
    let mut r = HeadlessRenderer::new(world.clone(), view, &options)?;
    r.render(MEASURED_FRAME - TIMED_FRAMES)?;
    r.clear_gpu_pass_times();
    let start = Instant::now();
    let image = r.render(TIMED_FRAMES)?;
    let wall_ms = start.elapsed().as_secs_f64() * 1000.0 / TIMED_FRAMES as f64;
    let times: Vec<f64> = all_passes().iter().filter_map(|p| r.gpu_pass_ms(p.name)).collect();
    let image = if config.lattice > 1 { image.lattice(config.lattice) } else { image };
    Ok(Realisation {
        metrics: compare(&image, truth)?,
        flip: flip(&image, Encoding::Linear, truth, Encoding::Linear)?.mean,
        gpu_ms: (!times.is_empty()).then(|| times.iter().sum()),
        wall_ms,
    })
}

/// One row: the mean over the config's seeds (independent realisations: one frame's relMSE is decided by its
/// few brightest outliers, and which frame has them is chance).
fn measure_row(
    case: &FrameCase,
    scene: (&VoxelWorld, &CameraView),
    scale: f32,
    spent: Option<&'static str>,
    config: &DenoiseConfig,
    truth: &LinearImage,
) -> Result<ScaleRow, String> {
    let settings = settings_for(case, scale, spent, &config.settings)?;
    let runs: Vec<Realisation> = (0..config.seeds.max(1))
        .map(|seed| realise(scene, settings.clone(), seed, config, truth))
        .collect::<Result<_, _>>()?;
    let n = runs.len() as f64;
    let gpu: Vec<f64> = runs.iter().filter_map(|r| r.gpu_ms).collect();
    Ok(ScaleRow {
        scale,
        spent,
        metrics: mean_metrics(&runs.iter().map(|r| r.metrics).collect::<Vec<_>>()),
        flip: runs.iter().map(|r| r.flip).sum::<f64>() / n,
        gpu_ms: (gpu.len() == runs.len()).then(|| gpu.iter().sum::<f64>() / n),
        wall_ms: runs.iter().map(|r| r.wall_ms).sum::<f64>() / n,
    })
}

/// Every scale (and the equal-time try) of one scene.
fn measure_scene(case: &FrameCase, config: &DenoiseConfig) -> Result<UpscaleScene, String> {
    let (world, view) = case_world(case)?;
    let settings = settings_for(case, 1.0, None, &config.settings)?;
    let what = Reference {
        bounces: REFERENCE_BOUNCES,
        daylight: settings.daylight(),
        lattice: (config.lattice > 1).then_some(config.lattice),
        indirect: false,
    };
    let references = ReferenceCache::new(config.width, config.height, config.reference_spp);
    let (truth, noise) = references.two_seeds(&world, &view, &what)?;
    let mut rows = Vec::new();
    let tries = SCALES.iter().map(|&s| (s, None)).chain([(SPENT.0, Some(SPENT.1))]);
    for (scale, spent) in tries {
        let row = measure_row(case, (&world, &view), scale, spent, config, &truth)?;
        eprintln!(
            "upscale bench: {} at {scale}{}: {} flip={:.4} gpu={:?} ms",
            case.label,
            spent.map_or(String::new(), |s| format!(" {s}")),
            row.metrics,
            row.flip,
            row.gpu_ms
        );
        rows.push(row);
    }
    Ok(UpscaleScene { label: case.label, mean: truth.mean_luminance(), noise, rows })
}

/// Runs every picked scene.
pub fn run_upscale(config: &DenoiseConfig, cases: &[FrameCase]) -> Result<Vec<UpscaleScene>, String> {
    check_lattice(config.lattice)?;
    cases.iter().map(|case| measure_scene(case, config)).collect()
}

/// A lattice that shares a factor with a scale's pattern of sampled output pixels measures only some of them:
/// `--lattice 2` reads pixels `2i + 1`, exactly the ones render scale 0.5 lights with their own render pixel,
/// and flattered that scale. 1 or a step without the factors 2 and 3 mixes every kind of pixel.
pub fn check_lattice(lattice: u32) -> Result<(), String> {
    if lattice > 1 && (lattice % 2 == 0 || lattice % 3 == 0) {
        return Err(format!(
            "--upscale --lattice {lattice}: a step with the factor 2 or 3 lines up with the render scales' sampled \
             pixels (at 0.5 every other pixel) and measures only some kinds of pixel; use 1, 5 or 7"
        ));
    }
    Ok(())
}

/// relMSE at native's GPU time, taking a Monte Carlo estimate's error to fall as one over the time spent:
/// `relmse * ms / native_ms` (lower wins). None without timestamps.
pub fn relmse_at_native_time(row: &ScaleRow, native: &ScaleRow) -> Option<f64> {
    Some(row.metrics.relmse * row.gpu_ms? / native.gpu_ms?.max(1e-9))
}

/// The report.
pub fn upscale_markdown(scenes: &[UpscaleScene], config: &DenoiseConfig) -> String {
    let lattice = if config.lattice > 1 {
        format!(" (reference and errors on every {}-th pixel each way)", config.lattice)
    } else {
        String::new()
    };
    let mut text = format!(
        "# The upscaler at each render scale\n\n`glowbrick bench --denoise --upscale --size {w}x{h} --spp {spp} \
         --lattice {l} --seeds {seeds}` on {adapter}: the game's frame (`lighting=full gi=on denoise=on`), frame \
         {MEASURED_FRAME} at {w}x{h} output{lattice}, the mean of {seeds} independent realisations, against a {REFERENCE_BOUNCES}-bounce CPU reference of 2 x {spp} spp. \
         **ratio** is relMSE over native's; **at native's time** is relMSE x (GPU ms / native's GPU ms), the \
         error the scale would reach spending native's time if its error fell as one over the time (lower wins); \
         the last row of each scene spends the time 0.5 saves on `{spent}` and is measured. GPU ms: the frame's \
         passes, mean of its last {TIMED_FRAMES} frames (timestamps).\n",
        w = config.width,
        h = config.height,
        spp = config.reference_spp,
        l = config.lattice,
        seeds = config.seeds.max(1),
        adapter = adapter_name(),
        spent = SPENT.1,
    );
    let ms = |v: Option<f64>| v.map_or("-".to_string(), |ms| format!("{ms:.1}"));
    for scene in scenes {
        text += &format!(
            "\n## {}\n\nReference mean {:.4}; its own noise: relMSE {:.5}, MAE {:.5}.\n\n\
             | scale | relMSE | ratio | FLIP | FLIP ratio | bias (% of mean) | GPU ms | wall ms | relMSE at native's time |\n\
             |---|---|---|---|---|---|---|---|---|\n",
            scene.label, scene.mean, scene.noise.relmse, scene.noise.mae
        );
        let Some(native) = scene.rows.first() else { continue };
        for row in &scene.rows {
            let label = match row.spent {
                Some(s) => format!("{} + {s}", row.scale),
                None => format!("{}", row.scale),
            };
            text += &format!(
                "| {label} | {:.5} | {:.2}x | {:.4} | {:.2}x | {:+.2}% | {} | {:.0} | {} |\n",
                row.metrics.relmse,
                row.metrics.relmse / native.metrics.relmse.max(1e-12),
                row.flip,
                row.flip / native.flip.max(1e-12),
                100.0 * row.metrics.bias / scene.mean.max(1e-12),
                ms(row.gpu_ms),
                row.wall_ms,
                relmse_at_native_time(row, native).map_or("-".into(), |e| format!("{e:.5}"))
            );
        }
        let best = scene
            .rows
            .iter()
            .filter_map(|r| relmse_at_native_time(r, native).map(|e| (r, e)))
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((row, _)) = best {
            text += &format!(
                "\nAt equal GPU time the lowest error is at scale {}{}.\n",
                row.scale,
                row.spent.map_or(String::new(), |s| format!(" with {s}"))
            );
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(scale: f32, relmse: f64, gpu_ms: Option<f64>) -> ScaleRow {
        let metrics = Metrics { mae: 0.0, mse: 0.0, relmse, bias: 0.0, fireflies: 0 };
        ScaleRow { scale, spent: None, metrics, flip: 0.1, gpu_ms, wall_ms: 1.0 }
    }

    /// A scale at a quarter of native's time with twice its error reaches half native's error at equal time.
    #[test]
    fn equal_time_scales_the_error_by_the_time_spent() {
        let native = row(1.0, 0.01, Some(8.0));
        assert_eq!(relmse_at_native_time(&native, &native), Some(0.01));
        assert_eq!(relmse_at_native_time(&row(0.5, 0.02, Some(2.0)), &native), Some(0.005));
        assert_eq!(relmse_at_native_time(&row(0.5, 0.02, None), &native), None);
    }

    /// `--scenes` picks by the frame profile's labels and refuses others.
    #[test]
    fn scenes_are_the_frame_profiles() {
        assert_eq!(pick_scenes(&[]).unwrap().len(), CASES.len());
        let picked = pick_scenes(&["generated-night".into(), "cornell".into()]).unwrap();
        assert_eq!(picked.iter().map(|c| c.label).collect::<Vec<_>>(), ["cornell", "generated-night"]);
        assert!(pick_scenes(&["kitchen".into()]).unwrap_err().contains("generated-noon"));
    }

    /// The lattice never lines up with the pixels a scale samples.
    #[test]
    fn lattices_that_line_up_with_a_scale_are_refused() {
        for ok in [1, 5, 7, 11] {
            assert!(check_lattice(ok).is_ok(), "{ok}");
        }
        for refused in [2, 3, 4, 6, 9] {
            assert!(check_lattice(refused).unwrap_err().contains("use 1, 5 or 7"), "{refused}");
        }
    }

    /// Every row's settings parse: the scales, the equal-time try, and the scene's own time of day.
    #[test]
    fn every_row_has_valid_settings() {
        for case in CASES {
            for scale in SCALES {
                let s = settings_for(&case, scale, None, &[]).unwrap();
                assert_eq!(s.render_scale, crate::settings::RenderScale::Fixed(scale));
                assert!(s.denoise && s.gi.enabled);
            }
            assert_eq!(settings_for(&case, SPENT.0, Some(SPENT.1), &[]).unwrap().restir.candidates, 64);
        }
    }
}
