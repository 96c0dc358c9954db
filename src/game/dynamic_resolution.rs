//! Dynamic resolution (`render_scale=auto`, the game's default): the render scale follows the measured GPU time
//! of the voxel passes (timestamp queries, not the CPU's frame time) toward `frame_target`. Each decision waits
//! for measurements made at the scale in force, averages several, and changes nothing inside a dead band, so the
//! scale does not pump; a change of render size restarts the lighting passes' histories, so fewer is better.

use crate::render::upscale::RenderScaleInForce;
use crate::settings::{RENDER_SCALE_RANGE, RenderScale, RenderSettings};
use bevy::diagnostic::DiagnosticsStore;
use bevy::prelude::*;
use std::time::Instant;

pub struct DynamicResolutionPlugin;

impl Plugin for DynamicResolutionPlugin {
    fn build(&self, app: &mut App) {
        if !app.is_plugin_added::<bevy::render::diagnostic::RenderDiagnosticsPlugin>() {
            app.add_plugins(bevy::render::diagnostic::RenderDiagnosticsPlugin);
        }
        app.init_resource::<DynamicResolution>()
            .insert_resource(RenderScaleInForce(1.0))
            .add_systems(Update, follow_gpu_time);
    }
}

/// Measurements after a change that are skipped (the frames in flight were made at the old scale).
const SETTLE_MEASUREMENTS: u32 = 3;
/// Measurements averaged for one decision.
const DECISION_MEASUREMENTS: u32 = 4;
/// No change while the GPU time is within this share of the target.
const DEAD_BAND: f64 = 0.08;
/// The scale moves in steps of this much (fewer distinct render sizes, fewer restarts).
const SCALE_STEP: f32 = 0.05;

/// The controller: the scale in force and the measurements toward the next decision.
#[derive(Resource, Clone, Debug)]
pub struct DynamicResolution {
    pub scale: f32,
    /// The average GPU ms of the last decision's measurements (0 before the first).
    pub gpu_ms: f64,
    skipped: u32,
    samples: Vec<f64>,
    last_seen: Option<Instant>,
}

impl Default for DynamicResolution {
    fn default() -> Self {
        DynamicResolution { scale: 1.0, gpu_ms: 0.0, skipped: 0, samples: Vec::new(), last_seen: None }
    }
}

impl DynamicResolution {
    /// Takes one frame's GPU time; returns the new scale when this measurement completes a decision that changes
    /// it. GPU time is taken to grow with the render pixels (the square of the scale), and each step goes part of
    /// the way, so a cost that does not shrink with the pixels (the primary pass, the GI cache) is approached over
    /// several decisions instead of overshot.
    pub fn measure(&mut self, gpu_ms: f64, target_ms: f64, range: (f32, f32)) -> Option<f32> {
        if !(gpu_ms.is_finite() && gpu_ms > 0.0) {
            return None;
        }
        if self.skipped < SETTLE_MEASUREMENTS {
            self.skipped += 1;
            return None;
        }
        self.samples.push(gpu_ms);
        if self.samples.len() < DECISION_MEASUREMENTS as usize {
            return None;
        }
        let mean = self.samples.iter().sum::<f64>() / self.samples.len() as f64;
        self.samples.clear();
        self.gpu_ms = mean;
        let ratio = target_ms / mean;
        if (ratio - 1.0).abs() <= DEAD_BAND {
            return None;
        }
        let wanted = self.scale * ratio.clamp(0.25, 4.0).powf(0.4) as f32;
        let stepped = ((wanted / SCALE_STEP).round() * SCALE_STEP).clamp(range.0, range.1);
        if (stepped - self.scale).abs() < SCALE_STEP * 0.5 {
            return None;
        }
        self.scale = stepped;
        self.skipped = 0;
        Some(stepped)
    }
}

/// The GPU time of the latest frame the diagnostics hold: the sum of the voxel passes' timestamps, and when it
/// was recorded (None until the adapter's timestamps arrive).
fn latest_gpu_ms(store: &DiagnosticsStore) -> Option<(f64, Instant)> {
    let mut total = 0.0;
    let mut newest: Option<Instant> = None;
    for diagnostic in store.iter() {
        let path = diagnostic.path().as_str();
        if !(path.starts_with("render/glowbrick_") && path.ends_with("/elapsed_gpu")) {
            continue;
        }
        if let Some(m) = diagnostic.measurement() {
            total += m.value;
            newest = Some(newest.map_or(m.time, |t| t.max(m.time)));
        }
    }
    newest.map(|at| (total, at))
}

fn follow_gpu_time(
    settings: Res<RenderSettings>,
    store: Option<Res<DiagnosticsStore>>,
    mut controller: ResMut<DynamicResolution>,
    mut in_force: ResMut<RenderScaleInForce>,
) {
    if settings.render_scale != RenderScale::Auto {
        return;
    }
    let Some((gpu_ms, at)) = store.as_deref().and_then(latest_gpu_ms) else { return };
    if controller.last_seen.is_some_and(|seen| seen >= at) {
        return;
    }
    controller.last_seen = Some(at);
    let (before, decided) = (controller.scale, controller.gpu_ms);
    if let Some(scale) = controller.measure(gpu_ms, f64::from(settings.frame_target), RENDER_SCALE_RANGE) {
        in_force.0 = scale;
    }
    if controller.gpu_ms != decided {
        info!(
            "dynamic resolution: GPU {:.1} ms against a target of {} ms at render scale {before:.2}, now {:.2}",
            controller.gpu_ms, settings.frame_target, controller.scale
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A frame whose GPU time is `fixed` plus `per_pixel` at scale 1, shrinking with the render pixels.
    fn cost(scale: f32, fixed: f64, per_pixel: f64) -> f64 {
        fixed + per_pixel * f64::from(scale * scale)
    }

    /// From native, the scale settles where the frame meets its target within the dead band, and then stays.
    #[test]
    fn the_scale_settles_within_the_dead_band_and_stays() {
        let mut controller = DynamicResolution::default();
        let (fixed, per_pixel, target) = (150.0, 1850.0, 800.0);
        let mut changes = 0;
        for _ in 0..400 {
            if controller.measure(cost(controller.scale, fixed, per_pixel), target, RENDER_SCALE_RANGE).is_some() {
                changes += 1;
            }
        }
        let settled = cost(controller.scale, fixed, per_pixel);
        assert!((settled / target - 1.0).abs() <= 0.15, "{settled} ms at scale {}", controller.scale);
        assert!(changes <= 6, "{changes} changes");
        // Settled: more measurements change nothing.
        let scale = controller.scale;
        for _ in 0..100 {
            assert_eq!(controller.measure(cost(scale, fixed, per_pixel), target, RENDER_SCALE_RANGE), None);
        }
    }

    /// Noise of 5% around the target does not move it (no pumping).
    #[test]
    fn noise_inside_the_dead_band_does_not_pump() {
        let mut controller = DynamicResolution { scale: 0.5, ..default() };
        for i in 0..200 {
            let noisy = 800.0 * (1.0 + 0.05 * ((i * 7 % 11) as f64 / 5.0 - 1.0));
            assert_eq!(controller.measure(noisy, 800.0, RENDER_SCALE_RANGE), None, "measurement {i}");
        }
    }

    /// A target out of reach stops at the range's ends; junk measurements are ignored.
    #[test]
    fn the_scale_stays_in_its_range_and_ignores_junk() {
        let mut controller = DynamicResolution::default();
        for _ in 0..200 {
            controller.measure(5000.0, 16.7, RENDER_SCALE_RANGE);
        }
        assert_eq!(controller.scale, RENDER_SCALE_RANGE.0);
        for _ in 0..200 {
            controller.measure(1.0, 16.7, RENDER_SCALE_RANGE);
        }
        assert_eq!(controller.scale, RENDER_SCALE_RANGE.1);
        for junk in [f64::NAN, f64::INFINITY, -1.0, 0.0] {
            assert_eq!(controller.measure(junk, 16.7, RENDER_SCALE_RANGE), None);
        }
    }
}
