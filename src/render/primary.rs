//! The primary-ray pass (`shaders/primary.wgsl`): one ray per pixel through the brick grid and the moving
//! objects, writing the G-buffer (hit point and packed surface: face, material, object id) that every later pass
//! reads, touching the GI cache entries the camera sees, and lighting the hit itself (sun and sky, or one
//! next-event-estimation sample of the light pool) unless Voxel ReSTIR shades it. Also the debug views.
//!
//! Its per-view state is the G-buffer, this frame's and last frame's (`GBuffers`, swapped, never copied).

use super::frame::{Dispatch, VoxelPass};
use super::gpu_types::GBUFFER_TEXEL_BYTES;
use bevy::render::render_resource::{BindingResource, Buffer, BufferDescriptor, BufferUsages};
use bevy::render::renderer::RenderDevice;
use std::sync::atomic::{AtomicUsize, Ordering};

pub const PRIMARY: VoxelPass =
    VoxelPass { name: "glowbrick_primary", shader: "primary.wgsl", entry_point: "main", dispatch: Dispatch::Pixels };

/// The name the pass's GPU time is recorded under.
pub const PRIMARY_PASS_NAME: &str = PRIMARY.name;

/// A view's G-buffer (group 1, bindings 4 and 5): this frame's, which the primary pass writes, and last frame's,
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
                size: pixels * GBUFFER_TEXEL_BYTES,
                usage: BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        GBuffers {
            buffers: [buffer("glowbrick_gbuffer_a"), buffer("glowbrick_gbuffer_b")],
            current: AtomicUsize::new(0),
        }
    }

    /// Starts a frame of the primary pass: last frame's G-buffer becomes the previous one.
    pub fn swap(&self) {
        self.current.fetch_xor(1, Ordering::Relaxed);
    }

    /// Which of the two buffers is this frame's (the view's bind groups are cached by it).
    pub fn parity(&self) -> usize {
        self.current.load(Ordering::Relaxed)
    }

    /// Bindings 4 and 5 of the view's group: this frame's, then last frame's.
    pub fn bindings(&self) -> [BindingResource<'_>; 2] {
        let current = self.current.load(Ordering::Relaxed);
        [self.buffers[current].as_entire_binding(), self.buffers[current ^ 1].as_entire_binding()]
    }
}
