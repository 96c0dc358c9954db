//! The GI cache bench (`glowbrick bench --gi`): error against time for K in {16, 32, 64, 128}, with and without
//! the static visibility cache (without it every update traces its rays against the static world again), without
//! the filter and with one bounce; the cost of an edit against the entries it reaches; memory per entry. Direct
//! light is NEE in every row, so the rows differ only in the indirect light. Error against an 8-bounce CPU path
//! tracer; GPU ms from timestamp queries. Then convergence curves with and without the cache (`gi-plot.svg`):
//! the error against that reference as a still camera accumulates frames from a cold cache.

use super::convergence::{CurvePoint, CurveSpec, equal_time_table, measure_curve};
use super::plot;
use super::reference_cache::{Reference, ReferenceCache};
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::reference::REFERENCE_BOUNCES;
use crate::reference::metrics::{Metrics, compare};
use crate::render::gi::{ENTRY_BYTES, GI_PASS_NAMES, RAY_BYTES, cache_bytes};
use crate::render::gpu_types::GpuCounter;
use crate::render::primary::PRIMARY_PASS_NAME;
use crate::settings::RenderSettings;
use crate::world::events::EditRequest;
use crate::world::recipe::load_scene;
use crate::world::{CameraView, Edit, VoxelWorld};
use bevy::math::IVec3;
use std::path::Path;
use std::time::Instant;

/// What `bench --gi` runs.
#[derive(Clone, Debug)]
pub struct GiConfig {
    pub width: u32,
    pub height: u32,
    pub reference_spp: u32,
    /// Frames of the longest convergence point.
    pub curve_frames: u32,
    /// `--game-sizes`: only the section at game sizes.
    pub game_sizes_only: bool,
    /// `--sizes`: that section's sizes (empty: `gi_scale::SIZES`).
    pub sizes: Vec<(u32, u32)>,
}

impl GiConfig {
    /// The whole bench at its own size, with `reference_spp` samples per pixel in the references.
    pub fn new(reference_spp: u32) -> Self {
        GiConfig { width: 128, height: 72, reference_spp, curve_frames: 128, game_sizes_only: false, sizes: Vec::new() }
    }
}

/// (row name, `--set` pairs) of the GI rows; each adds to NEE direct light with alpha 0.1.
const ROWS: &[(&str, &[&str])] = &[
    ("direct only", &["gi=off"]),
    ("fresh directions", &["gi=on"]),
    ("fresh, random rays", &["gi=on", "gi_qmc=off"]),
    ("cached, K=16", &["gi=on", "gi_cached_hits=on", "gi_cached_rays=16"]),
    ("cached, K=32", &["gi=on", "gi_cached_hits=on", "gi_cached_rays=32"]),
    ("cached, K=64", &["gi=on", "gi_cached_hits=on", "gi_cached_rays=64"]),
    ("cached, K=128", &["gi=on", "gi_cached_hits=on", "gi_cached_rays=128"]),
    ("no filter", &["gi=on", "gi_filter=off"]),
    ("one bounce", &["gi=on", "gi_bounces=off"]),
];

/// Scenes (and views) of the GI bench: the window room lit through its window, the cornell box.
const SCENES: &[(&str, &str)] = &[("window-room", "inside"), ("cornell", "front")];

/// The curves: (name, row whose frame time they use); their pairs are the row's.
const CURVES: &[(&str, &str)] = &[("nee, direct only", "direct only"), ("nee + GI cache", "fresh directions")];

/// Frames for the cache to settle (alpha 0.1: about ten frames per bounce), frames timed, frames averaged.
const SETTLE_FRAMES: u32 = 100;
const TIMED_FRAMES: u32 = 24;
const AVERAGED_FRAMES: u32 = 64;

struct GiRow {
    scene: &'static str,
    name: &'static str,
    frame_ms: f64,
    primary_ms: Option<f64>,
    /// Refresh, update and filter GPU ms (None where the pass did not run).
    gi_ms: [Option<f64>; 4],
    metrics: Metrics,
    live: u32,
    megabytes: f64,
}

fn renderer(
    world: &VoxelWorld,
    view: &CameraView,
    config: &GiConfig,
    pairs: &[&str],
) -> Result<HeadlessRenderer, String> {
    let pairs: Vec<String> = ["lighting=nee", "gi_alpha=0.1"].iter().chain(pairs).map(|p| p.to_string()).collect();
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width: config.width, height: config.height, settings, ..Default::default() };
    HeadlessRenderer::new(world.clone(), view, &options)
}

fn set_accumulate(r: &mut HeadlessRenderer, on: bool) {
    r.app_mut().world_mut().resource_mut::<RenderSettings>().accumulate = on;
}

fn measure_row(
    scene: &'static str,
    (name, pairs): (&'static str, &[&str]),
    world: &VoxelWorld,
    view: &CameraView,
    config: &GiConfig,
    reference: &crate::image_io::LinearImage,
) -> Result<GiRow, String> {
    let mut r = renderer(world, view, config, pairs)?;
    r.render(SETTLE_FRAMES)?;
    let start = Instant::now();
    for _ in 0..TIMED_FRAMES {
        r.step();
    }
    let frame_ms = start.elapsed().as_secs_f64() * 1000.0 / TIMED_FRAMES as f64;
    let gi_ms = GI_PASS_NAMES.map(|n| r.gpu_pass_ms(n));
    let primary_ms = r.gpu_pass_ms(PRIMARY_PASS_NAME);
    let live = r.counters()?[GpuCounter::GiLive as usize];
    set_accumulate(&mut r, true);
    let image = r.render(AVERAGED_FRAMES)?;
    let settings = RenderSettings::default().with_pairs(&pairs.iter().map(|p| p.to_string()).collect::<Vec<_>>())?;
    Ok(GiRow {
        scene,
        name,
        frame_ms,
        primary_ms,
        gi_ms,
        metrics: compare(&image, reference)?,
        live,
        megabytes: cache_bytes(&settings.gi) as f64 / (1024.0 * 1024.0),
    })
}

/// One edit's cost: entries alive, entries with a ray traced again, rays traced again.
struct EditCost {
    label: &'static str,
    live: u32,
    retraced: u32,
    rays: u32,
}

/// Edits of growing size in the window room, each measured in the frame it reaches the cache.
fn measure_edits(world: &VoxelWorld, view: &CameraView, config: &GiConfig) -> Result<Vec<EditCost>, String> {
    // The static visibility cache on: what is measured is how few of its cached hits an edit retraces.
    let mut r = renderer(world, view, config, &["gi=on", "gi_cached_hits=on", "gi_cached_rays=64"])?;
    r.render(SETTLE_FRAMES / 2)?;
    let white = world.palette.id_of("plaster").unwrap_or(1);
    let edits: [(&'static str, Edit); 4] = [
        ("one voxel on the floor", Edit::Place { at: IVec3::new(32, 2, 32), material: white }),
        ("a 4^3 block", Edit::FillBox { min: IVec3::new(20, 2, 20), max: IVec3::new(23, 5, 23), material: white }),
        (
            "a 16 x 8 x 1 wall",
            Edit::FillBox { min: IVec3::new(24, 2, 40), max: IVec3::new(39, 9, 40), material: white },
        ),
        ("a voxel in a far corner", Edit::Place { at: IVec3::new(3, 28, 3), material: white }),
    ];
    let mut costs = Vec::new();
    for (label, edit) in edits {
        r.app_mut().world_mut().write_message(EditRequest::player(edit));
        let c = r.counters()?;
        costs.push(EditCost {
            label,
            live: c[GpuCounter::GiLive as usize],
            retraced: c[GpuCounter::GiRetraced as usize],
            rays: c[GpuCounter::GiRaysTraced as usize],
        });
        r.render(4)?;
    }
    Ok(costs)
}

fn ms(v: Option<f64>) -> String {
    v.map_or("-".into(), |v| format!("{v:.1}"))
}

/// Runs the GI bench at the config's size, writes `gi.md` into `out` and returns its text.
pub fn run_gi_bench(config: &GiConfig, out: &Path) -> Result<String, String> {
    if config.game_sizes_only {
        let sizes = if config.sizes.is_empty() { super::gi_scale::SIZES } else { &config.sizes };
        let text =
            format!("# GI cache at game sizes\n{}", super::gi_scale::markdown(&super::gi_scale::measure_all(sizes)?));
        std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
        let path = out.join("gi-scale.md");
        std::fs::write(&path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
        return Ok(text);
    }
    let mut rows = Vec::new();
    let mut curves: Vec<CurvePoint> = Vec::new();
    let mut edit_costs = Vec::new();
    let references = ReferenceCache::new(config.width, config.height, config.reference_spp);
    for &(scene, view_name) in SCENES {
        let world = load_scene(scene).map_err(|e| e.to_string())?;
        let view = world.view(Some(view_name)).cloned().ok_or_else(|| format!("{scene}: no view {view_name}"))?;
        let reference = references.image(&world, &view, &Reference::bounces(REFERENCE_BOUNCES))?;
        for &row in ROWS {
            let measured = measure_row(scene, row, &world, &view, config, &reference)?;
            eprintln!("gi bench: {scene} {}: {} ({:.0} ms/frame)", row.0, measured.metrics, measured.frame_ms);
            rows.push(measured);
        }
        for &(name, row) in CURVES {
            let (Some(&(_, row_pairs)), Some(measured)) = (
                ROWS.iter().find(|(n, _)| *n == row),
                rows.iter().find(|r: &&GiRow| r.scene == scene && r.name == row),
            ) else {
                continue;
            };
            let pairs: Vec<String> =
                ["lighting=nee", "gi_alpha=0.1"].iter().chain(row_pairs).map(|p| p.to_string()).collect();
            let spec = CurveSpec {
                name,
                pairs: &pairs,
                frame_ms: measured.frame_ms,
                size: (config.width, config.height),
                frames: config.curve_frames,
            };
            let points = measure_curve(&world, &view, &spec, &reference, scene)?;
            eprintln!("gi bench: {scene} {name} accumulated: {} points", points.len());
            curves.extend(points);
        }
        if scene == "window-room" {
            edit_costs = measure_edits(&world, &view, config)?;
        }
    }
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    plot::write_plot(&[], &curves, &out.join("gi-plot.svg"))?;
    let mut text = markdown(&rows, &edit_costs, config);
    text += &super::gi_scale::markdown(&super::gi_scale::measure_all(super::gi_scale::SIZES)?);
    text += &format!(
        "\n## Convergence with and without the cache\n\nA still camera accumulating frames from a cold cache \
         (`accumulate=on`), error against the {REFERENCE_BOUNCES}-bounce reference after about 1, 2, 4, ... {} \
         frames, at frames x the row's frame time. Without the cache the error levels off at the missing indirect \
         light; with it, it keeps falling once the cache has settled. ![convergence](gi-plot.svg)\n\n{}\n\
         | scene | curve | frames | ms | MAE | relMSE | bias |\n|---|---|---|---|---|---|---|\n",
        config.curve_frames,
        equal_time_table(&curves)
    );
    for p in &curves {
        text += &format!(
            "| {} | {} | {} | {:.1} | {:.5} | {:.5} | {:+.5} |\n",
            p.scene, p.method, p.frames, p.ms, p.metrics.mae, p.metrics.relmse, p.metrics.bias
        );
    }
    let path = out.join("gi.md");
    std::fs::write(&path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(text)
}

fn markdown(rows: &[GiRow], edits: &[EditCost], config: &GiConfig) -> String {
    let mut text = format!(
        "# GI cache: run time against error\n\n`glowbrick bench --gi`: {}x{}, NEE direct light plus the cache (alpha \
         0.1), {SETTLE_FRAMES} frames to settle, {TIMED_FRAMES} timed, then {AVERAGED_FRAMES} averaged and compared \
         with a {}-spp, {REFERENCE_BOUNCES}-bounce CPU path tracer. GPU ms are timestamp queries averaged over the \
         recent frames (lists: ageing entries and listing those due; refresh: tracing cached static hits again and \
         each entry's direct light; update: re-shading 8 rays per visible entry; \
         filter: the 3x3x3 same-orientation mean). Memory: the two tables at the given K.\n\n\
         | scene | setting | frame ms | primary ms | lists ms | refresh ms | update ms | filter ms | MAE | relMSE | \
         bias | live entries | cache MiB |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        config.width, config.height, config.reference_spp
    );
    for r in rows {
        text += &format!(
            "| {} | {} | {:.1} | {} | {} | {} | {} | {} | {:.5} | {:.5} | {:+.5} | {} | {:.1} |\n",
            r.scene,
            r.name,
            r.frame_ms,
            ms(r.primary_ms),
            ms(r.gi_ms[0]),
            ms(r.gi_ms[1]),
            ms(r.gi_ms[2]),
            ms(r.gi_ms[3]),
            r.metrics.mae,
            r.metrics.relmse,
            r.metrics.bias,
            r.live,
            r.megabytes
        );
    }
    for scene in SCENES.iter().map(|(s, _)| *s) {
        let find = |name: &str| rows.iter().find(|r| r.scene == scene && r.name == name);
        if let (Some(cached), Some(fresh)) = (find("cached, K=64"), find("fresh directions")) {
            let gi = |r: &GiRow| r.gi_ms.iter().flatten().sum::<f64>();
            text += &format!(
                "\n{scene}: caching static visibility along 64 fixed directions: GI passes {:.1} ms against {:.1} ms \
                 tracing fresh directions every update (cached / fresh {:.2}); MAE {:.5} against {:.5}.\n",
                gi(cached),
                gi(fresh),
                gi(cached) / gi(fresh).max(1e-9),
                cached.metrics.mae,
                fresh.metrics.mae
            );
        }
    }
    text += "\n## Cost of an edit (window room, `gi_cached_hits=on`, K = 64)\n\nThe frame an edit reaches the cache, only the rays whose \
             segments cross an edited brick are traced again.\n\n| edit | live entries | entries with a ray traced \
             again | rays traced again | of all cached rays |\n|---|---|---|---|---|\n";
    for e in edits {
        text += &format!(
            "| {} | {} | {} | {} | {:.1}% |\n",
            e.label,
            e.live,
            e.retraced,
            e.rays,
            100.0 * e.rays as f64 / (e.live as f64 * 64.0).max(1.0)
        );
    }
    let static_slots = crate::render::gi::static_capacity(&crate::settings::GiSettings::default());
    text += &format!(
        "\n## Memory\n\nPer entry: {ENTRY_BYTES} bytes (key, payload, blended and filtered radiance, direct light, \
         work-list slot) plus {RAY_BYTES} \
         bytes per cached ray with `gi_cached_hits=on`: {} bytes at K = 16, {} at K = 64, {} at K = 128; without (the \
         default) one placeholder ray, {} bytes. The tables hold {} static and {} dynamic entries: {:.1} MiB by \
         default, {:.1} MiB with the cache at K = 64; GI off keeps a 188-byte placeholder.\n",
        ENTRY_BYTES + 16 * RAY_BYTES,
        ENTRY_BYTES + 64 * RAY_BYTES,
        ENTRY_BYTES + 128 * RAY_BYTES,
        ENTRY_BYTES + RAY_BYTES,
        static_slots,
        crate::render::gi::DYNAMIC_CAPACITY,
        (static_slots + crate::render::gi::DYNAMIC_CAPACITY) as f64 * (ENTRY_BYTES + RAY_BYTES) as f64
            / (1024.0 * 1024.0),
        (static_slots + crate::render::gi::DYNAMIC_CAPACITY) as f64 * (ENTRY_BYTES + 64 * RAY_BYTES) as f64
            / (1024.0 * 1024.0)
    );
    text
}
