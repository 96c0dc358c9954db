//! Convergence: the error of a static camera's accumulated image after 1, 2, 4, ... N frames, per method, each
//! point at its cumulative frame time (frames x the method's measured frame time). The equal-time ratios are read
//! off these curves: each method's error at the time NEE took for its last point, and the time each method needs
//! to reach NEE's last error (log-log interpolation between the two points around it).

use super::sweep::EQUAL_TIME_TO;
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::LinearImage;
use crate::reference::flip::{Encoding, flip};
use crate::reference::metrics::{Metrics, compare};
use crate::settings::RenderSettings;
use crate::world::{CameraView, VoxelWorld};

/// A method drawn as a curve: its bench setting (whose frame time it uses) and its render pairs.
pub struct Method {
    pub name: &'static str,
    pub setting: &'static str,
    pub pairs: &'static [&'static str],
}

/// NEE, then Voxel ReSTIR with each reuse weighting (the default, `one-ray`, first). (The GI cache is not drawn: these are direct-light curves
/// against a direct-light reference; `bench --gi` measures it against a path-traced one.)
pub const METHODS: &[Method] = &[
    Method { name: "nee", setting: "nee-power", pairs: &["lighting=nee", "pick=power"] },
    Method { name: "restir", setting: EQUAL_TIME_TO, pairs: &["lighting=restir"] },
    Method { name: "restir-biased", setting: "restir-biased", pairs: &["lighting=restir", "reuse=biased"] },
    Method { name: "restir-unbiased", setting: "restir-unbiased", pairs: &["lighting=restir", "reuse=unbiased"] },
];

/// One point of a curve.
#[derive(Clone, Debug)]
pub struct CurvePoint {
    pub scene: String,
    pub method: &'static str,
    /// Frames accumulated in the image.
    pub frames: u32,
    /// Cumulative time: frames x the method's frame time.
    pub ms: f64,
    pub metrics: Metrics,
    pub flip: f64,
}

/// What a curve renders: its name in the plot and its `--set` pairs (accumulation is added).
pub struct CurveSpec<'a> {
    pub name: &'static str,
    pub pairs: &'a [String],
    /// The method's frame time (from the bench's one-frame rows): a point's time is frames x this.
    pub frame_ms: f64,
    /// Image size.
    pub size: (u32, u32),
    /// Frames of the longest point (points read 1, 2, 4, ... up to it).
    pub frames: u32,
}

/// The points of one method on one scene: accumulation from the first frame, images read at about powers of two.
pub fn measure_curve(
    world: &VoxelWorld,
    view: &CameraView,
    spec: &CurveSpec,
    reference: &LinearImage,
    scene: &str,
) -> Result<Vec<CurvePoint>, String> {
    let mut pairs = spec.pairs.to_vec();
    pairs.push("accumulate=on".into());
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width: spec.size.0, height: spec.size.1, settings, ..Default::default() };
    let mut renderer = HeadlessRenderer::new(world.clone(), view, &options)?;
    let mut points = Vec::new();
    let mut goal = 1u32;
    while goal <= spec.frames.max(1) {
        let before = renderer.camera_frames_rendered();
        let image = renderer.render(goal.saturating_sub(before).max(1))?;
        // The readback lands a frame or two after the goal: the image holds every frame rendered so far.
        let frames = renderer.camera_frames_rendered().max(1);
        let metrics = compare(&image, reference)?;
        let flip = flip(&image, Encoding::Linear, reference, Encoding::Linear)?.mean;
        points.push(CurvePoint {
            scene: scene.to_string(),
            method: spec.name,
            frames,
            ms: frames as f64 * spec.frame_ms,
            metrics,
            flip,
        });
        goal = (frames + 1).next_power_of_two().max(goal * 2);
    }
    Ok(points)
}

/// relMSE of a curve at time `ms`, interpolated log-log; `None` outside the curve.
pub fn error_at(curve: &[&CurvePoint], ms: f64) -> Option<f64> {
    curve.windows(2).find(|w| w[0].ms <= ms && ms <= w[1].ms).map(|w| {
        let t = (ms.ln() - w[0].ms.ln()) / (w[1].ms.ln() - w[0].ms.ln()).max(1e-12);
        (w[0].metrics.relmse.ln() * (1.0 - t) + w[1].metrics.relmse.ln() * t).exp()
    })
}

/// Time a curve takes to reach relMSE `target`, interpolated log-log; `None` if it never does within the curve.
pub fn time_to(curve: &[&CurvePoint], target: f64) -> Option<f64> {
    if let Some(first) = curve.first().filter(|p| p.metrics.relmse <= target) {
        return Some(first.ms);
    }
    curve.windows(2).find(|w| w[0].metrics.relmse > target && w[1].metrics.relmse <= target).map(|w| {
        let (e0, e1) = (w[0].metrics.relmse.ln(), w[1].metrics.relmse.ln());
        let t = (target.ln() - e0) / (e1 - e0).min(-1e-12);
        (w[0].ms.ln() * (1.0 - t) + w[1].ms.ln() * t).exp()
    })
}

/// The report's equal-time table: per scene and method, relMSE at the baseline's last time and the time to the
/// baseline's last error, with the ratios to it. The baseline is each scene's first curve (NEE).
pub fn equal_time_table(points: &[CurvePoint]) -> String {
    let mut text = String::from(
        "| scene | method | relMSE at the baseline's time | baseline / method | ms to the baseline's relMSE | \
         baseline ms / method ms |\n\
         |---|---|---|---|---|---|\n",
    );
    let mut scenes: Vec<&str> = points.iter().map(|p| p.scene.as_str()).collect();
    scenes.dedup();
    for scene in scenes {
        let curve = |method: &str| -> Vec<&CurvePoint> {
            points.iter().filter(|p| p.scene == scene && p.method == method).collect()
        };
        let Some(first) = points.iter().find(|p| p.scene == scene) else { continue };
        let nee = curve(first.method);
        let Some(last) = nee.last() else { continue };
        let mut methods: Vec<&str> = points.iter().filter(|p| p.scene == scene).map(|p| p.method).collect();
        methods.dedup();
        for method in methods {
            let c = curve(method);
            let at = error_at(&c, last.ms);
            let to = time_to(&c, last.metrics.relmse);
            let fmt = |v: Option<f64>, digits: usize| v.map_or("beyond the curve".into(), |v| format!("{v:.digits$}"));
            text += &format!(
                "| {scene} | {} | {} | {} | {} | {} |\n",
                method,
                fmt(at, 5),
                fmt(at.map(|e| last.metrics.relmse / e), 1),
                fmt(to, 1),
                fmt(to.map(|t| last.ms / t), 1),
            );
        }
    }
    text
}
