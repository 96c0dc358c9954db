//! `glowbrick bench`: run time against error, in eight modes, each in its own module with its own config and its
//! report writer beside its measures:
//!
//! - `sweep`: every scene x render setting against a direct-light reference, the equal-time comparison
//!   (`equal_time`) and the convergence curves (`convergence`, drawn by `plot`); the default mode.
//! - `thesis`: the thesis' protocol, beside its Table 3.
//! - `gi`: the GI cache (and `gi_scale`, at game sizes).
//! - `daylight`: the game's lighting at three times of day.
//! - `denoise`: the denoiser (with `reaction` for a lamp switched off and on, `motion` for ghosting).
//! - `frame`: the game's frame pass by pass, GPU time and ray / step counters, no reference.
//! - `rays`: the CPU traversal's rays per second and steps / loads per ray, against the plain DDA.
//! - `net`: one server and many clients over loopback: joining, the server's tick, edits per second, bytes.
//!
//! Every mode measures against CPU references from one `reference_cache::ReferenceCache`. What is shared by
//! several modes lives here.

pub mod convergence;
pub mod daylight;
pub mod denoise;
pub mod equal_time;
pub mod frame;
pub mod gi;
pub mod gi_indirect;
pub mod gi_scale;
pub mod motion;
pub mod net;
pub mod net_endless;
pub mod plot;
pub mod rays;
pub mod reaction;
pub mod reference_cache;
pub mod same_hit;
pub mod sweep;
pub mod thesis;
pub mod travel;
pub mod upscale;

use crate::headless::HeadlessRenderer;
use crate::reference::metrics::Metrics;
use crate::render::primary::PRIMARY_PASS_NAME;
use crate::render::restir::RESTIR_PASS_NAMES;
use crate::world::VoxelWorld;
use crate::world::recipe::load_scene;

/// A bench scene by name: a bundled recipe (`assets/scenes/NAME.ron`) or `thesis-NAME`, the thesis' `NAME.vx`
/// from `../shared/scenes/thesis` (or the tests' copy).
pub fn load_bench_scene(name: &str) -> Result<VoxelWorld, String> {
    match name.strip_prefix("thesis-") {
        Some(stem) => {
            let path = thesis::thesis_scene(&format!("{stem}.vx"))?;
            crate::world::source::load_path(&path).map_err(|e| e.to_string())
        }
        None => load_scene(name).map_err(|e| e.to_string()),
    }
}

/// GPU ms per pass that ran, by pass name.
pub type PassTimes = Vec<(&'static str, f64)>;

/// GPU time of each voxel pass that ran (the primary pass, and the ReSTIR passes when they ran).
pub(crate) fn pass_times(renderer: &HeadlessRenderer) -> PassTimes {
    std::iter::once(PRIMARY_PASS_NAME)
        .chain(RESTIR_PASS_NAMES)
        .filter_map(|name| renderer.gpu_pass_ms(name).map(|ms| (name, ms)))
        .collect()
}

/// GPU time of the direct-light frame (the passes `pass_times` reads), or None without timestamps.
pub(crate) fn direct_light_ms(renderer: &HeadlessRenderer) -> Option<f64> {
    let times = pass_times(renderer);
    (!times.is_empty()).then(|| times.iter().map(|(_, ms)| ms).sum())
}

/// The mean of several measurements; fireflies are the most any one had.
pub(crate) fn mean_metrics(all: &[Metrics]) -> Metrics {
    let n = all.len().max(1) as f64;
    let mean = |f: fn(&Metrics) -> f64| all.iter().map(f).sum::<f64>() / n;
    Metrics {
        mae: mean(|m| m.mae),
        mse: mean(|m| m.mse),
        relmse: mean(|m| m.relmse),
        bias: mean(|m| m.bias),
        fireflies: all.iter().map(|m| m.fireflies).max().unwrap_or(0),
    }
}
