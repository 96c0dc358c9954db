//! Main-world side of the GPU upload: after gameplay each frame, turn the world's dirty bricks into a small
//! upload (changed top cells and pooled bricks), or a full upload when the world was replaced or outgrew the GPU
//! buffers. The render world receives it through `extract_world_upload`.

use crate::world::grid::{BRICK_VOXELS, BrickCell, Voxel};
use crate::world::{Palette, VoxelWorld};
use bevy::prelude::*;
use bevy::render::Extract;
use std::sync::Arc;

/// One material as the shader reads it (`shaders/world.wgsl`, `Material`).
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuMaterial {
    pub albedo: [f32; 4],
    pub radiance: [f32; 4],
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
