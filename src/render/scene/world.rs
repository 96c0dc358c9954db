//! The brick grid on the GPU (group 0 of every voxel pass, `shaders/lib/world.wgsl`). Main world, PostUpdate:
//! `stage_world_upload` turns the world's dirty bricks into a small upload (changed top cells and pooled bricks),
//! or a full one when the world was replaced or outgrew the GPU buffers; the render world applies it in
//! `prepare_gpu_world`, writing only the changed ranges.

use super::counters::GpuCountersBuffer;
use super::objects::GpuObjects;
use super::storage_buffer;
use crate::render::gpu_types::{GpuMaterial, WorldInfo};
use crate::world::grid::{BRICK_VOXELS, BrickCell, Voxel};
use crate::world::{Palette, VoxelWorld};
use bevy::prelude::*;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, storage_buffer_sized, uniform_buffer_sized,
};
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::storage::GpuShaderBuffer;
use bevy::render::{Extract, ExtractSchedule, RenderApp};
use std::num::NonZeroU64;
use std::sync::Arc;

/// Stages the world's dirty bricks (main world) and keeps its GPU copy (render world).
pub struct WorldUploadPlugin;

impl Plugin for WorldUploadPlugin {
    fn build(&self, app: &mut App) {
        add(app);
    }
}

fn add(app: &mut App) {
    app.init_resource::<UploadState>()
        .init_resource::<WorldUpload>()
        .add_systems(PostUpdate, stage_world_upload.run_if(resource_exists::<VoxelWorld>));
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
    render_app
        .insert_resource(WorldLayout(world_bind_group_layout()))
        .init_resource::<PendingUploads>()
        .add_systems(ExtractSchedule, extract_world_upload);
}

/// Materials indexed by voxel id (entry 0 is air).
pub fn gpu_materials(palette: &Palette) -> Vec<GpuMaterial> {
    let mut out = vec![GpuMaterial::default()];
    out.extend(palette.materials.iter().map(|m| {
        let [r, g, b] = m.albedo;
        let [er, eg, eb] = m.radiance();
        GpuMaterial { albedo: [r, g, b, 0.0], radiance: [er, eg, eb, 0.0] }
    }));
    out
}

/// Everything the GPU needs to rebuild its copy of the world.
#[derive(Debug)]
pub struct FullWorld {
    pub size: UVec3,
    pub brick_dims: UVec3,
    pub top_cells: Vec<u32>,
    /// Pool voxels of all slots, padded with air to `pool_slots` slots.
    pub pool: Vec<Voxel>,
    pub pool_slots: u32,
}

/// This frame's changes for the GPU copy of the world.
#[derive(Resource, Clone, Debug, Default)]
pub struct WorldUpload {
    /// Rebuild everything from this (world replaced or pool outgrew its GPU buffer).
    pub full: Option<Arc<FullWorld>>,
    /// Changed top cells: (brick index, encoded cell).
    pub top_cells: Vec<(u32, u32)>,
    /// Changed pooled bricks: (pool slot, its voxels).
    pub bricks: Vec<(u32, Arc<[Voxel]>)>,
    /// The material table, when it changed.
    pub materials: Option<Arc<Vec<GpuMaterial>>>,
}

impl WorldUpload {
    pub fn is_empty(&self) -> bool {
        self.full.is_none() && self.top_cells.is_empty() && self.bricks.is_empty() && self.materials.is_none()
    }

    /// Bytes this upload writes to GPU buffers (for the HUD and tests).
    pub fn bytes(&self) -> u64 {
        let full = self.full.as_ref().map_or(0, |f| f.top_cells.len() as u64 * 4 + f.pool.len() as u64 * 2);
        full + self.top_cells.len() as u64 * 4 + self.bricks.len() as u64 * BRICK_VOXELS as u64 * 2
    }
}

/// What the GPU already holds, so each frame sends only the difference.
#[derive(Resource, Default)]
pub struct UploadState {
    world_instance: Option<u64>,
    gpu_pool_slots: u32,
    palette: Option<Palette>,
}

/// Pool slots to allocate on the GPU for `needed` slots: headroom so growth rarely forces a full upload.
pub fn gpu_pool_slots(needed: u32) -> u32 {
    (needed + needed / 2 + 64).max(64)
}

/// Stages this frame's upload from the world's dirty set (PostUpdate, after all edits).
pub fn stage_world_upload(
    mut world: ResMut<VoxelWorld>,
    mut state: ResMut<UploadState>,
    mut upload: ResMut<WorldUpload>,
) {
    *upload = stage_upload(&mut world, &mut state);
}

/// This frame's upload for `world` given what the GPU already holds; clears the world's dirty set.
pub fn stage_upload(world: &mut VoxelWorld, state: &mut UploadState) -> WorldUpload {
    let mut upload = WorldUpload::default();
    let needed_slots = world.grid.pool_capacity();
    let replaced = state.world_instance != Some(world.instance);
    if replaced || needed_slots > state.gpu_pool_slots {
        let grid = &mut world.grid;
        grid.take_dirty();
        let pool_slots = gpu_pool_slots(needed_slots);
        let mut pool = grid.pool().to_vec();
        pool.resize(pool_slots as usize * BRICK_VOXELS, 0);
        upload.full = Some(Arc::new(FullWorld {
            size: grid.size(),
            brick_dims: grid.brick_dims(),
            top_cells: grid.top_cells().to_vec(),
            pool,
            pool_slots,
        }));
        state.world_instance = Some(world.instance);
        state.gpu_pool_slots = pool_slots;
    } else if !world.grid.dirty().is_empty() {
        let grid = &mut world.grid;
        for index in grid.take_dirty() {
            let raw = grid.top_cells()[index as usize];
            upload.top_cells.push((index, raw));
            if let BrickCell::Pooled(slot) = BrickCell::decode(raw) {
                upload.bricks.push((slot, Arc::from(grid.pool_brick(slot))));
            }
        }
    }
    if replaced || state.palette.as_ref() != Some(&world.palette) {
        upload.materials = Some(Arc::new(gpu_materials(&world.palette)));
        state.palette = Some(world.palette.clone());
    }
    upload
}

/// Render-world queue of uploads not yet written to GPU buffers (applied in order by `prepare_gpu_world`).
#[derive(Resource, Default)]
pub struct PendingUploads(pub Vec<WorldUpload>);

/// Copies this frame's upload into the render world.
pub fn extract_world_upload(upload: Extract<Option<Res<WorldUpload>>>, mut pending: ResMut<PendingUploads>) {
    if let Some(upload) = upload.as_ref()
        && !upload.is_empty()
    {
        pending.0.push((**upload).clone());
    }
}

/// Layout of group 0 (`shaders/lib/world.wgsl`, `shaders/lib/counters.wgsl`).
pub fn world_bind_group_layout() -> BindGroupLayoutDescriptor {
    BindGroupLayoutDescriptor::new(
        "glowbrick_world_layout",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                uniform_buffer_sized(false, NonZeroU64::new(size_of::<WorldInfo>() as u64)),
                storage_buffer_read_only_sized(false, None),
                storage_buffer_read_only_sized(false, None),
                storage_buffer_read_only_sized(false, None),
                // Moving objects and their voxels (`super::objects`).
                storage_buffer_read_only_sized(false, None),
                storage_buffer_read_only_sized(false, None),
                // Counters (`super::counters`).
                storage_buffer_sized(false, None),
            ),
        ),
    )
}

/// The GPU world, once the first full upload arrived.
#[derive(Resource)]
pub struct GpuWorld {
    /// `info` as last written to `info_buffer`.
    pub info: WorldInfo,
    pub info_buffer: Buffer,
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

impl GpuWorld {
    /// Sets the moving-object count every trace loops over.
    pub fn set_object_count(&mut self, queue: &RenderQueue, count: u32) {
        if self.info.object_count != count {
            self.info.object_count = count;
            queue.write_buffer(&self.info_buffer, 0, bytemuck::bytes_of(&self.info));
        }
    }
}

/// Layout of group 0, resolved once.
#[derive(Resource)]
pub struct WorldLayout(pub BindGroupLayoutDescriptor);

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
    mut gpu: Option<ResMut<GpuWorld>>,
    objects: Option<Res<GpuObjects>>,
    counters: Option<Res<GpuCountersBuffer>>,
    shader_buffers: Res<RenderAssets<GpuShaderBuffer>>,
) {
    // The bind group needs the object and counter buffers; until they exist the uploads wait.
    let Some(objects) = objects else { return };
    let Some(counters) = counters.and_then(|c| shader_buffers.get(&c.0)) else { return };
    if let Some(gpu) = gpu.as_deref_mut() {
        gpu.uploaded_bytes = 0;
        gpu.edited_bricks.clear();
        gpu.replaced = false;
    }
    let bind = |gpu_buffers: [&Buffer; 4]| {
        let [info, top_cells, brick_pool, materials] = gpu_buffers;
        device.create_bind_group(
            "glowbrick_world",
            &pipeline_cache.get_bind_group_layout(&layout.0),
            &BindGroupEntries::sequential((
                info.as_entire_binding(),
                top_cells.as_entire_binding(),
                brick_pool.as_entire_binding(),
                materials.as_entire_binding(),
                objects.objects.as_entire_binding(),
                objects.voxels.as_entire_binding(),
                counters.buffer.as_entire_binding(),
            )),
        )
    };
    for upload in pending.0.drain(..) {
        if let Some(full) = &upload.full {
            let materials = upload.materials.as_deref().cloned().unwrap_or_else(|| vec![GpuMaterial::default()]);
            let info = WorldInfo {
                size: full.size.as_ivec3().to_array(),
                object_count: objects.count,
                bricks: full.brick_dims.as_ivec3().to_array(),
                _pad: 0,
            };
            let info_buffer = device.create_buffer_with_data(&BufferInitDescriptor {
                label: Some("glowbrick_world_info"),
                contents: bytemuck::bytes_of(&info),
                usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
            });
            let top_cells = storage_buffer(&device, "glowbrick_top_cells", bytemuck::cast_slice(&full.top_cells));
            let brick_pool = storage_buffer(&device, "glowbrick_brick_pool", voxel_bytes(&full.pool));
            let material_capacity = materials.len() as u32;
            let materials = material_buffer(&device, &materials);
            let bind_group = bind([&info_buffer, &top_cells, &brick_pool, &materials]);
            let new_gpu = GpuWorld {
                info,
                info_buffer,
                top_cells,
                brick_pool,
                materials,
                material_capacity,
                bind_group,
                uploaded_bytes: upload.bytes(),
                brick_dims: full.brick_dims,
                edited_bricks: Vec::new(),
                replaced: true,
            };
            match gpu.as_deref_mut() {
                Some(existing) => *existing = new_gpu,
                None => commands.insert_resource(new_gpu),
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
                gpu.bind_group = bind([&gpu.info_buffer, &gpu.top_cells, &gpu.brick_pool, &gpu.materials]);
            } else {
                queue.write_buffer(&gpu.materials, 0, bytemuck::cast_slice(materials));
            }
        }
        gpu.uploaded_bytes += upload.bytes();
    }
}
