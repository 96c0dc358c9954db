//! Render-world copy of the brick grid: storage buffers for the top grid, brick pool and materials, and the
//! bind group (group 0 of every voxel pass) over them. Updated from `PendingUploads` in `RenderSystems::
//! PrepareResources`: partial uploads write only the changed ranges.

use super::upload::{FullWorld, GpuMaterial, PendingUploads};
use crate::world::grid::BRICK_VOXELS;
use bevy::prelude::*;
use bevy::render::render_resource::binding_types::{storage_buffer_read_only_sized, uniform_buffer_sized};
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use std::num::NonZeroU64;

/// Layout of group 0 (`shaders/world.wgsl`).
pub fn world_bind_group_layout() -> BindGroupLayoutDescriptor {
    BindGroupLayoutDescriptor::new(
        "glowbrick_world_layout",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer_sized(false, NonZeroU64::new(32)),
                storage_buffer_read_only_sized(false, None),
                storage_buffer_read_only_sized(false, None),
                storage_buffer_read_only_sized(false, None),
                // Moving objects and their voxels (src/dynamic/upload.rs).
                storage_buffer_read_only_sized(false, None),
                storage_buffer_read_only_sized(false, None),
            ),
        ),
    )
}

/// The GPU world, once the first full upload arrived.
#[derive(Resource)]
pub struct GpuWorld {
    pub info: Buffer,
    pub top_cells: Buffer,
    pub brick_pool: Buffer,
    pub materials: Buffer,
    pub material_capacity: u32,
    pub bind_group: BindGroup,
    /// Bytes written to GPU buffers last frame (0 when nothing changed).
    pub uploaded_bytes: u64,
    /// Brick grid dimensions.
    pub brick_dims: UVec3,
    /// Bricks whose voxels changed this frame (the GI cache invalidates what their edits can reach).
    pub edited_bricks: Vec<UVec3>,
    /// The whole world was replaced this frame.
    pub replaced: bool,
}

/// Layout of group 0, resolved once.
#[derive(Resource)]
pub struct WorldLayout(pub BindGroupLayoutDescriptor);

/// A storage buffer initialised with `contents` that later frames can write (COPY_DST).
pub fn storage_buffer(device: &RenderDevice, label: &str, contents: &[u8]) -> Buffer {
    device.create_buffer_with_data(&BufferInitDescriptor {
        label: Some(label),
        contents,
        usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
    })
}

fn info_bytes(full: &FullWorld) -> Vec<u8> {
    let s = full.size.as_ivec3();
    let b = full.brick_dims.as_ivec3();
    bytemuck::cast_slice(&[s.x, s.y, s.z, 0, b.x, b.y, b.z, 0]).to_vec()
}

/// Voxels as the shader reads them: pairs of u16 packed little-endian into u32 words.
fn voxel_bytes(voxels: &[u16]) -> &[u8] {
    bytemuck::cast_slice(voxels)
}

fn material_buffer(device: &RenderDevice, materials: &[GpuMaterial]) -> Buffer {
    storage_buffer(device, "glowbrick_materials", bytemuck::cast_slice(materials))
}

/// Applies the queued uploads to the GPU buffers (creating them on the first full upload).
#[allow(clippy::too_many_arguments)]
pub fn prepare_gpu_world(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    pipeline_cache: Res<PipelineCache>,
    layout: Res<WorldLayout>,
    mut pending: ResMut<PendingUploads>,
    gpu: Option<ResMut<GpuWorld>>,
    objects: Option<Res<crate::dynamic::upload::GpuObjects>>,
) {
    let Some(objects) = objects else { return };
    let mut gpu = gpu;
    if let Some(gpu) = gpu.as_deref_mut() {
        gpu.uploaded_bytes = 0;
        gpu.edited_bricks.clear();
        gpu.replaced = false;
    }
    for upload in pending.0.drain(..) {
        let mut rebuild = false;
        if let Some(full) = &upload.full {
            let materials = upload.materials.as_deref().cloned().unwrap_or_else(|| vec![GpuMaterial::default()]);
            let info = device.create_buffer_with_data(&BufferInitDescriptor {
                label: Some("glowbrick_world_info"),
                contents: &info_bytes(full),
                usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
            });
            let top_cells = storage_buffer(&device, "glowbrick_top_cells", bytemuck::cast_slice(&full.top_cells));
            let brick_pool = storage_buffer(&device, "glowbrick_brick_pool", voxel_bytes(&full.pool));
            let material_capacity = materials.len() as u32;
            let materials = material_buffer(&device, &materials);
            let buffers = [&info, &top_cells, &brick_pool, &materials, &objects.objects, &objects.voxels];
            let bind_group = world_bind_group(&device, &pipeline_cache, &layout.0, buffers);
            let bytes = upload.bytes();
            let new_gpu = GpuWorld {
                info,
                top_cells,
                brick_pool,
                materials,
                material_capacity,
                bind_group,
                uploaded_bytes: bytes,
                brick_dims: full.brick_dims,
                edited_bricks: Vec::new(),
                replaced: true,
            };
            match gpu.as_deref_mut() {
                Some(existing) => *existing = new_gpu,
                None => {
                    commands.insert_resource(new_gpu);
                }
            }
            continue;
        }
        // Partial uploads need the buffers of an earlier full upload; the main world always sends one first.
        let Some(gpu) = gpu.as_deref_mut() else { continue };
        for &(index, raw) in &upload.top_cells {
            queue.write_buffer(&gpu.top_cells, index as u64 * 4, bytemuck::bytes_of(&raw));
            let d = gpu.brick_dims;
            gpu.edited_bricks.push(UVec3::new(index % d.x, index / d.x % d.y, index / (d.x * d.y)));
        }
        for (slot, voxels) in &upload.bricks {
            let offset = *slot as u64 * BRICK_VOXELS as u64 * 2;
            queue.write_buffer(&gpu.brick_pool, offset, voxel_bytes(voxels));
        }
        if let Some(materials) = &upload.materials {
            if materials.len() as u32 > gpu.material_capacity {
                gpu.materials = material_buffer(&device, materials);
                gpu.material_capacity = materials.len() as u32;
                rebuild = true;
            } else {
                queue.write_buffer(&gpu.materials, 0, bytemuck::cast_slice(materials));
            }
        }
        if rebuild {
            let buffers =
                [&gpu.info, &gpu.top_cells, &gpu.brick_pool, &gpu.materials, &objects.objects, &objects.voxels];
            gpu.bind_group = world_bind_group(&device, &pipeline_cache, &layout.0, buffers);
        }
        gpu.uploaded_bytes += upload.bytes();
    }
}

/// Group 0: world info, top cells, brick pool, materials, objects, object voxels.
fn world_bind_group(
    device: &RenderDevice,
    pipeline_cache: &PipelineCache,
    layout: &BindGroupLayoutDescriptor,
    buffers: [&Buffer; 6],
) -> BindGroup {
    device.create_bind_group(
        "glowbrick_world",
        &pipeline_cache.get_bind_group_layout(layout),
        &BindGroupEntries::sequential((
            buffers[0].as_entire_binding(),
            buffers[1].as_entire_binding(),
            buffers[2].as_entire_binding(),
            buffers[3].as_entire_binding(),
            buffers[4].as_entire_binding(),
            buffers[5].as_entire_binding(),
        )),
    )
}
