//! Input shows on screen within a frame or two, whatever the adapter.
//!
//! Submitting GPU work does not wait for the GPU: a renderer whose frames take longer on the GPU than on the CPU
//! could run ahead, and every frame queued between a key and the screen would be latency. So the game keeps at
//! most one frame of GPU work in flight: once a frame is submitted, the render world waits for the previous one
//! to finish before it prepares the next. With the same setting the game also runs without pipelined rendering
//! (`game::run_game`), so the update that reads a key renders it. On lavapipe a key reaches the GPU's finished
//! frame in 1.35-1.4 frames this way against 1.8-2.2 without, at the same frame time (`docs/latency.md`).
//!
//! The probe: each key press is stamped in the main world and carried into the render world, which logs how long
//! after the press the GPU finished the first frame that saw it, in milliseconds and in frames of the current
//! frame time.

use bevy::prelude::*;
use bevy::render::extract_resource::{ExtractResource, ExtractResourcePlugin};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::{Render, RenderApp, RenderSystems};
use std::time::Instant;

pub struct FramePacingPlugin;

impl Plugin for FramePacingPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<KeyStamp>()
            .add_plugins(ExtractResourcePlugin::<KeyStamp>::default())
            .add_systems(PreUpdate, stamp_key_presses.after(bevy::input::InputSystems));
        if let Some(render_app) = app.get_sub_app_mut(RenderApp) {
            render_app
                .init_resource::<InFlight>()
                .add_systems(Render, wait_for_previous_frame.in_set(RenderSystems::Cleanup));
        }
    }
}

/// The latest key press the main world saw: when, and how many presses so far (so the render world reports each
/// once).
#[derive(Resource, Clone, Default, ExtractResource)]
pub struct KeyStamp {
    pub presses: u64,
    pub at: Option<Instant>,
    /// The main world's last frame time at the press (what the HUD shows), beside the render world's.
    pub main_frame_ms: f64,
}

fn stamp_key_presses(keys: Res<ButtonInput<KeyCode>>, time: Res<Time<Real>>, mut stamp: ResMut<KeyStamp>) {
    if keys.get_just_pressed().next().is_some() {
        stamp.presses += 1;
        stamp.at = Some(Instant::now());
        stamp.main_frame_ms = time.delta_secs_f64() * 1e3;
    }
}

/// The last frame's submission and when it was made, and the last key press reported.
#[derive(Resource, Default)]
struct InFlight {
    previous: Option<wgpu::SubmissionIndex>,
    previous_at: Option<Instant>,
    last_interval_ms: f64,
    reported: u64,
}

fn wait_for_previous_frame(
    queue: Res<RenderQueue>,
    device: Res<RenderDevice>,
    stamp: Option<Res<KeyStamp>>,
    settings: Option<Res<crate::settings::RenderSettings>>,
    mut in_flight: ResMut<InFlight>,
) {
    // An empty submission's index stands for everything submitted before it: this frame's work.
    let this_frame = queue.submit(std::iter::empty());
    // The frame time before this frame: a key that changes what is drawn (a debug view) changes this one's.
    let now = Instant::now();
    let interval = in_flight.previous_at.replace(now).map_or(0.0, |t| (now - t).as_secs_f64() * 1e3);
    let frame_ms = std::mem::replace(&mut in_flight.last_interval_ms, interval);
    if let Some(stamp) = stamp
        && stamp.presses > in_flight.reported
        && let Some(at) = stamp.at
    {
        in_flight.reported = stamp.presses;
        let submitted = at.elapsed().as_secs_f64() * 1e3;
        let main_ms = stamp.main_frame_ms;
        queue.on_submitted_work_done(move || {
            let ms = at.elapsed().as_secs_f64() * 1e3;
            info!(
                "input latency: {ms:.0} ms from the key to the GPU finishing the first frame that saw it ({:.1} frames \
                 of {frame_ms:.0} ms; submitted after {submitted:.0} ms; main world frame {main_ms:.0} ms)",
                ms / frame_ms.max(1e-3)
            );
        });
    }
    let previous = in_flight.previous.replace(this_frame);
    if let Some(previous) = previous.filter(|_| settings.is_none_or(|s| s.pacing)) {
        let wait = wgpu::PollType::Wait { submission_index: Some(previous), timeout: None };
        if let Err(e) = device.wgpu_device().poll(wait) {
            warn!("waiting for the previous frame: {e}");
        }
    }
}
