//! The GI cache at the sizes a game renders (`glowbrick bench --gi`, section "Cost at game sizes", or alone with
//! `bench --gi --game-sizes`): with Voxel ReSTIR lighting the emitters (the thesis protocol), a frame with `gi=on` against
//! the same frame with `gi=off`, per-pass GPU times, the entries the table holds, its load and the inserts that
//! found it full. The cache runs at the game's settings (alpha 0.03, fresh directions, the default table).

use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::render::gi::{GI_PASS_NAMES, WARM_UP_FRAMES, static_capacity};
use crate::render::gpu_types::GpuCounter;
use crate::settings::RenderSettings;
use crate::world::recipe::load_scene;
use std::time::Instant;

/// Scenes (and views) measured, and the sizes.
const SCENES: &[(&str, &str)] = &[("window-room", "inside"), ("cornell", "front"), ("apartments", "")];
pub const SIZES: &[(u32, u32)] = &[(320, 180), (1280, 720)];
/// Frames before any timing (pipelines, the first inserts); then the rest of a fresh cache's warm-up (four
/// update iterations a frame, `gi::WARM_UP_FRAMES`), timed on its own; then frames to settle and frames timed.
/// A settled frame is timed after the warm-up: timed inside it, it would carry the warm-up's extra iterations.
const FIRST_FRAMES: u32 = 8;
const WARM_FRAMES: u32 = WARM_UP_FRAMES + 8;
const TIMED_FRAMES: u32 = 16;

pub struct ScaleRow {
    pub scene: &'static str,
    pub size: (u32, u32),
    /// Wall-clock ms per frame without and with the cache (settled).
    pub frame_off_ms: f64,
    pub frame_on_ms: f64,
    /// Wall-clock ms per frame with the cache during its warm-up (frames FIRST_FRAMES + 1 to WARM_UP_FRAMES).
    pub frame_warm_up_ms: f64,
    /// GPU ms with the cache on: primary + ReSTIR (the direct-light frame), and each GI pass (lists, refresh,
    /// update, filter).
    pub direct_ms: f64,
    pub gi_ms: [Option<f64>; 4],
    pub live: u32,
    pub full: u32,
    pub table: u32,
}

impl ScaleRow {
    fn gi_total_ms(&self) -> f64 {
        self.gi_ms.iter().flatten().sum()
    }
}

/// Wall-clock ms per frame during the warm-up and over TIMED_FRAMES after WARM_FRAMES, and the renderer for
/// its counters and timings.
fn timed(scene: &str, view: &str, size: (u32, u32), gi: bool) -> Result<(f64, f64, HeadlessRenderer), String> {
    let world = load_scene(scene).map_err(|e| e.to_string())?;
    let view = world.view((!view.is_empty()).then_some(view)).cloned().unwrap_or_else(|| world.overview());
    let pairs = ["lighting=emitters".to_string(), format!("gi={}", if gi { "on" } else { "off" })];
    let settings = RenderSettings::default().with_pairs(&pairs)?;
    let options = HeadlessOptions { width: size.0, height: size.1, settings, ..Default::default() };
    let mut r = HeadlessRenderer::new(world, &view, &options)?;
    r.render(FIRST_FRAMES)?;
    let warm_up_ms = mean_frame_ms(&mut r, WARM_UP_FRAMES - FIRST_FRAMES);
    r.render(WARM_FRAMES - WARM_UP_FRAMES)?;
    let settled_ms = mean_frame_ms(&mut r, TIMED_FRAMES);
    Ok((warm_up_ms, settled_ms, r))
}

/// Wall-clock ms per frame over the next `frames` frames.
fn mean_frame_ms(r: &mut HeadlessRenderer, frames: u32) -> f64 {
    let start = Instant::now();
    for _ in 0..frames {
        r.step();
    }
    start.elapsed().as_secs_f64() * 1000.0 / frames as f64
}

pub fn measure(scene: &'static str, view: &str, size: (u32, u32)) -> Result<ScaleRow, String> {
    let (_, frame_off_ms, _) = timed(scene, view, size, false)?;
    let (frame_warm_up_ms, frame_on_ms, mut r) = timed(scene, view, size, true)?;
    let direct_ms = super::direct_light_ms(&r).unwrap_or(0.0);
    let counters = r.counters()?;
    Ok(ScaleRow {
        scene,
        size,
        frame_off_ms,
        frame_on_ms,
        frame_warm_up_ms,
        direct_ms,
        gi_ms: GI_PASS_NAMES.map(|n| r.gpu_pass_ms(n)),
        live: counters[GpuCounter::GiLive as usize],
        full: counters[GpuCounter::GiFull as usize],
        table: static_capacity(&RenderSettings::default().gi),
    })
}

/// Every scene at each of `sizes`.
pub fn measure_all(sizes: &[(u32, u32)]) -> Result<Vec<ScaleRow>, String> {
    let mut rows = Vec::new();
    for &size in sizes {
        for &(scene, view) in SCENES {
            let row = measure(scene, view, size)?;
            eprintln!(
                "gi scale: {scene} {}x{}: {:.0} -> {:.0} ms/frame, GI passes {:.1} ms against direct {:.1} ms, {} \
                 live, {} full",
                size.0,
                size.1,
                row.frame_off_ms,
                row.frame_on_ms,
                row.gi_total_ms(),
                row.direct_ms,
                row.live,
                row.full
            );
            rows.push(row);
        }
    }
    Ok(rows)
}

pub fn markdown(rows: &[ScaleRow]) -> String {
    let ms = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.1}"));
    let mut text = format!(
        "\n## Cost at game sizes\n\nOn {}. Voxel ReSTIR lighting the emitters (`lighting=emitters`), the cache at the game's \
         settings (8 fresh rays per entry and frame, alpha 0.03), {WARM_FRAMES} frames to warm up, {TIMED_FRAMES} \
         timed. Frame ms is wall clock (gi=off, gi=on); \"warm-up\" is gi=on's frames {} to {WARM_UP_FRAMES}, a \
         fresh cache's four update iterations a frame; the pass columns are GPU timestamps with gi=on; direct = \
         primary + ReSTIR's three passes. Load = live entries / static table slots; full = inserts that found their \
         probe window full in the last frame.\n\n\
         | scene | size | frame ms, gi off | frame ms, gi on | on / off | frame ms, warm-up | warm-up / on | direct ms | lists ms | refresh ms | update \
         ms | filter ms | GI / direct | live entries | load | full |\n\
         |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
        crate::render::adapter::adapter_name(),
        FIRST_FRAMES + 1
    );
    for r in rows {
        text += &format!(
            "| {} | {}x{} | {:.1} | {:.1} | {:.2} | {:.1} | {:.2} | {:.1} | {} | {} | {} | {} | {:.2} | {} | {:.2} | {} |\n",
            r.scene,
            r.size.0,
            r.size.1,
            r.frame_off_ms,
            r.frame_on_ms,
            r.frame_on_ms / r.frame_off_ms.max(1e-9),
            r.frame_warm_up_ms,
            r.frame_warm_up_ms / r.frame_on_ms.max(1e-9),
            r.direct_ms,
            ms(r.gi_ms[0]),
            ms(r.gi_ms[1]),
            ms(r.gi_ms[2]),
            ms(r.gi_ms[3]),
            r.gi_total_ms() / r.direct_ms.max(1e-9),
            r.live,
            r.live as f64 / r.table as f64,
            r.full
        );
    }
    text
}
