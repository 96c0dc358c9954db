//! The primary-ray pass (`shaders/primary.wgsl`): one ray per pixel through the brick grid and the moving
//! objects, writing the G-buffer (hit point and packed surface: face, material, object id) that every later pass
//! reads, touching the GI cache entries the camera sees, and lighting the hit itself (sun and sky, or one
//! next-event-estimation sample of the light pool) unless Voxel ReSTIR shades it. Also the debug views.
//!
//! Its per-view state is the G-buffer, this frame's and last frame's (`GBuffers`).

use super::frame::{Dispatch, VoxelPass};
use super::gpu_types::GBUFFER_TEXEL_BYTES;
use bevy::render::render_resource::{BindingResource, Buffer, BufferDescriptor, BufferUsages, CommandEncoder};
use bevy::render::renderer::RenderDevice;

pub const PRIMARY: VoxelPass =
    VoxelPass { name: "glowbrick_primary", shader: "primary.wgsl", entry_point: "main", dispatch: Dispatch::Pixels };

/// The name the pass's GPU time is recorded under.
pub const PRIMARY_PASS_NAME: &str = PRIMARY.name;

/// A view's G-buffer (group 1, bindings 4 and 5): this frame's, which the primary pass writes, and last frame's,
/// which the temporal reprojections of ReSTIR and the denoiser read.
pub struct GBuffers {
    current: Buffer,
    previous: Buffer,
}

impl GBuffers {
    pub fn new(device: &RenderDevice, pixels: u64) -> Self {
        let buffer = |label: &'static str, usage: BufferUsages| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size: pixels * GBUFFER_TEXEL_BYTES,
                usage: BufferUsages::STORAGE | usage,
                mapped_at_creation: false,
            })
        };
        GBuffers {
            current: buffer("glowbrick_gbuffer", BufferUsages::COPY_SRC),
            previous: buffer("glowbrick_prev_gbuffer", BufferUsages::COPY_DST),
        }
    }

    /// Keeps last frame's G-buffer before this frame's primary pass overwrites it.
    pub fn keep_previous(&self, encoder: &mut CommandEncoder) {
        encoder.copy_buffer_to_buffer(&self.current, 0, &self.previous, 0, self.current.size());
    }

    /// Bindings 4 and 5 of the view's group.
    pub fn bindings(&self) -> [BindingResource<'_>; 2] {
        [self.current.as_entire_binding(), self.previous.as_entire_binding()]
    }
}
