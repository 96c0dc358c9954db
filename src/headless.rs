//! Rendering without a window: a Bevy app with no winit, a camera that renders into an image, and a GPU
//! readback of the linear HDR result after the requested number of frames. Used by `glowbrick render` and tests.

use crate::image_io::LinearImage;
use crate::render::FramesRendered;
use crate::render::camera::voxel_camera_bundle;
use crate::settings::RenderSettings;
use crate::world::{CameraView, VoxelWorld};
use bevy::app::PluginsState;
use bevy::camera::RenderTarget;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::log::LogPlugin;
use bevy::prelude::*;
use bevy::render::RenderPlugin;
use bevy::render::gpu_readback::{Readback, ReadbackComplete};
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use bevy::render::render_resource::{PollType, TextureFormat, TextureUsages};
use bevy::render::renderer::RenderDevice;
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
#[derive(Resource, Clone, Default)]
struct Captured(Arc<Mutex<Option<Vec<u8>>>>);

#[derive(Resource)]
struct CaptureTarget(Handle<Image>);

/// Renders `world` from `view` without a window and returns the linear HDR image (before tonemapping).
pub fn render_headless(world: VoxelWorld, view: &CameraView, options: &HeadlessOptions) -> Result<LinearImage, String> {
    let (w, h) = (options.width, options.height);
    if w == 0 || h == 0 || w > MAX_IMAGE_EDGE || h > MAX_IMAGE_EDGE {
        return Err(format!("image size {w}x{h} must be within 1..={MAX_IMAGE_EDGE} on each side"));
    }
    if options.frames == 0 || options.frames > 100_000 {
        return Err(format!("frames = {} must be within 1..=100000", options.frames));
    }
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
    .add_plugins(crate::GlowbrickCorePlugin);

    let mut image = Image::new_target_texture(w, h, TextureFormat::Rgba32Float, None);
    image.texture_descriptor.usage |= TextureUsages::COPY_SRC;
    let target = app.world_mut().resource_mut::<Assets<Image>>().add(image);
    app.world_mut().spawn((voxel_camera_bundle(view), Tonemapping::None, RenderTarget::Image(target.clone().into())));
    let captured = Captured::default();
    app.insert_resource(captured.clone()).insert_resource(CaptureTarget(target));
    while app.plugins_state() == PluginsState::Adding {
        bevy::tasks::tick_global_task_pools_on_main_thread();
    }
    app.finish();
    app.cleanup();

    let frames = app.world().resource::<FramesRendered>().clone();
    let start = Instant::now();
    let mut readback_spawned = false;
    loop {
        app.update();
        // One frame in flight at a time: on software Vulkan, queued frames would otherwise pile up.
        if let Some(device) = app.world().get_resource::<RenderDevice>() {
            let _ = device.wgpu_device().poll(PollType::Wait { submission_index: None, timeout: None });
        }
        if let Some(bytes) = captured.0.lock().map_err(|_| "readback lock poisoned")?.take() {
            return decode_rgba32f(&bytes, w, h);
        }
        if !readback_spawned && frames.0.load(Ordering::Relaxed) >= options.frames {
            let handle = app.world().resource::<CaptureTarget>().0.clone();
            let sink = captured.clone();
            app.world_mut().spawn(Readback::texture(handle)).observe(move |event: On<ReadbackComplete>| {
                if let Ok(mut slot) = sink.0.lock() {
                    slot.get_or_insert_with(|| event.data.clone());
                }
            });
            readback_spawned = true;
        }
        if start.elapsed() > options.timeout {
            return Err(format!(
                "timed out after {:?}: {} of {} frames rendered (is a GPU adapter available?)",
                options.timeout,
                frames.0.load(Ordering::Relaxed),
                options.frames
            ));
        }
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
