//! Rendering without a window: a Bevy app with no winit, a camera that renders into an image, and a GPU
//! readback of the linear HDR result after the requested number of frames. Used by `glowbrick render` and tests.

use crate::image_io::LinearImage;
use crate::render::FramesRendered;
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
    /// Give up when the GPU has not produced the frames by then.
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

/// Pixels read back from the GPU, shared with the observer that receives them.
#[derive(Clone, Default)]
struct Captured(Arc<Mutex<Option<Vec<u8>>>>);

/// A windowless app rendering one voxel camera into an image: step it, edit its world, read frames back.
pub struct HeadlessRenderer {
    app: App,
    target: Handle<Image>,
    captured: Captured,
    frames: FramesRendered,
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
        // A saved world shows its moving objects where it was saved.
        if let Some(saved) = saved_objects {
            crate::dynamic::saved::spawn_saved(app.world_mut(), &saved)?;
        }
        let frames = app.world().resource::<FramesRendered>().clone();
        Ok(HeadlessRenderer {
            app,
            target,
            captured: Captured::default(),
            frames,
            width: w,
            height: h,
            timeout: options.timeout,
        })
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
    /// of what several cameras share). `frames_rendered` then counts each camera's frames.
    pub fn add_camera(&mut self, view: &CameraView) {
        let mut image = Image::new_target_texture(self.width, self.height, TextureFormat::Rgba32Float, None);
        image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
        let target = self.app.world_mut().resource_mut::<Assets<Image>>().add(image);
        self.app.world_mut().spawn((voxel_camera_bundle(view), Tonemapping::None, RenderTarget::Image(target.into())));
    }

    /// Frames the primary pass has dispatched so far.
    pub fn frames_rendered(&self) -> u32 {
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

    /// The GPU counters of the next rendered frame (`render::gpu_types::GpuCounter` indexes them). Renders that
    /// frame (and any before the readback arrives).
    pub fn counters(&mut self) -> Result<[u32; COUNTERS], String> {
        let handle = self.app.world().resource::<GpuCountersBuffer>().0.clone();
        let sink = Captured::default();
        let slot = sink.clone();
        let entity = self
            .app
            .world_mut()
            .spawn(Readback::buffer(handle))
            .observe(move |event: On<ReadbackComplete>| {
                if let Ok(mut s) = slot.0.lock() {
                    s.get_or_insert_with(|| event.data.clone());
                }
            })
            .id();
        let start = Instant::now();
        loop {
            self.step();
            if let Some(bytes) = sink.0.lock().map_err(|_| "readback lock poisoned")?.take() {
                self.app.world_mut().despawn(entity);
                let mut out = [0u32; COUNTERS];
                for (value, word) in out.iter_mut().zip(bytes.chunks_exact(4)) {
                    *value = u32::from_le_bytes([word[0], word[1], word[2], word[3]]);
                }
                return Ok(out);
            }
            if start.elapsed() > self.timeout {
                return Err(format!("timed out after {:?} waiting for the GI counters", self.timeout));
            }
        }
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
        let goal = self.frames_rendered() + frames;
        let mut readback: Option<Entity> = None;
        self.until_captured(|renderer| {
            if readback.is_none() && renderer.frames_rendered() >= goal {
                readback = Some(renderer.spawn_readback());
            }
            readback
        })
    }

    /// Renders one frame and returns its image: the frame that applies whatever was asked before the call (an
    /// edit message, a setting), not a later one. (The copy arrives while the next frame renders, so two frames
    /// run.)
    pub fn render_next(&mut self) -> Result<LinearImage, String> {
        let readback = self.spawn_readback();
        self.until_captured(|_| Some(readback))
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
        let images: Arc<Mutex<Vec<Vec<u8>>>> = Arc::default();
        let sink = images.clone();
        let readback = self
            .app
            .world_mut()
            .spawn(Readback::texture(self.target.clone()))
            .observe(move |event: On<ReadbackComplete>| {
                if let Ok(mut all) = sink.lock() {
                    all.push(event.data.clone());
                }
            })
            .id();
        let start = Instant::now();
        let mut frame = 0;
        // The last frames' copies arrive while later frames render (with the last frame's set-up).
        while images.lock().map_err(|_| "readback lock poisoned")?.len() < frames as usize {
            if frame < frames {
                before(frame, self);
                frame += 1;
            }
            self.step();
            if let Some(error) = crate::render::frame::pipeline_error(self.app.sub_app(RenderApp).world()) {
                return Err(error);
            }
            if start.elapsed() > self.timeout {
                return Err(format!("timed out after {:?} in a sequence of {frames} frames", self.timeout));
            }
        }
        self.app.world_mut().despawn(readback);
        let all = images.lock().map_err(|_| "readback lock poisoned")?;
        all.iter().take(frames as usize).map(|bytes| decode_rgba32f(bytes, self.width, self.height)).collect()
    }

    /// Asks for the render target of the next frame rendered.
    fn spawn_readback(&mut self) -> Entity {
        let sink = self.captured.clone();
        self.app
            .world_mut()
            .spawn(Readback::texture(self.target.clone()))
            .observe(move |event: On<ReadbackComplete>| {
                if let Ok(mut slot) = sink.0.lock() {
                    slot.get_or_insert_with(|| event.data.clone());
                }
            })
            .id()
    }

    /// Steps frames until a readback delivers an image; `after_step` (also asked once before the first step)
    /// spawns the readback when it is time and says which it is (despawned once it delivered).
    fn until_captured(
        &mut self,
        mut after_step: impl FnMut(&mut Self) -> Option<Entity>,
    ) -> Result<LinearImage, String> {
        let start = Instant::now();
        let mut readback = after_step(self);
        loop {
            self.step();
            if let Some(bytes) = self.captured.0.lock().map_err(|_| "readback lock poisoned")?.take() {
                if let Some(entity) = readback {
                    self.app.world_mut().despawn(entity);
                }
                return decode_rgba32f(&bytes, self.width, self.height);
            }
            readback = after_step(self);
            let render_world = self.app.sub_app(RenderApp).world();
            if let Some(error) = crate::render::frame::pipeline_error(render_world) {
                return Err(error);
            }
            if start.elapsed() > self.timeout {
                return Err(format!(
                    "timed out after {:?}: {} frames rendered (is a GPU adapter available?)",
                    self.timeout,
                    self.frames_rendered()
                ));
            }
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
