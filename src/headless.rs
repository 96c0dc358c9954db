//! Rendering without a window: a Bevy app with no winit, a camera that renders into an image, and a GPU
//! readback of the linear HDR result after the requested number of frames. Used by `glowbrick render` and tests.

use crate::image_io::LinearImage;
use crate::render::CameraFramesRendered;
use crate::render::camera::voxel_camera_bundle;
use crate::render::gpu_types::COUNTERS;
use crate::render::scene::counters::GpuCountersBuffer;
use crate::settings::RenderSettings;
use crate::world::{CameraView, VoxelWorld};
use bevy::app::PluginsState;
use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::log::LogPlugin;
use bevy::prelude::*;
use bevy::render::diagnostic::RenderDiagnosticsPlugin;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::render_resource::{PollType, TextureFormat, TextureUsages};
use bevy::render::renderer::RenderDevice;
use bevy::render::{RenderApp, RenderPlugin};
use bevy::window::ExitCondition;
use bevy::winit::WinitPlugin;
use std::sync::atomic::Ordering;
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

/// What to render.
#[derive(Clone, Debug)]
pub struct HeadlessOptions {
    pub width: u32,
    pub height: u32,
    /// Frames to render before reading back (the last one is returned).
    pub frames: u32,
    pub settings: RenderSettings,
    /// Give up when the GPU has rendered no frame for this long (a long render on a slow adapter runs on while its
    /// frames keep coming).
    pub timeout: Duration,
}

impl Default for HeadlessOptions {
    fn default() -> Self {
        HeadlessOptions {
            width: 320,
            height: 180,
            frames: 1,
            settings: RenderSettings::default(),
            timeout: Duration::from_secs(600),
        }
    }
}

/// Largest image edge `render` accepts (keeps a typo from allocating gigabytes).
pub const MAX_IMAGE_EDGE: u32 = 8192;

/// A windowless app rendering one voxel camera into an image: step it, edit its world, read frames back.
pub struct HeadlessRenderer {
    app: App,
    target: Handle<Image>,
    frames: CameraFramesRendered,
    width: u32,
    height: u32,
    timeout: Duration,
}

impl HeadlessRenderer {
    /// Builds the app around `world` with a camera at `view`. Panics inside Bevy when no GPU adapter exists
    /// (callers that must report it catch the unwind).
    pub fn new(world: VoxelWorld, view: &CameraView, options: &HeadlessOptions) -> Result<Self, String> {
        let (w, h) = (options.width, options.height);
        if w == 0 || h == 0 || w > MAX_IMAGE_EDGE || h > MAX_IMAGE_EDGE {
            return Err(format!("image size {w}x{h} must be within 1..={MAX_IMAGE_EDGE} on each side"));
        }
        let saved_objects = world.objects.clone();
        let mut app = App::new();
        app.add_plugins(
            DefaultPlugins
                .set(WindowPlugin { primary_window: None, exit_condition: ExitCondition::DontExit, ..default() })
                .set(RenderPlugin { synchronous_pipeline_compilation: true, ..default() })
                .set(LogPlugin { level: bevy::log::Level::WARN, filter: "wgpu=error,naga=warn".into(), ..default() })
                .disable::<WinitPlugin>()
                .disable::<PipelinedRenderingPlugin>(),
        )
        .insert_resource(world)
        .insert_resource(options.settings.clone())
        .add_plugins((crate::core_plugin::GlowbrickCorePlugin, RenderDiagnosticsPlugin));

        let mut image = Image::new_target_texture(w, h, TextureFormat::Rgba32Float, None);
        image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
        let target = app.world_mut().resource_mut::<Assets<Image>>().add(image);
        app.world_mut().spawn((
            voxel_camera_bundle(view),
            Tonemapping::None,
            RenderTarget::Image(target.clone().into()),
        ));
        while app.plugins_state() == PluginsState::Adding {
            bevy::tasks::tick_global_task_pools_on_main_thread();
        }
        app.finish();
        app.cleanup();
        if let Some(device) = app.world().get_resource::<RenderDevice>() {
            crate::render::scene::world::fits_device(app.world().resource::<VoxelWorld>(), device)?;
        }
        // A saved world shows its moving objects where it was saved.
        if let Some(saved) = saved_objects {
            crate::dynamic::saved::spawn_saved(app.world_mut(), &saved)?;
        }
        let frames = app.world().resource::<CameraFramesRendered>().clone();
        Ok(HeadlessRenderer { app, target, frames, width: w, height: h, timeout: options.timeout })
    }

    /// The app, to send edit messages or read resources of either world.
    pub fn app_mut(&mut self) -> &mut App {
        &mut self.app
    }

    /// Moves the camera to `view`, field of view included (takes effect on the next frame; temporal history is
    /// kept).
    pub fn set_view(&mut self, view: &CameraView) {
        let transform = crate::world::view_transform(view);
        let world = self.app.world_mut();
        let mut cameras = world.query_filtered::<(&mut Transform, &mut Projection), With<crate::render::VoxelCamera>>();
        for (mut t, mut projection) in cameras.iter_mut(world) {
            *t = transform;
            if let Projection::Perspective(p) = projection.as_mut() {
                p.fov = view.fov_deg.to_radians();
            }
        }
    }

    /// Adds another voxel camera at `view`, rendering into an image of its own that is never read back (for tests
    /// of what several cameras share). `camera_frames_rendered` then counts each camera's frames.
    pub fn add_camera(&mut self, view: &CameraView) {
        let mut image = Image::new_target_texture(self.width, self.height, TextureFormat::Rgba32Float, None);
        image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
        let target = self.app.world_mut().resource_mut::<Assets<Image>>().add(image);
        self.app.world_mut().spawn((voxel_camera_bundle(view), Tonemapping::None, RenderTarget::Image(target.into())));
    }

    /// Camera-frames the primary pass has dispatched so far (one per camera per frame).
    pub fn camera_frames_rendered(&self) -> u32 {
        self.frames.0.load(Ordering::Relaxed)
    }

    /// Mean GPU time of the pass called `name` over the recent frames, in milliseconds, when the adapter
    /// records timestamps.
    pub fn gpu_pass_ms(&self, name: &str) -> Option<f64> {
        let store = self.app.world().get_resource::<bevy::diagnostic::DiagnosticsStore>()?;
        store
            .iter()
            .find(|d| {
                let path = d.path().as_str();
                path.ends_with(&format!("{name}/elapsed_gpu"))
            })
            .and_then(|d| d.average())
    }

    /// Forgets the GPU times recorded so far, so that `gpu_pass_ms` averages only the frames rendered from now on
    /// (not the warm-up's).
    pub fn clear_gpu_pass_times(&mut self) {
        if let Some(mut store) = self.app.world_mut().get_resource_mut::<bevy::diagnostic::DiagnosticsStore>() {
            store.iter_mut().for_each(|d| d.clear_history());
        }
    }

    /// The GPU counters of the next rendered frame (`render::gpu_types::GpuCounter` indexes them). Renders that
    /// frame (and any before the readback arrives).
    pub fn counters(&mut self) -> Result<[u32; COUNTERS], String> {
        let handle = self.app.world().resource::<GpuCountersBuffer>().0.clone();
        let copies = self.read_back(|| Readback::buffer(handle.clone()), 1, "the GI counters", |_| true)?;
        let mut out = [0u32; COUNTERS];
        for (value, word) in out.iter_mut().zip(copies[0].chunks_exact(4)) {
            *value = u32::from_le_bytes([word[0], word[1], word[2], word[3]]);
        }
        Ok(out)
    }

    /// Runs one frame and waits for the GPU (one frame in flight: on software Vulkan, queued frames would
    /// otherwise pile up).
    pub fn step(&mut self) {
        self.app.update();
        if let Some(device) = self.app.world().get_resource::<RenderDevice>() {
            let _ = device.wgpu_device().poll(PollType::Wait { submission_index: None, timeout: None });
        }
    }

    /// Renders `frames` more frames and returns the last one's linear HDR image.
    pub fn render(&mut self, frames: u32) -> Result<LinearImage, String> {
        check_frames(frames)?;
        let goal = self.camera_frames_rendered() + frames;
        let copies =
            self.read_back(self.texture_readback(), 1, "the last frame", |r| r.camera_frames_rendered() >= goal)?;
        decode_rgba32f(&copies[0], self.width, self.height)
    }

    /// Renders one frame and returns its image: the frame that applies whatever was asked before the call (an
    /// edit message, a setting), not a later one. (The copy arrives while the next frame renders, so two frames
    /// run.) A setting that needs pipelines not compiled yet (a new `render::pass_key::PassKey`) shows only once
    /// they are: `render` waits for them, this does not.
    pub fn render_next(&mut self) -> Result<LinearImage, String> {
        let copies = self.read_back(self.texture_readback(), 1, "the next frame", |_| true)?;
        decode_rgba32f(&copies[0], self.width, self.height)
    }

    /// Renders `frames` frames, each after `before(k, renderer)` sets frame k up (a camera on a path, objects
    /// where they are), and returns every one of them. One readback stays on the target: frame k's copy arrives
    /// while frame k + 1 renders, so unlike `render_next` in a loop no frame renders twice (a measurement of
    /// motion sees every step once).
    pub fn render_sequence(
        &mut self,
        frames: u32,
        mut before: impl FnMut(u32, &mut Self),
    ) -> Result<Vec<LinearImage>, String> {
        check_frames(frames)?;
        let mut frame = 0;
        let what = format!("a sequence of {frames} frames");
        // The last frames' copies arrive while later frames render (with the last frame's set-up).
        let copies = self.read_back(self.texture_readback(), frames as usize, &what, |r| {
            if frame < frames {
                before(frame, r);
                frame += 1;
            }
            true
        })?;
        copies.iter().map(|bytes| decode_rgba32f(bytes, self.width, self.height)).collect()
    }

    /// A copy of the render target.
    fn texture_readback(&self) -> impl Fn() -> Readback + use<> {
        let target = self.target.clone();
        move || Readback::texture(target.clone())
    }

    /// The one loop every read-back waits in: steps frames until `copies` copies of `readback` arrived and
    /// returns them. `armed(renderer)` runs before every step (where a sequence sets its next frame up) and says
    /// whether the readback should be on by then (once on, it stays on: it copies every frame after). A voxel pass whose pipeline failed fails the wait at
    /// once, with its name, rather than waiting out the timeout for frames that will never come.
    fn read_back(
        &mut self,
        readback: impl Fn() -> Readback,
        copies: usize,
        what: &str,
        mut armed: impl FnMut(&mut Self) -> bool,
    ) -> Result<Vec<Vec<u8>>, String> {
        let delivered: Arc<Mutex<Vec<Vec<u8>>>> = Arc::default();
        let mut entity: Option<Entity> = None;
        let timeout = self.timeout;
        let result = wait_for(
            self,
            timeout,
            |r| {
                // Asked every step, even once armed: a sequence sets each of its frames up here.
                let arm = armed(r);
                if entity.is_none() && arm {
                    let sink = delivered.clone();
                    let observer = move |event: On<ReadbackComplete>| {
                        if let Ok(mut all) = sink.lock() {
                            all.push(event.data.clone());
                        }
                    };
                    entity = Some(r.app.world_mut().spawn(readback()).observe(observer).id());
                }
                r.step();
                let mut all = delivered.lock().map_err(|_| "readback lock poisoned")?;
                Ok((all.len() >= copies).then(|| all.drain(..copies).collect()))
            },
            |r| crate::render::frame::pipeline_error(r.app.sub_app(RenderApp).world()),
            |r| r.camera_frames_rendered(),
            |r, timeout| {
                format!(
                    "timed out after {timeout:?} without a frame, waiting for {what}: {} frames rendered (is a GPU \
                     adapter available?)",
                    r.camera_frames_rendered()
                )
            },
        );
        if let Some(entity) = entity {
            self.app.world_mut().despawn(entity);
        }
        result
    }
}

/// Runs `tick` until it returns a value. After every tick that returned none, `failed` may name an error that
/// ends the wait at once (a pipeline that failed to compile); once `progress` (frames rendered) has stood still
/// for `timeout`, `timed_out` says what was missing. A render of many frames on a slow adapter is not a hang.
fn wait_for<S, T>(
    state: &mut S,
    timeout: Duration,
    mut tick: impl FnMut(&mut S) -> Result<Option<T>, String>,
    failed: impl Fn(&S) -> Option<String>,
    progress: impl Fn(&S) -> u32,
    timed_out: impl FnOnce(&S, Duration) -> String,
) -> Result<T, String> {
    let mut last_progress = (progress(state), Instant::now());
    loop {
        if let Some(value) = tick(state)? {
            return Ok(value);
        }
        if let Some(error) = failed(state) {
            return Err(error);
        }
        let now = progress(state);
        if now != last_progress.0 {
            last_progress = (now, Instant::now());
        } else if last_progress.1.elapsed() > timeout {
            return Err(timed_out(state, timeout));
        }
    }
}

/// Renders `world` from `view` without a window and returns the linear HDR image (before tonemapping).
pub fn render_headless(world: VoxelWorld, view: &CameraView, options: &HeadlessOptions) -> Result<LinearImage, String> {
    check_frames(options.frames)?; // before the GPU starts
    HeadlessRenderer::new(world, view, options)?.render(options.frames)
}

/// Frames one `render` call may run.
fn check_frames(frames: u32) -> Result<(), String> {
    match frames {
        1..=100_000 => Ok(()),
        _ => Err(format!("frames = {frames} must be within 1..=100000")),
    }
}

/// Strips any 256-byte row padding of a texture readback and decodes little-endian f32 RGBA.
fn decode_rgba32f(bytes: &[u8], width: u32, height: u32) -> Result<LinearImage, String> {
    let row = width as usize * 16;
    // Readbacks may keep wgpu's 256-byte row alignment; tell by the length.
    let stride = if bytes.len() == row * height as usize { row } else { row.div_ceil(256) * 256 };
    if bytes.len() < stride * (height as usize - 1) + row {
        return Err(format!("readback returned {} bytes for a {width}x{height} image", bytes.len()));
    }
    let mut pixels = Vec::with_capacity((width * height) as usize);
    for y in 0..height as usize {
        for px in bytes[y * stride..y * stride + row].chunks_exact(16) {
            let c = |i: usize| f32::from_le_bytes([px[i], px[i + 1], px[i + 2], px[i + 3]]);
            pixels.push([c(0), c(4), c(8), c(12)]);
        }
    }
    Ok(LinearImage { width, height, pixels })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A shader error fails the wait on the tick it appears, with the check's message, not after the timeout.
    #[test]
    fn a_pipeline_error_ends_the_wait_at_once() {
        let mut ticks = 0u32;
        let start = Instant::now();
        let result: Result<(), String> = wait_for(
            &mut ticks,
            Duration::from_secs(600),
            |t| {
                *t += 1;
                Ok(None)
            },
            |t| (*t >= 3).then(|| "the primary shader (primary.wgsl) failed to compile: oops".to_string()),
            |_| 0,
            |_, _| "timed out".to_string(),
        );
        assert_eq!(result, Err("the primary shader (primary.wgsl) failed to compile: oops".to_string()));
        assert_eq!(ticks, 3);
        assert!(start.elapsed() < Duration::from_secs(5));
    }

    /// A value that arrives is returned, even on a tick the check would fail.
    #[test]
    fn a_delivered_value_is_returned() {
        let mut ticks = 0u32;
        let result = wait_for(
            &mut ticks,
            Duration::from_secs(600),
            |t| {
                *t += 1;
                Ok((*t == 2).then_some(*t))
            },
            |t| (*t >= 2).then(|| "a failure after the value arrived".to_string()),
            |_| 0,
            |_, _| "timed out".to_string(),
        );
        assert_eq!(result, Ok(2));
    }

    /// Without a value or an error, the wait ends at the timeout with the caller's message.
    #[test]
    fn the_timeout_says_what_was_missing() {
        let mut ticks = 0u32;
        let result: Result<(), String> = wait_for(
            &mut ticks,
            Duration::from_millis(20),
            |t| {
                *t += 1;
                std::thread::sleep(Duration::from_millis(1));
                Ok(None)
            },
            |_| None,
            |_| 0,
            |t, timeout| format!("timed out after {timeout:?} at tick {t}"),
        );
        let error = result.unwrap_err();
        assert!(error.starts_with("timed out after 20ms at tick"), "{error}");
        assert!(ticks >= 2);
    }

    /// A wait whose frames keep coming runs past the timeout (here 3x it): only a stall ends it.
    #[test]
    fn frames_that_keep_coming_outlast_the_timeout() {
        let start = Instant::now();
        let mut ticks = 0u32;
        let result = wait_for(
            &mut ticks,
            Duration::from_millis(100),
            |t| {
                *t += 1;
                std::thread::sleep(Duration::from_millis(2));
                Ok((*t == 150).then_some(*t))
            },
            |_| None,
            // A frame every tick, a few milliseconds apart: far under the timeout even on a loaded machine.
            |t| *t,
            |t, timeout| format!("timed out after {timeout:?} at tick {t}"),
        );
        assert_eq!(result, Ok(150));
        assert!(start.elapsed() >= Duration::from_millis(300));
    }
}
