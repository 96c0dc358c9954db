//! The equal-time comparison of the settings sweep (`sweep.rs`): NEE accumulated for the time one ReSTIR frame
//! takes, against ReSTIR's one frame, each as an expected error over several independent draws; and the report's
//! table of it.

use super::mean_metrics;
use super::same_hit;
use super::sweep::{EQUAL_TIME_TO, SweepConfig};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::LinearImage;
use crate::reference::flip::{Encoding, flip};
use crate::reference::metrics::{Metrics, compare};
use crate::settings::RenderSettings;
use crate::world::{CameraView, VoxelWorld};

/// Independent draws the equal-time comparison averages. One accumulation's relMSE is heavy-tailed (a rare
/// firefly moves it several times over), so the ratio of two single draws swings from run to run; the mean of
/// several draws estimates the expected error a player gets.
pub(crate) const EQUAL_TIME_TRIALS: u32 = 8;

/// The mean error of `images` against `reference`, over all pixels and over the pixels of `keep`.
pub(crate) fn expected_errors(
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
pub(crate) struct EqualTime {
    pub frames: u32,
    /// The first average (the row of the table) and its FLIP.
    pub first: Metrics,
    pub flip: f64,
    /// The mean error over the trials, over all pixels and over the pixels of `keep`.
    pub expected: Metrics,
    pub expected_kept: Metrics,
}

pub(crate) fn measure_equal_time(
    world: &VoxelWorld,
    view: &CameraView,
    config: &SweepConfig,
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
    // Warm up as the timed settings do: a sequence read from a new renderer's first frame can catch a frame with
    // no light yet, which darkens the first average.
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
pub(crate) struct EqualTimeRow {
    pub scene: String,
    pub nee_frames: u32,
    pub nee: Metrics,
    pub restir: Metrics,
    /// The same over the pixels whose camera ray hits the same voxel face on the GPU and the CPU
    /// (`same_hit`), and how many pixels that leaves out.
    pub nee_kept: Metrics,
    pub restir_kept: Metrics,
    pub left_out: usize,
}

/// The expected equal-time comparison: the ratio of the mean errors, each over `EQUAL_TIME_TRIALS` draws.
pub(crate) fn equal_time_markdown(rows: &[EqualTimeRow]) -> String {
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
