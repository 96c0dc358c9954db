//! The denoiser bench (`glowbrick bench --denoise`): one real-time frame of the game's lighting (`lighting=full`
//! with the GI cache) raw and denoised against a converged reference on four scenes; what the filter does to
//! the mean once frames accumulate; how much a still view flickers; how many frames a lamp switched off or on
//! takes to show (`reaction`); what the passes cost at 320x180 and 1280x720; and ghosting under motion (`motion`).
//! Writes `denoise.md`, or one section alone into its own file.

use super::motion::{motion_markdown, run_motion};
use super::reaction::{Reaction, reaction_markdown, reactions};
use super::reference_cache::{Reference, ReferenceCache};
use super::{direct_light_ms, mean_metrics};
use crate::colour::luminance;
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::LinearImage;
use crate::lights::daylight::{DEFAULT_HOURS, Daylight};
use crate::reference::REFERENCE_BOUNCES;
use crate::reference::metrics::{Metrics, compare};
use crate::render::adapter::adapter_name;
use crate::render::denoise::DENOISE_PASS_NAMES;
use crate::render::gi::GI_PASS_NAMES;
use crate::settings::RenderSettings;
use crate::world::recipe::load_scene;
use crate::world::{CameraView, VoxelWorld};
use std::path::Path;
use std::time::Instant;

/// Scenes and views: the window room, the cornell box, the letters, the apartments (first view where `None`).
const SCENES: [(&str, Option<&str>); 4] =
    [("window-room", Some("inside")), ("cornell", Some("front")), ("letters", None), ("apartments", None)];
/// `--scenes`: each must be one of `SCENES` (a typo would otherwise measure nothing); `--upscale` measures the
/// frame profile's scenes instead.
pub fn check_scenes(scenes: &[String], section: Option<DenoiseSection>) -> Result<(), String> {
    if section == Some(DenoiseSection::Upscale) {
        return super::upscale::pick_scenes(scenes).map(|_| ());
    }
    match scenes.iter().find(|s| !SCENES.iter().any(|(known, _)| known == s)) {
        Some(unknown) => {
            let known: Vec<&str> = SCENES.iter().map(|(s, _)| *s).collect();
            Err(format!("the denoiser bench has no scene '{unknown}' (it measures {})", known.join(", ")))
        }
        None => Ok(()),
    }
}

/// What `bench --denoise` runs.
#[derive(Clone, Debug)]
pub struct DenoiseConfig {
    /// The image size of the one-frame and reaction measures.
    pub width: u32,
    pub height: u32,
    pub reference_spp: u32,
    /// One section alone, or all of them.
    pub section: Option<DenoiseSection>,
    /// Independent realisations (the `seed` setting 0..N) each measure averages.
    pub seeds: u32,
    /// `--set KEY=VALUE`: settings on top of each measure's own (e.g. `gi_qmc=off` to compare).
    pub settings: Vec<String>,
    /// The one-frame measure's reference and errors at every n-th pixel in each direction only
    /// (`Reference::lattice`; 1: every pixel), so a game's size stays affordable.
    pub lattice: u32,
    /// Only these of the one-frame scenes (empty: all four).
    pub scenes: Vec<String>,
    /// The cost section's sizes (empty: `COST_SIZES`).
    pub cost_sizes: Vec<(u32, u32)>,
}

impl DenoiseConfig {
    /// The whole bench at `width` x `height`, one seed, with `reference_spp` samples per pixel in the references.
    pub fn new(width: u32, height: u32, reference_spp: u32) -> Self {
        DenoiseConfig {
            width,
            height,
            reference_spp,
            section: None,
            seeds: 1,
            settings: Vec::new(),
            lattice: 1,
            scenes: Vec::new(),
            cost_sizes: Vec::new(),
        }
    }
}

/// A section of the bench that runs alone, into its own report.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DenoiseSection {
    /// `--one-frame`: denoise-frame.md.
    Frame,
    /// `--reaction`: denoise-reaction.md.
    Reaction,
    /// `--cost`: denoise-cost.md.
    Cost,
    /// `--motion`: denoise-motion.md.
    Motion,
    /// `--upscale`: upscale-frame.md (the game's frame at each render scale; `super::upscale`).
    Upscale,
}

/// Frames for the GI cache (and the denoiser's history) to settle, frames whose changes are averaged for the
/// flicker, frames accumulated for the bias.
pub(crate) const SETTLE_FRAMES: u32 = 64;
const FLICKER_FRAMES: u32 = 8;
pub(crate) const ACCUMULATED_FRAMES: u32 = 64;
/// The cost section's sizes, unless `--sizes` names others.
const COST_SIZES: &[(u32, u32)] = &[(320, 180), (1280, 720)];
/// The game's frame.
const GAME: [&str; 2] = ["lighting=full", "gi=on"];

struct SceneRow {
    scene: &'static str,
    raw: Metrics,
    denoised: Metrics,
    raw_accumulated: Metrics,
    denoised_accumulated: Metrics,
    raw_flicker: f64,
    denoised_flicker: f64,
    mean: f64,
    /// The reference's own error (the two seeds' mean: see `ReferenceCache::two_seeds`).
    noise: Metrics,
}

struct CostRow {
    size: (u32, u32),
    raw_ms: f64,
    denoised_ms: f64,
    /// GPU ms of each denoiser pass (None without timestamps).
    passes: Vec<Option<f64>>,
    /// GPU ms of the rest of the denoised frame: primary + ReSTIR's three passes, and the GI cache's passes
    /// (None without timestamps).
    direct_ms: Option<f64>,
    gi_ms: Option<f64>,
}

/// The game's frame with `pairs` and the run's `--set` pairs on top.
pub(crate) fn renderer(
    world: &VoxelWorld,
    view: &CameraView,
    size: (u32, u32),
    pairs: &[&str],
    extra: &[String],
) -> Result<HeadlessRenderer, String> {
    // The game's frame, then the measure's own pairs, then the run's `--set` pairs.
    let pairs: Vec<String> = GAME.iter().chain(pairs).map(|p| p.to_string()).chain(extra.iter().cloned()).collect();
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width: size.0, height: size.1, settings, ..Default::default() };
    HeadlessRenderer::new(world.clone(), view, &options)
}

/// Mean absolute luminance change between consecutive frames of a still view.
fn flicker(r: &mut HeadlessRenderer, frames: u32) -> Result<f64, String> {
    let mut previous = r.render_next()?;
    let mut sum = 0.0;
    for _ in 0..frames {
        let now = r.render_next()?;
        let change: f64 = previous
            .pixels
            .iter()
            .zip(&now.pixels)
            .map(|(a, b)| (luminance([a[0], a[1], a[2]]) - luminance([b[0], b[1], b[2]])).abs() as f64)
            .sum();
        sum += change / now.pixels.len() as f64;
        previous = now;
    }
    Ok(sum / frames as f64)
}

/// One frame, the flicker and the accumulated image of one setting against `truth`: each the mean over the
/// config's seeds (independent realisations).
fn measure(
    world: &VoxelWorld,
    view: &CameraView,
    config: &DenoiseConfig,
    truth: &LinearImage,
    denoise: &str,
) -> Result<(Metrics, f64, Metrics), String> {
    let mut singles = Vec::new();
    let mut flickers = 0.0;
    let mut accumulated = Vec::new();
    // The frames are whole; the reference may hold only the lattice's pixels (flicker needs no reference).
    let against_truth = |image: LinearImage| {
        let measured = if config.lattice > 1 { image.lattice(config.lattice) } else { image };
        compare(&measured, truth)
    };
    for seed in 0..config.seeds {
        let seed = format!("seed={seed}");
        let mut r = renderer(world, view, (config.width, config.height), &[denoise, &seed], &config.settings)?;
        r.render(SETTLE_FRAMES)?;
        singles.push(against_truth(r.render_next()?)?);
        flickers += flicker(&mut r, FLICKER_FRAMES)?;
        r.app_mut().world_mut().resource_mut::<RenderSettings>().accumulate = true;
        accumulated.push(against_truth(r.render(ACCUMULATED_FRAMES)?)?);
    }
    Ok((mean_metrics(&singles), flickers / config.seeds.max(1) as f64, mean_metrics(&accumulated)))
}

fn measure_scene(scene: &'static str, view: Option<&str>, config: &DenoiseConfig) -> Result<SceneRow, String> {
    let world = load_scene(scene).map_err(|e| e.to_string())?;
    let view = world.view(view).cloned().ok_or_else(|| format!("{scene}: no such view"))?;
    let what = Reference {
        bounces: REFERENCE_BOUNCES,
        daylight: Some(Daylight::at(DEFAULT_HOURS, true)),
        lattice: (config.lattice > 1).then_some(config.lattice),
        indirect: false,
    };
    let references = ReferenceCache::new(config.width, config.height, config.reference_spp);
    let (truth, noise) = references.two_seeds(&world, &view, &what)?;
    let (raw, raw_flicker, raw_accumulated) = measure(&world, &view, config, &truth, "denoise=off")?;
    let (denoised, denoised_flicker, denoised_accumulated) = measure(&world, &view, config, &truth, "denoise=on")?;
    Ok(SceneRow {
        scene,
        raw,
        denoised,
        raw_accumulated,
        denoised_accumulated,
        raw_flicker,
        denoised_flicker,
        mean: truth.mean_luminance(),
        noise,
    })
}

fn cost(size: (u32, u32)) -> Result<CostRow, String> {
    let world = load_scene("cornell").map_err(|e| e.to_string())?;
    let view = world.view(Some("front")).cloned().ok_or("cornell: no view 'front'")?;
    let time = |denoise: &str| -> Result<(f64, HeadlessRenderer), String> {
        let mut r = renderer(&world, &view, size, &[denoise], &[])?;
        // Past the GI cache's warm-up (four update iterations a frame): a settled frame is what the filter's
        // share is of.
        r.render(crate::render::gi::WARM_UP_FRAMES + 8)?;
        let start = Instant::now();
        for _ in 0..8 {
            r.step();
        }
        Ok((start.elapsed().as_secs_f64() * 1000.0 / 8.0, r))
    };
    let (raw_ms, _) = time("denoise=off")?;
    let (denoised_ms, r) = time("denoise=on")?;
    Ok(CostRow {
        size,
        raw_ms,
        denoised_ms,
        passes: DENOISE_PASS_NAMES.iter().map(|n| r.gpu_pass_ms(n)).collect(),
        direct_ms: direct_light_ms(&r),
        gi_ms: GI_PASS_NAMES.iter().filter_map(|n| r.gpu_pass_ms(n)).reduce(|a, b| a + b),
    })
}

/// Runs the bench at the config's size, writes `denoise.md` into `out` and returns its text.
pub fn run_denoise_bench(config: &DenoiseConfig, out: &Path) -> Result<String, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let only = |section| config.section == Some(section);
    if only(DenoiseSection::Reaction) {
        let text = format!(
            "# The denoiser's reaction to a change of light\n{}",
            reaction_markdown(&reactions(config)?, config.seeds)
        );
        return write_report(out, "denoise-reaction.md", text);
    }
    if only(DenoiseSection::Upscale) {
        let cases = super::upscale::pick_scenes(&config.scenes)?;
        let scenes = super::upscale::run_upscale(config, &cases)?;
        return write_report(out, "upscale-frame.md", super::upscale::upscale_markdown(&scenes, config));
    }
    let motion = || run_motion((config.width, config.height), config.reference_spp, &config.settings);
    if only(DenoiseSection::Motion) {
        let run = motion()?;
        super::motion::write_snapshots(&run, out)?;
        let text = format!("# The denoiser under motion\n{}", motion_markdown(&run));
        return write_report(out, "denoise-motion.md", text);
    }
    let costs = || -> Result<Vec<CostRow>, String> {
        let sizes = if config.cost_sizes.is_empty() { COST_SIZES } else { &config.cost_sizes };
        sizes.iter().map(|&size| cost(size)).collect()
    };
    if only(DenoiseSection::Cost) {
        let text = format!("# The denoiser's cost\n{}", cost_markdown(&costs()?, &adapter_name()));
        return write_report(out, "denoise-cost.md", text);
    }
    let mut rows = Vec::new();
    for (scene, view) in
        SCENES.into_iter().filter(|(s, _)| config.scenes.is_empty() || config.scenes.iter().any(|c| c == s))
    {
        let row = measure_scene(scene, view, config)?;
        eprintln!("denoise bench: {scene}: raw {} / denoised {}", row.raw, row.denoised);
        rows.push(row);
    }
    if only(DenoiseSection::Frame) {
        let text = format!("# The denoiser on one frame\n\n{}", frame_markdown(&rows, config));
        return write_report(out, "denoise-frame.md", text);
    }
    let reaction = reactions(config)?;
    eprintln!("denoise bench: reaction {}", reaction_markdown(&reaction, config.seeds));
    let costs = costs()?;
    let motion = motion()?;
    let text = markdown(&rows, &reaction, &costs, config) + &motion_markdown(&motion);
    write_report(out, "denoise.md", text)
}

/// Writes a report into `out` and returns its text.
fn write_report(out: &Path, name: &str, text: String) -> Result<String, String> {
    let path = out.join(name);
    std::fs::write(&path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(text)
}

/// The cost section: the frame with and without the filter, each denoiser pass's GPU time, and the GPU time of
/// the frame's other passes beside them.
fn cost_markdown(costs: &[CostRow], adapter: &str) -> String {
    let mut text = format!(
        "\n## Cost\n\ncornell, the game's frame, on {adapter}: mean wall time of 8 frames after the GI cache's \
         warm-up, the GPU time of each denoiser pass (timestamp queries), and the GPU time of the denoised frame's \
         other passes (direct = primary + ReSTIR's three; GI = the cache's four). The GPU share is the \
         denoiser's passes over all the timed passes (wall time also holds the CPU's part of a frame and the \
         read-back).\n\n| size | frame ms raw | frame ms denoised | share of the frame | temporal | wavelet 1 \
         | 2 | 4 | 8 | 16 + write | GPU ms direct | GPU ms GI | GPU share |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    let ms = |v: Option<f64>| v.map_or("-".to_string(), |ms| format!("{ms:.2}"));
    for c in costs {
        let passes: Vec<String> = c.passes.iter().map(|&p| ms(p)).collect();
        let denoiser: f64 = c.passes.iter().flatten().sum();
        let gpu_share = match (c.direct_ms, c.gi_ms) {
            (Some(direct), gi) if denoiser > 0.0 => {
                format!("{:.0}%", 100.0 * denoiser / (denoiser + direct + gi.unwrap_or(0.0)))
            }
            _ => "-".into(),
        };
        text += &format!(
            "| {}x{} | {:.1} | {:.1} | {:.0}% | {} | {} | {} | {} |\n",
            c.size.0,
            c.size.1,
            c.raw_ms,
            c.denoised_ms,
            100.0 * (c.denoised_ms - c.raw_ms) / c.denoised_ms.max(1e-9),
            passes.join(" | "),
            ms(c.direct_ms),
            ms(c.gi_ms),
            gpu_share
        );
    }
    text
}

/// Where the one-frame errors were measured, when not on every pixel.
fn lattice_note(config: &DenoiseConfig) -> String {
    if config.lattice <= 1 {
        return String::new();
    }
    let step = config.lattice;
    format!(
        " Errors (and the reference) on every {step}th pixel in each direction only (`--lattice {step}`: {}x{} \
         pixels, an unbiased estimate of the whole frame's error at 1/{} of the reference's cost); the frames and \
         the flicker are whole.",
        config.width / step,
        config.height / step,
        step * step
    )
}

/// The one-frame section: error raw and denoised, the bias the filter adds, flicker.
fn frame_markdown(rows: &[SceneRow], config: &DenoiseConfig) -> String {
    let mut text = format!(
        "`glowbrick bench --denoise`: {}x{}, the game's \
         frame (`lighting=full gi=on`, time {DEFAULT_HOURS} h), {SETTLE_FRAMES} frames to settle, then one frame, \
         {FLICKER_FRAMES} frame-to-frame changes and {ACCUMULATED_FRAMES} accumulated frames, raw (`denoise=off`) \
         and denoised, each the mean over {} seed(s) (`seed=0..`: independent realisations of the renderer's \
         noise), against a CPU reference with {REFERENCE_BOUNCES} bounces: the mean of two of {} spp with \
         different seeds. The reference's own error is estimated from their difference (MAE halved, relMSE \
         quartered); the last column is the ratio of the two relMSEs with that share taken out of both (the \
         frame's and the reference's errors are independent, so their squared errors add).{}\n\n## One frame\n\n\
         | scene | raw MAE | raw relMSE | raw bias | denoised MAE | denoised relMSE | denoised bias | relMSE raw / \
         denoised | reference's MAE | reference's relMSE | raw / denoised, reference's share out |\n\
         |---|---|---|---|---|---|---|---|---|---|---|\n",
        config.width,
        config.height,
        config.seeds,
        config.reference_spp,
        lattice_note(config)
    );
    for r in rows {
        let own = r.noise.relmse;
        let corrected = if r.denoised.relmse > 1.5 * own {
            format!("{:.1}x", (r.raw.relmse - own) / (r.denoised.relmse - own))
        } else {
            format!("> {:.1}x (denoised within 1.5x of the reference's own)", (r.raw.relmse - own) / (0.5 * own))
        };
        text += &format!(
            "| {} | {:.5} | {:.4} | {:+.5} | {:.5} | {:.4} | {:+.5} | {:.1}x | {:.5} | {:.4} | {} |\n",
            r.scene,
            r.raw.mae,
            r.raw.relmse,
            r.raw.bias,
            r.denoised.mae,
            r.denoised.relmse,
            r.denoised.bias,
            r.raw.relmse / r.denoised.relmse.max(1e-12),
            r.noise.mae,
            own,
            corrected
        );
    }
    text += &format!(
        "\n## What the filter does to the mean, and flicker\n\nBias of the accumulated images against the \
         reference; the filter's own bias is the difference, as a share of the reference's mean. Flicker: the \
         mean absolute luminance change between consecutive frames of the still view. The accumulated raw \
         image's relMSE is the renderer's error with most of its frame-to-frame noise averaged away: what is \
         left is its bias, slow noise (the GI cache's) and 1/{ACCUMULATED_FRAMES} of its fireflies, so a \
         denoised frame may read lower.\n\n| scene | raw bias (accumulated) | denoised bias | added by the \
         filter | raw flicker | denoised flicker | raw relMSE (accumulated) |\n|---|---|---|---|---|---|---|\n"
    );
    for r in rows {
        text += &format!(
            "| {} | {:+.5} | {:+.5} | {:+.2}% | {:.5} | {:.5} | {:.5} |\n",
            r.scene,
            r.raw_accumulated.bias,
            r.denoised_accumulated.bias,
            100.0 * (r.denoised_accumulated.bias - r.raw_accumulated.bias) / r.mean.max(1e-12),
            r.raw_flicker,
            r.denoised_flicker,
            r.raw_accumulated.relmse
        );
    }
    text
}

fn markdown(rows: &[SceneRow], reaction: &[Reaction], costs: &[CostRow], config: &DenoiseConfig) -> String {
    let mut text =
        format!("# The denoiser: error, bias, flicker, reaction and cost\n\n{}", frame_markdown(rows, config));
    text += &reaction_markdown(reaction, config.seeds);
    text += &cost_markdown(costs, &adapter_name());
    text
}
