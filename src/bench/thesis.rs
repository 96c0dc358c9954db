//! The thesis protocol (`glowbrick bench --thesis`): seed 000's own scenes and camera views, a static camera,
//! 32 frames of Voxel ReSTIR with M = 32 and temporal + spatial reuse, area and point samples, the cornell box
//! with brick lights on and off; MAE and MSE (seed 000 §3.3) of the last frame against the direct-light CPU
//! reference; our GPU time per pass. Writes `thesis.md` beside the thesis' Table 3.
//!
//! The thesis rendered 1600 x 1024; `scale` shrinks both sides (and the 30 px spatial radius with them), so the
//! CPU reference stays affordable on a small machine. Or `lattice` keeps the thesis' size and integrates the
//! reference at every `lattice`-th pixel only, measuring the error on those pixels: an unbiased estimate of the
//! full image's MAE and MSE at 1 / lattice^2 of the reference's cost. The reference is the mean of two seeds, so
//! its own noise is measured and stated.

use super::reference_cache::{Reference, ReferenceCache, check_lattice};
use super::{PassTimes, pass_times};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::write_image;
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
    /// Table 1's MSE of Voxel ReSTIR, area samples, 32 candidates.
    pub thesis_mse_area: f64,
}

pub const THESIS_VIEWS: [ThesisView; 4] = [
    ThesisView {
        label: "letters 1",
        file: "letters.vx",
        view: "letters1",
        brick_lights: true,
        thesis_mae: [Some(0.0059), Some(0.0075), Some(0.0133)],
        thesis_mse_area: 0.0009,
    },
    ThesisView {
        label: "letters 2",
        file: "letters.vx",
        view: "letters2",
        brick_lights: true,
        thesis_mae: [Some(0.0067), Some(0.0089), Some(0.0101)],
        thesis_mse_area: 0.0013,
    },
    ThesisView {
        label: "cornell, 256 brick lights",
        file: "cornellbox.vx",
        view: "cornell1",
        brick_lights: true,
        thesis_mae: [Some(0.0111), Some(0.0396), Some(0.0279)],
        thesis_mse_area: 0.0252,
    },
    ThesisView {
        label: "cornell, voxel lights",
        file: "cornellbox.vx",
        view: "cornell1",
        brick_lights: false,
        thesis_mae: [Some(0.0142), Some(0.0430), None],
        thesis_mse_area: 0.1660,
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
    /// The same with both images clamped to 1 (what an 8-bit export without tone mapping holds).
    pub clamped: Metrics,
    pub passes: PassTimes,
}

/// What `bench --thesis` runs.
pub struct ThesisOptions {
    /// Image size as a fraction of the thesis' 1600 x 1024.
    pub scale: f32,
    /// Samples per pixel of the reference, in total over its two seeds.
    pub spp: u32,
    /// The reference at every `lattice`-th pixel only (1: all).
    pub lattice: u32,
    /// Only the views whose label contains one of these (empty: all four).
    pub views: Vec<String>,
    /// Area samples only; the point-sample columns read n/a.
    pub area_only: bool,
    /// `--set KEY=VALUE`: settings on top of the protocol's (e.g. `denoise=on`).
    pub settings: Vec<String>,
}

fn render_mode(
    world: &VoxelWorld,
    view: &crate::world::CameraView,
    (width, height): (u32, u32),
    reference: &Lattice,
    sample: &str,
    extra: &[String],
    (label, out): (&str, &Path),
) -> Result<ThesisResult, String> {
    let radius = (30.0 * width as f32 / 1600.0).round().max(1.0);
    let pairs = [
        "lighting=restir",
        "candidates=32",
        "taps=5",
        "temporal=on",
        "spatial=on",
        "reuse=biased",
        "initial_visibility=on",
    ]
    .iter()
    .map(|p| p.to_string())
    .chain([format!("radius={radius}"), format!("sample={sample}")])
    .chain(extra.iter().cloned())
    .collect::<Vec<_>>();
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width, height, settings, ..Default::default() };
    let mut renderer = HeadlessRenderer::new(world.clone(), view, &options)?;
    let image = renderer.render(THESIS_FRAMES)?;
    let passes = pass_times(&renderer);
    let measured = if reference.step > 1 { image.lattice(reference.step) } else { image };
    let path = out.join(format!("{}-{sample}.exr", file_stem(label)));
    write_image(&measured, &path)?;
    Ok(ThesisResult {
        metrics: compare(&measured, &reference.image)?,
        clamped: compare(&measured.clamped(1.0), &reference.image.clamped(1.0))?,
        passes,
    })
}

/// A view's label as a file name: "cornell, voxel lights" -> "cornell-voxel-lights".
fn file_stem(label: &str) -> String {
    label.split(|c: char| !c.is_ascii_alphanumeric()).filter(|w| !w.is_empty()).collect::<Vec<_>>().join("-")
}

/// The reference of a view at the lattice's pixels (every `step`-th; 1: all).
struct Lattice {
    image: crate::image_io::LinearImage,
    step: u32,
}

/// Runs the protocol, writes `thesis.md` into `out`.
pub fn run_thesis_bench(options: &ThesisOptions, out: &Path) -> Result<String, String> {
    let ThesisOptions { scale, spp, lattice, .. } = *options;
    if !(scale.is_finite() && scale > 0.0 && scale <= 1.0) {
        return Err(format!("--scale {scale} must be within (0, 1]"));
    }
    if spp < 2 {
        return Err(format!("--spp {spp}: the reference is the mean of two seeds, so it needs at least 2"));
    }
    // A bad `--set` is refused before the references' minutes, not after.
    RenderSettings::default().with_pairs(&options.settings)?;
    let size = (((1600.0 * scale).round() as u32).max(16), ((1024.0 * scale).round() as u32).max(16));
    check_lattice(lattice, size.0, size.1)?;
    // Each seed's half of the samples.
    let references = ReferenceCache::new(size.0, size.1, spp / 2);
    let views: Vec<&ThesisView> = THESIS_VIEWS
        .iter()
        .filter(|t| options.views.is_empty() || options.views.iter().any(|v| t.label.contains(v.as_str())))
        .collect();
    if views.is_empty() {
        let labels: Vec<&str> = THESIS_VIEWS.iter().map(|t| t.label).collect();
        return Err(format!("--views {:?} names none of the views: {}", options.views, labels.join(", ")));
    }
    let what = Reference { lattice: (lattice > 1).then_some(lattice), ..Reference::default() };
    let mut rows = Vec::new();
    let mut loaded: Option<(&str, VoxelWorld)> = None;
    for t in views {
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
        let (image, noise) = references.two_seeds(&world, &view, &what)?;
        std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
        write_image(&image, &out.join(format!("{}-reference.exr", file_stem(t.label))))?;
        let reference = Lattice { image, step: lattice };
        let area = render_mode(&world, &view, size, &reference, "area", &options.settings, (t.label, out))?;
        let point = if options.area_only {
            None
        } else {
            Some(render_mode(&world, &view, size, &reference, "point", &options.settings, (t.label, out))?)
        };
        let point_text = point.as_ref().map_or("not rendered".to_string(), |p| p.metrics.to_string());
        eprintln!("thesis: {}: area {}, point {point_text}, reference noise {}", t.label, area.metrics, noise);
        rows.push((t, area, point, noise));
    }
    let text = thesis_markdown(&rows, size, options);
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

type ThesisRow<'a> = (&'a ThesisView, ThesisResult, Option<ThesisResult>, Metrics);

fn thesis_markdown(rows: &[ThesisRow], (width, height): (u32, u32), options: &ThesisOptions) -> String {
    let ThesisOptions { scale, lattice, .. } = *options;
    let seed_spp = options.spp / 2;
    let mut command = format!("glowbrick bench --thesis --scale {scale} --spp {}", options.spp);
    if lattice > 1 {
        command += &format!(" --lattice {lattice}");
    }
    if !options.views.is_empty() {
        command += &format!(" --views {}", options.views.join(","));
    }
    if options.area_only {
        command += " --area-only";
    }
    for pair in &options.settings {
        command += &format!(" --set {pair}");
    }
    let on_top = if options.settings.is_empty() {
        String::new()
    } else {
        format!(", with `{}` on top", options.settings.join(" "))
    };
    let measured_on = if lattice > 1 {
        format!(
            "; errors measured on every {lattice}th pixel in each direction ({}x{} pixels, an unbiased estimate of \
             the whole image's), where the reference is integrated",
            width / lattice,
            height / lattice
        )
    } else {
        String::new()
    };
    let mut text = format!(
        "# The thesis protocol\n\n`{command}`: seed 000's scenes and views at {}x{} ({scale} of 1600x1024, \
         spatial radius scaled from 30 px), static camera, frame {THESIS_FRAMES} of Voxel ReSTIR (M = 32, temporal \
         + spatial reuse, 5 taps, biased reuse{on_top}), against a {}-spp direct-light CPU reference (the mean of two \
         seeds' {} spp; its own noise is their MAE halved){measured_on}. MAE and MSE as seed 000 §3.3. GPU ms: \
         timestamp queries of our passes (primary + the three ReSTIR passes), averaged over the run. What each row \
         means and why some are worse than the thesis: [restir.md](restir.md#against-the-thesis-table-3).\n\n\
         | view | our MAE area | our MAE point | thesis area | thesis point | GfxExp | reference noise (MAE) \
         | our MAE area, point clamped to 1 | our MSE area | our MSE point | thesis MSE area | GPU ms area (per pass) \
         | GPU ms point |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        width,
        height,
        2 * seed_spp,
        seed_spp
    );
    for (t, area, point, noise) in rows {
        let of_point = |f: &dyn Fn(&ThesisResult) -> String| point.as_ref().map_or("n/a".to_string(), f);
        text += &format!(
            "| {} | {:.4} | {} | {} | {} | {} | {:.4} | {:.4}, {} | {:.5} | {} | {:.4} | {} | {} |\n",
            t.label,
            area.metrics.mae,
            of_point(&|p| format!("{:.4}", p.metrics.mae)),
            cell(t.thesis_mae[0]),
            cell(t.thesis_mae[1]),
            cell(t.thesis_mae[2]),
            noise.mae,
            area.clamped.mae,
            of_point(&|p| format!("{:.4}", p.clamped.mae)),
            area.metrics.mse,
            of_point(&|p| format!("{:.5}", p.metrics.mse)),
            t.thesis_mse_area,
            passes_text(&area.passes),
            of_point(&|p| passes_text(&p.passes)),
        );
    }
    text
}
