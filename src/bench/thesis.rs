//! The thesis protocol (`glowbrick bench --thesis`): seed 000's own scenes and camera views, a static camera,
//! 32 frames of Voxel ReSTIR with M = 32 and temporal + spatial reuse, area and point samples, the cornell box
//! with brick lights on and off; MAE and MSE (seed 000 §3.3) of the last frame against the direct-light CPU
//! reference; our GPU time per pass. Writes `thesis.md` beside the thesis' Table 3.
//!
//! The thesis rendered 1600 x 1024; `scale` shrinks both sides (and the 30 px spatial radius with them), so the
//! CPU reference stays affordable on a small machine.

use super::{BenchConfig, PassTimes, cached_reference, pass_times};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::reference::metrics::{Metrics, compare};
use crate::settings::RenderSettings;
use crate::world::VoxelWorld;
use crate::world::source::load_path;
use std::path::{Path, PathBuf};

/// One row of the thesis' Table 3.
pub struct ThesisView {
    pub label: &'static str,
    pub file: &'static str,
    pub view: &'static str,
    pub brick_lights: bool,
    /// Table 3 MAE: Voxel ReSTIR area, point, and GfxExp's triangle ReSTIR (None where the thesis has none).
    pub thesis_mae: [Option<f64>; 3],
}

pub const THESIS_VIEWS: [ThesisView; 4] = [
    ThesisView {
        label: "letters 1",
        file: "letters.vx",
        view: "letters1",
        brick_lights: true,
        thesis_mae: [Some(0.0059), Some(0.0075), Some(0.0133)],
    },
    ThesisView {
        label: "letters 2",
        file: "letters.vx",
        view: "letters2",
        brick_lights: true,
        thesis_mae: [Some(0.0067), Some(0.0089), Some(0.0101)],
    },
    ThesisView {
        label: "cornell, 256 brick lights",
        file: "cornellbox.vx",
        view: "cornell1",
        brick_lights: true,
        thesis_mae: [Some(0.0111), Some(0.0396), Some(0.0279)],
    },
    ThesisView {
        label: "cornell, voxel lights",
        file: "cornellbox.vx",
        view: "cornell1",
        brick_lights: false,
        thesis_mae: [Some(0.0142), Some(0.0430), None],
    },
];

/// Frames rendered with a static camera before the measured frame (the thesis: "more than 20").
pub const THESIS_FRAMES: u32 = 32;

/// Where the thesis' `.vx` files are: `../shared/scenes/thesis` beside the checkout, else the copies the tests
/// carry in `tests/data/thesis`.
pub fn thesis_scene(file: &str) -> Result<PathBuf, String> {
    let crate_dir = Path::new(env!("CARGO_MANIFEST_DIR"));
    let candidates = [
        crate_dir.join("../shared/scenes/thesis").join(file),
        crate_dir.join("tests/data/thesis").join(file),
        PathBuf::from("tests/data/thesis").join(file),
    ];
    candidates
        .iter()
        .find(|p| p.is_file())
        .cloned()
        .ok_or_else(|| format!("{file}: not found in ../shared/scenes/thesis or tests/data/thesis"))
}

/// One measured mode of one view.
pub struct ThesisResult {
    pub metrics: Metrics,
    pub passes: PassTimes,
}

fn render_mode(
    world: &VoxelWorld,
    view: &crate::world::CameraView,
    config: &BenchConfig,
    reference: &crate::image_io::LinearImage,
    sample: &str,
) -> Result<ThesisResult, String> {
    let radius = (30.0 * config.width as f32 / 1600.0).round().max(1.0);
    let pairs = ["lighting=restir", "candidates=32", "taps=5", "temporal=on", "spatial=on", "reuse=biased"]
        .iter()
        .map(|p| p.to_string())
        .chain([format!("radius={radius}"), format!("sample={sample}")])
        .collect::<Vec<_>>();
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width: config.width, height: config.height, settings, ..Default::default() };
    let mut renderer = HeadlessRenderer::new(world.clone(), view, &options)?;
    let image = renderer.render(THESIS_FRAMES)?;
    let passes = pass_times(&renderer);
    Ok(ThesisResult { metrics: compare(&image, reference)?, passes })
}

/// Runs the protocol at `scale` of 1600 x 1024 with `reference_spp`, writes `thesis.md` into `out`.
pub fn run_thesis_bench(scale: f32, reference_spp: u32, out: &Path) -> Result<String, String> {
    if !(scale.is_finite() && scale > 0.0 && scale <= 1.0) {
        return Err(format!("--scale {scale} must be within (0, 1]"));
    }
    let config = BenchConfig {
        width: ((1600.0 * scale).round() as u32).max(16),
        height: ((1024.0 * scale).round() as u32).max(16),
        warmup_frames: 0,
        timed_frames: 0,
        reference_spp,
        curve_frames: 0,
        camera: None,
        only: Vec::new(),
    };
    let mut rows = Vec::new();
    let mut loaded: Option<(&str, VoxelWorld)> = None;
    for t in &THESIS_VIEWS {
        if loaded.as_ref().is_none_or(|(file, _)| *file != t.file) {
            let path = thesis_scene(t.file)?;
            let start = std::time::Instant::now();
            let world = load_path(&path).map_err(|e| e.to_string())?;
            eprintln!("thesis: loaded {} in {:.1} s", path.display(), start.elapsed().as_secs_f64());
            loaded = Some((t.file, world));
        }
        let mut world = loaded.as_ref().map(|(_, w)| w.clone()).ok_or("no world")?;
        world.brick_lights = t.brick_lights;
        let view = world.view(Some(t.view)).cloned().ok_or_else(|| format!("{}: no view {}", t.file, t.view))?;
        let reference = cached_reference(&world, &view, &config)?;
        let area = render_mode(&world, &view, &config, &reference, "area")?;
        let point = render_mode(&world, &view, &config, &reference, "point")?;
        eprintln!("thesis: {}: area {}, point {}", t.label, area.metrics, point.metrics);
        rows.push((t, area, point));
    }
    let text = thesis_markdown(&rows, &config, scale);
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let path = out.join("thesis.md");
    std::fs::write(&path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(text)
}

fn cell(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.4}"))
}

fn passes_text(passes: &[(&'static str, f64)]) -> String {
    if passes.is_empty() {
        return "n/a".into();
    }
    let total: f64 = passes.iter().map(|(_, ms)| ms).sum();
    let each: Vec<String> =
        passes.iter().map(|(n, ms)| format!("{} {ms:.1}", n.trim_start_matches("glowbrick_"))).collect();
    format!("{total:.1} ({})", each.join(", "))
}

fn thesis_markdown(rows: &[(&ThesisView, ThesisResult, ThesisResult)], config: &BenchConfig, scale: f32) -> String {
    let mut text = format!(
        "# The thesis protocol\n\n`glowbrick bench --thesis --scale {scale}`: seed 000's scenes and views at {}x{} \
         ({scale} of 1600x1024, spatial radius scaled from 30 px), static camera, frame {THESIS_FRAMES} of Voxel \
         ReSTIR (M = 32, temporal + spatial reuse, 5 taps, biased reuse), against a {}-spp direct-light CPU \
         reference. MAE and MSE as seed 000 §3.3. GPU ms: timestamp queries of our passes (primary + the three \
         ReSTIR passes), averaged over the run. What each row means and why some are worse than the thesis: \
         [restir.md](restir.md#against-the-thesis-table-3).\n\n\
         | view | our MAE area | our MAE point | thesis area | thesis point | GfxExp | our MSE area | our MSE point \
         | GPU ms area (per pass) | GPU ms point |\n|---|---|---|---|---|---|---|---|---|---|\n",
        config.width, config.height, config.reference_spp
    );
    for (t, area, point) in rows {
        text += &format!(
            "| {} | {:.4} | {:.4} | {} | {} | {} | {:.5} | {:.5} | {} | {} |\n",
            t.label,
            area.metrics.mae,
            point.metrics.mae,
            cell(t.thesis_mae[0]),
            cell(t.thesis_mae[1]),
            cell(t.thesis_mae[2]),
            area.metrics.mse,
            point.metrics.mse,
            passes_text(&area.passes),
            passes_text(&point.passes),
        );
    }
    text
}
