//! The GI cache's light alone (`bench --gi --indirect`): `debug=indirect` (the cache's share of the image, the
//! denoiser off) against the path tracer's indirect light (`reference --indirect`, 32 bounces, the mean of two
//! seeds, its own noise stated), with each entry's light-pool reservoirs (`gi_reservoirs`, seed 002) off and on,
//! and on with guided rays (`gi_guiding`, seed 004), on scenes of many small lights: the generated world at night
//! (the village, inside a house, a crystal cave), the thesis' apartments and letters, the cornell box and the
//! window room. One frame's error at frames 16, 64 and 256 of a cold cache, the bias of frames 65-256's mean (the
//! cache's own, as a share of the indirect light and of the lit frame), the GI passes' GPU ms, and the error
//! at equal GPU time (a mode's error at the frame its time reaches the frame-64 time of the first mode, log-log
//! between the frames measured). With `seeds` above one, every figure is the mean over that many independent
//! realisations (the `seed` setting 0, 1, ..): one run's apartments move by 10-40% between runs.

use super::frame::{FrameCase, case_world};
use super::mean_metrics;
use super::reference_cache::{Reference, ReferenceCache};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::LinearImage;
use crate::reference::REFERENCE_BOUNCES;
use crate::reference::metrics::{Metrics, compare};
use crate::render::gi::GI_PASS_NAMES;
use crate::settings::RenderSettings;
use std::path::Path;

/// The scenes: night is 22:00 in the generated world (its lamps lit, the moon low); the rest are lit by their
/// emitters alone, as the thesis' protocol has them.
pub const CASES: [FrameCase; 7] = [
    FrameCase { label: "night village", scene: "generated", view: "village", settings: &["time=22"] },
    FrameCase { label: "night house", scene: "generated", view: "house", settings: &["time=22"] },
    FrameCase { label: "crystal cave", scene: "generated", view: "cave", settings: &["time=22"] },
    FrameCase { label: "apartments", scene: "apartments", view: "street", settings: &["lighting=emitters"] },
    FrameCase { label: "letters", scene: "thesis-letters", view: "letters1", settings: &["lighting=emitters"] },
    FrameCase { label: "cornell", scene: "cornell", view: "front", settings: &["lighting=emitters"] },
    FrameCase { label: "window-room", scene: "window-room", view: "inside", settings: &["lighting=emitters"] },
];

/// The modes compared (settings separated by spaces): one light a sample, the reservoirs, and the reservoirs with
/// guided rays.
const MODES: [(&str, &str); 3] = [
    ("one light a sample", "gi_reservoirs=off gi_guiding=off"),
    ("reservoirs", "gi_reservoirs=on gi_guiding=off"),
    ("reservoirs, guided rays", "gi_reservoirs=on gi_guiding=on"),
];

/// Frames after which one frame is measured (cumulative).
const FRAMES: [u32; 3] = [16, 64, 256];

/// What `bench --gi --indirect` runs.
#[derive(Clone, Debug)]
pub struct IndirectConfig {
    pub width: u32,
    pub height: u32,
    pub reference_spp: u32,
    /// Only the cases whose label contains one of these (all when empty).
    pub only: Vec<String>,
    /// Independent realisations averaged per row (the `seed` setting 0..seeds).
    pub seeds: u32,
}

struct Row {
    case: &'static str,
    mode: &'static str,
    /// One frame's error at each of FRAMES.
    errors: Vec<Metrics>,
    /// The bias of the mean of frames 65-256 (luminance): the cache's own, its frame-to-frame noise averaged out.
    steady_bias: f64,
    gi_ms: f64,
    frame_ms: f64,
}

fn settings_for(case: &FrameCase, mode: &str, seed: u32) -> Result<RenderSettings, String> {
    let seed = format!("seed={seed}");
    let pairs: Vec<String> = case
        .settings
        .iter()
        .copied()
        .chain(["gi=on", "denoise=off", "debug=indirect"])
        .chain(mode.split_whitespace())
        .chain([seed.as_str()])
        .map(str::to_string)
        .collect();
    RenderSettings::default().with_pairs(&pairs)
}

/// One mode on one case, averaged over the config's seeds.
fn measure(
    case: &FrameCase,
    mode: (&'static str, &str),
    config: &IndirectConfig,
    truth: &LinearImage,
) -> Result<Row, String> {
    let runs = (0..config.seeds.max(1))
        .map(|seed| measure_seed(case, mode, config, truth, seed))
        .collect::<Result<Vec<_>, _>>()?;
    let n = runs.len() as f64;
    let mean = |f: fn(&Row) -> f64| runs.iter().map(f).sum::<f64>() / n;
    let errors =
        (0..FRAMES.len()).map(|i| mean_metrics(&runs.iter().map(|r| r.errors[i]).collect::<Vec<_>>())).collect();
    Ok(Row {
        case: case.label,
        mode: mode.0,
        errors,
        steady_bias: mean(|r| r.steady_bias),
        gi_ms: mean(|r| r.gi_ms),
        frame_ms: mean(|r| r.frame_ms),
    })
}

fn measure_seed(
    case: &FrameCase,
    mode: (&'static str, &str),
    config: &IndirectConfig,
    truth: &LinearImage,
    seed: u32,
) -> Result<Row, String> {
    let (world, view) = case_world(case)?;
    let settings = settings_for(case, mode.1, seed)?;
    let options = HeadlessOptions { width: config.width, height: config.height, settings, ..Default::default() };
    let mut r = HeadlessRenderer::new(world, &view, &options)?;
    let mut errors = Vec::new();
    let mut done = 0;
    let mut steady_bias = f64::NAN;
    for &frames in &FRAMES {
        if frames == 64 {
            r.clear_gpu_pass_times();
        }
        let image = if frames == FRAMES[2] {
            // Every frame after frame 64: their mean's bias is the cache's own.
            let sequence = r.render_sequence(frames - done, |_, _| {})?;
            steady_bias = compare(&mean_image(&sequence), truth)?.bias;
            sequence.into_iter().next_back().ok_or("no frames rendered")?
        } else {
            r.render(frames - done)?
        };
        done = frames;
        errors.push(compare(&image, truth)?);
        eprintln!("gi indirect: {} {} seed {seed} frame {frames}: {}", case.label, mode.0, errors.last().unwrap());
    }
    let gi_ms = GI_PASS_NAMES.iter().filter_map(|n| r.gpu_pass_ms(n)).sum();
    let frame_ms = crate::render::frame::all_passes().iter().filter_map(|p| r.gpu_pass_ms(p.name)).sum();
    Ok(Row { case: case.label, mode: mode.0, errors, steady_bias, gi_ms, frame_ms })
}

/// The pixel-by-pixel mean of images of one size.
fn mean_image(images: &[LinearImage]) -> LinearImage {
    let mut mean = images[0].clone();
    for (k, pixel) in mean.pixels.iter_mut().enumerate() {
        for c in 0..4 {
            pixel[c] = (images.iter().map(|i| i.pixels[k][c] as f64).sum::<f64>() / images.len() as f64) as f32;
        }
    }
    mean
}

/// The mean luminance of the lit image (the cache's light with the direct light, the default settings, frame
/// 16): what the indirect light's bias is a share of in the whole frame.
fn lit_mean(case: &FrameCase, config: &IndirectConfig) -> Result<f64, String> {
    let (world, view) = case_world(case)?;
    // The default mode's settings with the lit image in place of the indirect view.
    let settings = settings_for(case, "debug=none", 0)?;
    let options = HeadlessOptions { width: config.width, height: config.height, settings, ..Default::default() };
    Ok(HeadlessRenderer::new(world, &view, &options)?.render(16)?.mean_luminance())
}

/// The error `row` reaches after `frames` frames, log-log between the frames measured (clamped to their range).
fn error_at(row: &Row, frames: f64) -> f64 {
    let points: Vec<(f64, f64)> =
        FRAMES.iter().zip(&row.errors).map(|(&f, m)| ((f as f64).ln(), m.relmse.max(1e-12).ln())).collect();
    let x = frames.ln().clamp(points[0].0, points[points.len() - 1].0);
    let i = points.windows(2).position(|w| x <= w[1].0).unwrap_or(points.len() - 2);
    let (a, b) = (points[i], points[i + 1]);
    let t = (x - a.0) / (b.0 - a.0);
    (a.1 + t * (b.1 - a.1)).exp()
}

pub fn run_indirect_bench(config: &IndirectConfig, out: &Path) -> Result<String, String> {
    let references = ReferenceCache::new(config.width, config.height, config.reference_spp);
    let mut rows = Vec::new();
    let mut noises = Vec::new();
    let cases =
        CASES.iter().filter(|c| config.only.is_empty() || config.only.iter().any(|o| c.label.contains(o.as_str())));
    for case in cases {
        let (world, view) = case_world(case)?;
        let settings = settings_for(case, MODES[0].1, 0)?;
        let what = Reference { indirect: true, daylight: settings.daylight(), ..Reference::bounces(REFERENCE_BOUNCES) };
        let (truth, noise) = references.two_seeds(&world, &view, &what)?;
        noises.push((case.label, noise, truth.mean_luminance(), lit_mean(case, config)?));
        for mode in MODES {
            rows.push(measure(case, mode, config, &truth)?);
        }
    }
    let text = markdown(&rows, &noises, config);
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let path = out.join("gi-indirect.md");
    std::fs::write(&path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(text)
}

fn markdown(rows: &[Row], noises: &[(&str, Metrics, f64, f64)], config: &IndirectConfig) -> String {
    let mut text = format!(
        "# The GI cache's light alone: reservoirs per entry, guided rays\n\n`debug=indirect` at {}x{}, denoiser off, one frame \
         of a cold cache at frames {FRAMES:?}, against `reference --indirect` ({REFERENCE_BOUNCES} bounces, the \
         mean of two seeds of {} spp; its own relMSE beside each scene). Each figure is the mean of {} \
         realisation(s) (the `seed` setting). GPU ms: the GI passes, and the whole frame, \
         mean of frames 64-256. Equal time: a mode's error at the frame its GPU time reaches the frame-64 \
         time of one light a sample. Steady bias: the bias of the mean of frames 65-256 (the cache's own, its \
         noise averaged out, and in a scene whose bounces are still arriving its lag: docs/bench/gi.md, \
         \"The letters' slow light\"), as a share of the reference's indirect light and of the lit frame's mean (the \
         default settings' image with its direct light, frame 16).\n\n\
         | scene | mode | relMSE f16 | f64 | f256 | bias f64 (% of mean) | steady bias (% of indirect) | (% of lit frame) | GI ms | frame ms | relMSE at equal time | reference's relMSE |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|\n",
        config.width,
        config.height,
        config.reference_spp,
        config.seeds.max(1)
    );
    for row in rows {
        let (noise, mean, lit) =
            noises.iter().find(|n| n.0 == row.case).map_or((f64::NAN, f64::NAN, f64::NAN), |n| (n.1.relmse, n.2, n.3));
        let baseline = rows.iter().find(|r| r.case == row.case && r.mode == MODES[0].0);
        let equal = match baseline {
            Some(b) if row.mode != MODES[0].0 && row.frame_ms > 0.0 => {
                format!("{:.5}", error_at(row, 64.0 * b.frame_ms / row.frame_ms))
            }
            _ => format!("{:.5}", row.errors[1].relmse),
        };
        text += &format!(
            "| {} | {} | {:.5} | {:.5} | {:.5} | {:+.1} | {:+.1} | {:+.1} | {:.2} | {:.2} | {equal} | {noise:.5} |\n",
            row.case,
            row.mode,
            row.errors[0].relmse,
            row.errors[1].relmse,
            row.errors[2].relmse,
            100.0 * row.errors[1].bias / mean,
            100.0 * row.steady_bias / mean,
            100.0 * row.steady_bias / lit,
            row.gi_ms,
            row.frame_ms,
        );
    }
    text
}
