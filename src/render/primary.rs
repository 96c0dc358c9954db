//! The primary-ray pass (`shaders/primary.wgsl`): one ray per pixel through the brick grid and the moving
//! objects, writing the G-buffer (hit point and packed surface: face, material, object id) that every later pass
//! reads, touching the GI cache entries the camera sees, and lighting the hit itself (sun and sky, or one
//! next-event-estimation sample of the light pool) unless Voxel ReSTIR shades it. Also the debug views.
//!
//! Its per-view state is the G-buffer, this frame's and last frame's (`GBuffers`, swapped, never copied).

use super::gpu_types::{FrameParams, GBUFFER_REGIONS, GBUFFER_TEXEL_BYTES};
use super::interface::GpuBinding;
use super::pass::{Dispatch, VoxelPass};
use super::plan::FramePlan;
use super::view::{ViewPart, ViewPartKind};
use crate::settings::RenderSettings;
use bevy::render::render_resource::{BindingResource, Buffer, BufferDescriptor, BufferUsages};
use bevy::render::renderer::RenderDevice;
use std::sync::atomic::{AtomicUsize, Ordering};

pub const PRIMARY: VoxelPass = VoxelPass {
    name: "glowbrick_primary",
    shader: "primary.wgsl",
    entry_point: "main",
    dispatch: Dispatch::OutputPixels,
};

/// The name the pass's GPU time is recorded under.
pub const PRIMARY_PASS_NAME: &str = PRIMARY.name;

/// Its part of group 1 (`shaders/lib/frame.wgsl`): this frame's G-buffer, then last frame's.
pub const VIEW_BINDINGS: [GpuBinding; 2] = [GpuBinding::read_write("gbuffer"), GpuBinding::read_write("prev_gbuffer")];

/// Its view part.
pub const VIEW_PART: ViewPartKind =
    ViewPartKind { bindings: &VIEW_BINDINGS, new: |device, pixels| Box::new(GBuffers::new(device, pixels)) };

/// A view's G-buffer (below render scale 1 also the output's own and the upscaler's history, `GBUFFER_REGIONS`):
/// this frame's, which the primary pass writes, and last frame's,
/// which the temporal reprojections of ReSTIR and the denoiser read. Two buffers that swap roles each frame (the
/// primary pass writes every pixel of this frame's), so last frame's is never copied.
pub struct GBuffers {
    buffers: [Buffer; 2],
    /// Which of the two this frame writes.
    current: AtomicUsize,
}

impl GBuffers {
    pub fn new(device: &RenderDevice, pixels: u64) -> Self {
        let buffer = |label: &'static str| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size: pixels * GBUFFER_TEXEL_BYTES * GBUFFER_REGIONS,
                usage: BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        GBuffers {
            buffers: [buffer("glowbrick_gbuffer_a"), buffer("glowbrick_gbuffer_b")],
            current: AtomicUsize::new(0),
        }
    }
}

impl ViewPart for GBuffers {
    fn resources(&self) -> Vec<BindingResource<'_>> {
        let current = self.current.load(Ordering::Relaxed);
        vec![self.buffers[current].as_entire_binding(), self.buffers[current ^ 1].as_entire_binding()]
    }

    /// The G-buffer has no history of its own to restart: the reprojections that read last frame's test it.
    fn begin_frame(&mut self, _: &FramePlan, _: bool, _: &RenderSettings, _: &mut FrameParams) {}

    /// Every frame of the primary pass: last frame's G-buffer becomes the previous one.
    fn swap(&self) {
        self.current.fetch_xor(1, Ordering::Relaxed);
    }

    fn parity(&self) -> usize {
        self.current.load(Ordering::Relaxed)
    }
}
