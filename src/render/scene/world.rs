//! The brick grid on the GPU (group 0 of every voxel pass, `shaders/lib/world.wgsl`). Main world, PostUpdate:
//! `stage_world_upload` turns the world's dirty bricks into a small upload (changed top cells and pooled bricks),
//! or a full one when the world was replaced or outgrew the GPU buffers; the render world applies it in
//! `prepare_gpu_world`, writing only the changed ranges.

use super::counters::{COUNTER_BINDINGS, GpuCountersBuffer};
use super::objects::{GpuObjects, OBJECT_BINDINGS};
use super::staging::{BufferOp, Fit, Mirrored, Staging, sync, upload};
use super::storage_buffer;
use crate::render::gpu_types::{GpuMaterial, GridWindow, ONE_POOL_PART, WorldInfo};
use crate::render::interface::{GpuBinding, GroupInterface};
use crate::world::grid::{BRICK_VOXELS, BrickCell, Voxel};
use crate::world::occupancy::VOXEL_MASK_WORDS;
use crate::world::{Palette, VoxelWorld};
use bevy::prelude::*;
use bevy::render::render_asset::RenderAssets;
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::storage::GpuShaderBuffer;
use bevy::render::{Extract, ExtractSchedule, RenderApp};
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
        .insert_resource(WorldLayout(world_interface().layout()))
        .init_resource::<PendingUploads>()
        .add_systems(ExtractSchedule, extract_world_upload);
}

/// Materials indexed by voxel id (entry 0 is air).
pub fn gpu_materials(palette: &Palette) -> Vec<GpuMaterial> {
    let mut out = vec![GpuMaterial::default()];
    out.extend(palette.materials.iter().map(|m| {
        let [r, g, b] = m.albedo;
        let [er, eg, eb] = m.radiance();
        GpuMaterial { albedo: [r, g, b, m.variation], radiance: [er, eg, eb, 0.0] }
    }));
    out
}

/// Everything the GPU needs to rebuild its copy of the world.
#[derive(Debug)]
pub struct FullWorld {
    pub size: UVec3,
    pub brick_dims: UVec3,
    pub top_cells: Arc<Vec<u32>>,
    /// The occupancy masks (`world::occupancy`): bricks, then sectors, then regions, then the voxel masks of
    /// `pool_slots` pool slots (`VOXEL_MASK_WORDS` each).
    pub occupancy: Arc<Vec<u64>>,
    /// Where the sector masks, the region masks and the voxel masks start in `occupancy`, and the first two's grid
    /// sizes.
    pub occupancy_bases: (usize, usize),
    pub voxel_mask_base: usize,
    pub sector_dims: UVec3,
    pub region_dims: UVec3,
    /// The voxels `[lo, hi)` that may hold a solid one (`BrickGrid::occupied_box`).
    pub occupied: (IVec3, IVec3),
    /// Pool voxels of all slots, padded with air to `pool_slots` slots.
    pub pool: Arc<Vec<Voxel>>,
    pub pool_slots: u32,
    /// `VoxelWorld::detail_origin`.
    pub detail_origin: IVec3,
    /// The window and where its storage wraps.
    pub window: GridWindow,
}

/// This frame's changes for the GPU copy of the world.
#[derive(Resource, Clone, Debug, Default)]
pub struct WorldUpload {
    /// Rebuild everything from this (world replaced or pool outgrew its GPU buffer).
    pub full: Option<Arc<FullWorld>>,
    /// Changed top cells: (brick index, encoded cell).
    pub top_cells: Vec<(u32, u32)>,
    /// Occupancy masks an edited brick may have changed: (index in `FullWorld::occupancy`, mask).
    pub occupancy: Vec<(u32, u64)>,
    /// Changed pooled bricks: (pool slot, its voxels).
    pub bricks: Vec<(u32, Arc<[Voxel]>)>,
    /// The material table, when it changed.
    pub materials: Option<Arc<Vec<GpuMaterial>>>,
    /// The box of voxels that may hold a solid one, when an edit may have grown it.
    pub occupied: Option<(IVec3, IVec3)>,
    /// The window and where its storage wraps, with every edit (a scroll writes bricks).
    pub window: Option<GridWindow>,
    /// The bricks (window coordinates) of `top_cells`, in its order: what the GI cache's edit log is told.
    pub edited_bricks: Vec<IVec3>,
}

impl WorldUpload {
    pub fn is_empty(&self) -> bool {
        self.full.is_none() && self.top_cells.is_empty() && self.bricks.is_empty() && self.materials.is_none()
    }

    /// Bytes this upload writes to GPU buffers (for the HUD and tests).
    pub fn bytes(&self) -> u64 {
        let full = self
            .full
            .as_ref()
            .map_or(0, |f| f.top_cells.len() as u64 * 4 + f.occupancy.len() as u64 * 8 + f.pool.len() as u64 * 2);
        full + self.top_cells.len() as u64 * 4
            + self.occupancy.len() as u64 * 8
            + self.bricks.len() as u64 * BRICK_VOXELS as u64 * 2
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

/// Parts the brick pool may be split into (bindings 2, 8, 9 and 10 of group 0): a world's pool may be up to four
/// times what the GPU binds in one buffer (the 2048-wide world's 425 MiB on software Vulkan's 128 MiB).
pub const POOL_PARTS: usize = 4;

/// Bytes of one pool slot on the GPU.
const SLOT_BYTES: u64 = BRICK_VOXELS as u64 * size_of::<Voxel>() as u64;

/// Slots per pool part on a GPU that binds at most `max_binding` bytes per buffer, as a shift: the largest power
/// of two whose slots fit in one binding (a shift, so the shaders split a slot without a division).
pub fn pool_part_shift(max_binding: u64) -> u32 {
    (max_binding / SLOT_BYTES).max(1).ilog2().min(ONE_POOL_PART)
}

/// The binding a full upload of `world` needs, and the buffer that needs it: the occupancy masks with the pool's
/// voxel masks, the top grid, or one part of the brick pool with its headroom (the smallest power of two of slots
/// of which `POOL_PARTS` hold the pool).
pub fn required_binding(world: &VoxelWorld) -> (&'static str, u64) {
    let grid = &world.grid;
    let slots = u64::from(gpu_pool_slots(grid.pool_capacity()));
    let part = slots.div_ceil(POOL_PARTS as u64).next_power_of_two() * SLOT_BYTES;
    let masks = (grid.occupancy().masks().len() as u64 + slots * VOXEL_MASK_WORDS as u64) * 8;
    let top = grid.top_cells().len() as u64 * 4;
    [("brick pool", part), ("occupancy masks", masks), ("top grid", top)]
        .into_iter()
        .max_by_key(|&(_, bytes)| bytes)
        .expect("three buffers")
}

/// Bytes the GPU holds for `world`'s grid after a full upload: the brick pool (with its headroom), the
/// occupancy and voxel masks and the top grid.
pub fn world_gpu_bytes(world: &VoxelWorld) -> u64 {
    let grid = &world.grid;
    let slots = u64::from(gpu_pool_slots(grid.pool_capacity()));
    let masks = (grid.occupancy().masks().len() as u64 + slots * VOXEL_MASK_WORDS as u64) * 8;
    slots * SLOT_BYTES + masks + grid.top_cells().len() as u64 * 4
}

/// Whether a GPU that binds at most `max_binding` bytes per storage buffer can hold `world`; the error says which
/// buffer is too large and by how much. (Past the limit wgpu's validation stops the renderer, and the game with it.)
pub fn fits_gpu(world: &VoxelWorld, max_binding: u64) -> Result<(), String> {
    let (name, bytes) = required_binding(world);
    if bytes <= max_binding {
        return Ok(());
    }
    let mb = |b: u64| b as f64 / (1u64 << 20) as f64;
    let needs = if name == "brick pool" {
        format!("{POOL_PARTS} buffers of {:.0} MiB", mb(bytes))
    } else {
        format!("{:.0} MiB in one buffer", mb(bytes))
    };
    Err(format!(
        "this world is too large for this GPU: its {name} needs {needs} and the GPU binds at most {:.0} MiB per \
         buffer ({} stored bricks); try a smaller world or another GPU",
        mb(max_binding),
        world.grid.pool_capacity()
    ))
}

/// `fits_gpu` for the renderer's device.
pub fn fits_device(world: &VoxelWorld, device: &bevy::render::renderer::RenderDevice) -> Result<(), String> {
    fits_gpu(world, device.limits().max_storage_buffer_binding_size)
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
        let masks = grid.occupancy().masks();
        let mut occupancy = Vec::with_capacity(masks.len() + pool_slots as usize * VOXEL_MASK_WORDS);
        occupancy.extend_from_slice(masks);
        occupancy.extend_from_slice(grid.voxel_masks());
        occupancy.resize(masks.len() + pool_slots as usize * VOXEL_MASK_WORDS, 0);
        upload.full = Some(Arc::new(FullWorld {
            size: grid.size(),
            brick_dims: grid.brick_dims(),
            top_cells: Arc::new(grid.top_cells().to_vec()),
            occupancy: Arc::new(occupancy),
            occupancy_bases: grid.occupancy().bases(),
            voxel_mask_base: masks.len(),
            sector_dims: grid.occupancy().sector_dims(),
            region_dims: grid.occupancy().region_dims(),
            occupied: grid.occupied_box(),
            pool: Arc::new(pool),
            pool_slots,
            detail_origin: world.detail_origin,
            window: GridWindow::of(grid),
        }));
        state.world_instance = Some(world.instance);
        state.gpu_pool_slots = pool_slots;
    } else if !world.grid.dirty().is_empty() {
        let grid = &mut world.grid;
        let mut masks = std::collections::BTreeSet::new();
        let mut voxel_masks = Vec::new();
        let voxel_mask_base = grid.occupancy().masks().len();
        for index in grid.take_dirty() {
            let raw = grid.top_cells()[index as usize];
            upload.top_cells.push((index, raw));
            upload.edited_bricks.push(grid.brick_coord(index));
            masks.extend(grid.occupancy().indices_of_brick(index as usize, grid.brick_coord(index)));
            if let BrickCell::Pooled(slot) = BrickCell::decode(raw) {
                upload.bricks.push((slot, Arc::from(grid.pool_brick(slot))));
                let first = voxel_mask_base + slot as usize * VOXEL_MASK_WORDS;
                voxel_masks.extend(grid.voxel_mask(slot).iter().enumerate().map(|(k, &w)| ((first + k) as u32, w)));
            }
        }
        let all = grid.occupancy().masks();
        upload.occupancy = masks.into_iter().map(|i| (i as u32, all[i])).chain(voxel_masks).collect();
        upload.occupied = Some(grid.occupied_box());
        upload.window = Some(GridWindow::of(grid));
    }
    if replaced || state.palette.as_ref() != Some(&world.palette) {
        upload.materials = Some(Arc::new(gpu_materials(&world.palette)));
        state.palette = Some(world.palette.clone());
    }
    upload
}

/// Render-world uploads not yet written to GPU buffers, merged per buffer as they are extracted (in order) and
/// written by `prepare_gpu_world`.
#[derive(Resource, Default)]
pub struct PendingUploads {
    /// The world info of the latest full upload (its object count not yet set).
    layout: Option<WorldInfo>,
    top_cells: Staging<u32>,
    occupancy: Staging<u64>,
    pool: Staging<Voxel>,
    materials: Staging<GpuMaterial>,
    /// Bricks (window coordinates) whose top cell changed after the latest full upload.
    edited: Vec<IVec3>,
    /// The occupied box an edit left, when the batch holds no full upload (else it is in `layout`).
    occupied: Option<(IVec3, IVec3)>,
    /// The window a scroll left, likewise.
    window: Option<GridWindow>,
    /// Bytes of the uploads a later full upload did not supersede (`WorldUpload::bytes`).
    bytes: u64,
}

impl PendingUploads {
    /// Queues one frame's upload behind the ones already pending.
    pub fn push(&mut self, upload: &WorldUpload) {
        if let Some(full) = &upload.full {
            self.layout = Some(world_info(full, 0));
            self.top_cells.whole(full.top_cells.clone());
            self.occupancy.whole(full.occupancy.clone());
            self.pool.whole(full.pool.clone());
            self.edited.clear();
            self.occupied = None;
            self.window = None;
            self.bytes = 0;
        }
        for &(index, raw) in &upload.top_cells {
            self.top_cells.range(index as u64, &[raw]);
        }
        self.edited.extend_from_slice(&upload.edited_bricks);
        for &(index, mask) in &upload.occupancy {
            self.occupancy.range(index as u64, &[mask]);
        }
        if let Some(occupied) = upload.occupied {
            match &mut self.layout {
                Some(layout) => *layout = layout.with_occupied(occupied),
                None => self.occupied = Some(occupied),
            }
        }
        if let Some(window) = upload.window {
            match &mut self.layout {
                Some(layout) => *layout = layout.with_window(window),
                None => self.window = Some(window),
            }
        }
        for (slot, voxels) in &upload.bricks {
            self.pool.range(*slot as u64 * BRICK_VOXELS as u64, voxels);
        }
        // A full upload that only resized the pool carries no table: the GPU keeps the one it has.
        if let Some(materials) = &upload.materials {
            self.materials.whole(materials.clone());
        }
        self.bytes += upload.bytes();
    }

    /// The world info for the buffers to create, when the batch holds a full upload, with an air-only material
    /// table when no table came with it.
    fn prepare_creation(&mut self) -> Option<WorldInfo> {
        // Partial uploads need the buffers of a full one; the main world always sends one first.
        let layout = self.layout?;
        if !self.materials.has_whole() {
            self.materials.whole(Arc::new(vec![GpuMaterial::default()]));
        }
        Some(layout)
    }
}

/// Copies this frame's upload into the render world.
pub fn extract_world_upload(upload: Extract<Option<Res<WorldUpload>>>, mut pending: ResMut<PendingUploads>) {
    if let Some(upload) = upload.as_ref()
        && !upload.is_empty()
    {
        pending.push(upload);
    }
}

/// Group 0's world part (`shaders/lib/world.wgsl`): the uniform, the grid (top cells, the brick pool's parts in
/// order, occupancy masks) and the materials.
pub const WORLD_BINDINGS: [GpuBinding; 8] = [
    GpuBinding::uniform("world_info", size_of::<WorldInfo>()),
    GpuBinding::read("top_cells"),
    GpuBinding::read("brick_pool"),
    GpuBinding::read("brick_pool_1"),
    GpuBinding::read("brick_pool_2"),
    GpuBinding::read("brick_pool_3"),
    GpuBinding::read("occupancy"),
    GpuBinding::read("materials"),
];

/// Group 0: the world's part, then the moving objects' and the counters'.
pub fn world_interface() -> GroupInterface {
    GroupInterface::new(0, "glowbrick_world_layout", &[&WORLD_BINDINGS, &OBJECT_BINDINGS, &COUNTER_BINDINGS])
}

/// The GPU world, once the first full upload arrived.
#[derive(Resource)]
pub struct GpuWorld {
    /// `info` as last written to `info_buffer`.
    pub info: WorldInfo,
    pub info_buffer: Buffer,
    pub top_cells: Buffer,
    pub occupancy: Buffer,
    /// The brick pool's parts: `pool_bytes` in parts of 2^`pool_part_shift` slots, the unused ones placeholders.
    pub brick_pool: [Buffer; POOL_PARTS],
    pub pool_bytes: u64,
    pub pool_part_shift: u32,
    pub materials: Buffer,
    pub bind_group: BindGroup,
    /// Bytes written to GPU buffers last frame (0 when nothing changed).
    pub uploaded_bytes: u64,
    /// Brick grid dimensions.
    pub brick_dims: UVec3,
    /// Bricks whose voxels changed this frame (the GI cache invalidates what their edits can reach).
    pub edited_bricks: Vec<IVec3>,
    /// The whole world was replaced this frame.
    pub replaced: bool,
}

impl GpuWorld {
    /// Sets the moving-object count every trace loops over.
    fn set_object_count(&mut self, queue: &RenderQueue, count: u32) {
        if self.info.object_count != count {
            self.info.object_count = count;
            queue.write_buffer(&self.info_buffer, 0, bytemuck::bytes_of(&self.info));
        }
    }
}

/// Writes this frame's count of moving objects into the world's uniform (after `objects::prepare_gpu_objects`).
pub fn write_object_count(objects: Res<GpuObjects>, gpu_world: Option<ResMut<GpuWorld>>, queue: Res<RenderQueue>) {
    if let Some(mut world) = gpu_world {
        world.set_object_count(&queue, objects.count);
    }
}

/// Layout of group 0, resolved once.
#[derive(Resource)]
pub struct WorldLayout(pub BindGroupLayoutDescriptor);

/// The shaders index the whole grid and its masks (exact sizes); the materials only as far as voxels name them.
const TOP_CELLS: Mirrored = Mirrored { label: "glowbrick_top_cells", fit: Fit::Exact };
const OCCUPANCY: Mirrored = Mirrored { label: "glowbrick_occupancy", fit: Fit::Exact };
const MATERIALS: Mirrored = Mirrored { label: "glowbrick_materials", fit: Fit::AtLeast };
const BRICK_POOL_LABEL: &str = "glowbrick_brick_pool";

/// What group 0 binds next to the world's own buffers, and how to build it.
struct WorldBinding<'a> {
    device: &'a RenderDevice,
    cache: &'a PipelineCache,
    layout: &'a BindGroupLayoutDescriptor,
    objects: &'a GpuObjects,
    counters: &'a Buffer,
}

impl WorldBinding<'_> {
    fn bind(&self, gpu: &GpuWorldBuffers) -> BindGroup {
        self.device.create_bind_group(
            "glowbrick_world",
            &self.cache.get_bind_group_layout(self.layout),
            &world_interface().entries(vec![
                gpu.info.as_entire_binding(),
                gpu.top_cells.as_entire_binding(),
                gpu.brick_pool[0].as_entire_binding(),
                gpu.brick_pool[1].as_entire_binding(),
                gpu.brick_pool[2].as_entire_binding(),
                gpu.brick_pool[3].as_entire_binding(),
                gpu.occupancy.as_entire_binding(),
                gpu.materials.as_entire_binding(),
                self.objects.objects.as_entire_binding(),
                self.objects.voxels.as_entire_binding(),
                self.counters.as_entire_binding(),
            ]),
        )
    }
}

/// The buffers group 0 binds besides the objects and counters.
struct GpuWorldBuffers<'a> {
    info: &'a Buffer,
    top_cells: &'a Buffer,
    brick_pool: &'a [Buffer; POOL_PARTS],
    materials: &'a Buffer,
    occupancy: &'a Buffer,
}

/// The `WorldInfo` uniform of a full upload, for a world with `object_count` moving objects.
pub fn world_info(full: &FullWorld, object_count: u32) -> WorldInfo {
    WorldInfo {
        size: full.size.as_ivec3().to_array(),
        object_count,
        bricks: full.brick_dims.as_ivec3().to_array(),
        voxel_mask_base: full.voxel_mask_base as u32,
        sectors: full.sector_dims.as_ivec3().to_array(),
        sector_base: full.occupancy_bases.0 as u32,
        regions: full.region_dims.as_ivec3().to_array(),
        region_base: full.occupancy_bases.1 as u32,
        detail_origin: full.detail_origin.to_array(),
        ..WorldInfo::default()
    }
    .with_occupied(full.occupied)
    .with_window(full.window)
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
    let binding = WorldBinding {
        device: &device,
        cache: &pipeline_cache,
        layout: &layout.0,
        objects: &objects,
        counters: &counters.buffer,
    };
    let mut batch = std::mem::take(&mut *pending);
    match gpu.as_deref_mut() {
        Some(gpu) => apply_uploads(gpu, &mut batch, &binding, &queue),
        None => {
            if let Some(created) = create_gpu_world(&mut batch, &binding, &queue) {
                commands.insert_resource(created);
            }
        }
    }
}

/// The GPU world from a batch that holds a full upload (and whatever was queued behind it).
fn create_gpu_world(batch: &mut PendingUploads, binding: &WorldBinding, queue: &RenderQueue) -> Option<GpuWorld> {
    let info = batch.prepare_creation()?;
    let brick_dims = IVec3::from_array(info.bricks).as_uvec3();
    let device = binding.device;
    let max_binding = device.limits().max_storage_buffer_binding_size;
    let (brick_pool, pool_bytes, pool_part_shift) = upload_pool(&mut batch.pool, None, max_binding, device, queue)?;
    let info = WorldInfo { object_count: binding.objects.count, pool_part_shift, ..info };
    let info_buffer = device.create_buffer_with_data(&BufferInitDescriptor {
        label: Some("glowbrick_world_info"),
        contents: bytemuck::bytes_of(&info),
        usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
    });
    let top_cells = upload(&mut batch.top_cells, None, TOP_CELLS, device, queue)?;
    let occupancy = upload(&mut batch.occupancy, None, OCCUPANCY, device, queue)?;
    let materials = upload(&mut batch.materials, None, MATERIALS, device, queue)?;
    let bind_group = binding.bind(&GpuWorldBuffers {
        info: &info_buffer,
        top_cells: &top_cells,
        brick_pool: &brick_pool,
        materials: &materials,
        occupancy: &occupancy,
    });
    Some(GpuWorld {
        info,
        info_buffer,
        top_cells,
        occupancy,
        brick_pool,
        pool_bytes,
        pool_part_shift,
        materials,
        bind_group,
        uploaded_bytes: batch.bytes,
        brick_dims,
        edited_bricks: std::mem::take(&mut batch.edited),
        replaced: true,
    })
}

/// Writes a batch into the existing GPU world, recreating (and rebinding) the buffers whose size changed.
fn apply_uploads(gpu: &mut GpuWorld, batch: &mut PendingUploads, binding: &WorldBinding, queue: &RenderQueue) {
    let device = binding.device;
    gpu.replaced = batch.layout.is_some();
    if let Some(info) = batch.layout {
        gpu.brick_dims = IVec3::from_array(info.bricks).as_uvec3();
        gpu.info = WorldInfo { object_count: gpu.info.object_count, pool_part_shift: gpu.pool_part_shift, ..info };
    }
    if let Some(occupied) = batch.occupied {
        gpu.info = gpu.info.with_occupied(occupied);
    }
    if let Some(window) = batch.window {
        gpu.info = gpu.info.with_window(window);
    }
    if batch.layout.is_some() || batch.occupied.is_some() || batch.window.is_some() {
        queue.write_buffer(&gpu.info_buffer, 0, bytemuck::bytes_of(&gpu.info));
    }
    let mut rebind = sync(&mut batch.top_cells, &mut gpu.top_cells, TOP_CELLS, device, queue);
    rebind |= sync(&mut batch.occupancy, &mut gpu.occupancy, OCCUPANCY, device, queue);
    let current = Some(CurrentPool { parts: &gpu.brick_pool, bytes: gpu.pool_bytes, shift: gpu.pool_part_shift });
    let max_binding = device.limits().max_storage_buffer_binding_size;
    if let Some((parts, bytes, shift)) = upload_pool(&mut batch.pool, current, max_binding, device, queue) {
        (gpu.brick_pool, gpu.pool_bytes, gpu.pool_part_shift) = (parts, bytes, shift);
        rebind = true;
        if gpu.info.pool_part_shift != shift {
            gpu.info.pool_part_shift = shift;
            queue.write_buffer(&gpu.info_buffer, 0, bytemuck::bytes_of(&gpu.info));
        }
    }
    rebind |= sync(&mut batch.materials, &mut gpu.materials, MATERIALS, device, queue);
    if rebind {
        gpu.bind_group = binding.bind(&GpuWorldBuffers {
            info: &gpu.info_buffer,
            top_cells: &gpu.top_cells,
            brick_pool: &gpu.brick_pool,
            materials: &gpu.materials,
            occupancy: &gpu.occupancy,
        });
    }
    gpu.edited_bricks = std::mem::take(&mut batch.edited);
    gpu.uploaded_bytes = batch.bytes;
}

/// The pool's parts on the GPU: the buffers, the bytes they hold and the part shift they were made for.
struct CurrentPool<'a> {
    parts: &'a [Buffer; POOL_PARTS],
    bytes: u64,
    shift: u32,
}

/// The part shift of a `total`-byte pool on a GPU that binds `max_binding` bytes: one part when it fits in one
/// binding, else parts as large as a binding holds.
fn pool_shift_for(total: u64, max_binding: u64) -> u32 {
    if total <= max_binding { ONE_POOL_PART } else { pool_part_shift(max_binding) }
}

/// Writes what `pool` holds into the pool's parts (`current`), or into new ones when its size changed; returns the
/// new parts, their bytes and their part shift. Slot writes never straddle two parts.
fn upload_pool(
    pool: &mut Staging<Voxel>,
    current: Option<CurrentPool>,
    max_binding: u64,
    device: &RenderDevice,
    queue: &RenderQueue,
) -> Option<([Buffer; POOL_PARTS], u64, u32)> {
    let mut created: Option<([Buffer; POOL_PARTS], u64, u32)> = None;
    for op in pool.ops(current.as_ref().map(|c| c.bytes), Fit::Exact) {
        match op {
            BufferOp::Create(bytes) => {
                let (contents, shift) = split_pool(bytes, max_binding);
                let parts = contents.map(|part| storage_buffer(device, BRICK_POOL_LABEL, part));
                created = Some((parts, bytes.len() as u64, shift));
            }
            BufferOp::Write { offset, bytes } => {
                let target = match (&created, &current) {
                    (Some((parts, _, shift)), _) => (parts, *shift),
                    (None, Some(c)) => (c.parts, c.shift),
                    (None, None) => continue,
                };
                for (part, at, within) in split_write(offset, bytes.len() as u64, SLOT_BYTES << target.1) {
                    queue.write_buffer(&target.0[part], at, &bytes[within]);
                }
            }
        }
    }
    pool.clear();
    created
}

/// A pool's bytes as the contents of its `POOL_PARTS` buffers on a GPU that binds `max_binding` bytes, and their
/// part shift; an unused part holds a placeholder word (a binding may not be empty).
pub fn split_pool(bytes: &[u8], max_binding: u64) -> ([&[u8]; POOL_PARTS], u32) {
    let total = bytes.len() as u64;
    let shift = pool_shift_for(total, max_binding);
    let parts = std::array::from_fn(|part| {
        let range = part_range(part, total, SLOT_BYTES << shift);
        if range.is_empty() { &[0u8; 4][..] } else { &bytes[range] }
    });
    (parts, shift)
}

/// The bytes of a `total`-byte pool that part `part` holds (empty past the pool's end).
fn part_range(part: usize, total: u64, part_bytes: u64) -> std::ops::Range<usize> {
    let start = (part as u64 * part_bytes).min(total);
    let end = if part + 1 == POOL_PARTS { total } else { ((part as u64 + 1) * part_bytes).min(total) };
    start as usize..end as usize
}

/// A write of `len` bytes at pool offset `offset`, as (part, offset in the part, bytes of the write).
fn split_write(offset: u64, len: u64, part_bytes: u64) -> Vec<(usize, u64, std::ops::Range<usize>)> {
    let mut pieces = Vec::new();
    let mut done = 0;
    while done < len {
        let at = offset + done;
        let part = ((at / part_bytes) as usize).min(POOL_PARTS - 1);
        let part_start = part as u64 * part_bytes;
        let room = if part + 1 == POOL_PARTS { len - done } else { part_start + part_bytes - at };
        let n = room.min(len - done);
        pieces.push((part, at - part_start, done as usize..(done + n) as usize));
        done += n;
    }
    pieces
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::scene::staging::BufferOp;
    use crate::render::scene::staging::tests::{permutations, run};
    use crate::world::Edit;

    /// Parts are the largest power of two of slots a binding holds; writes land in the part that holds their
    /// bytes, split where they cross a part's end (a whole pool written in place), and the last part takes what
    /// lies past the others.
    #[test]
    fn pool_parts_split_slots_and_writes() {
        assert_eq!(WorldInfo::default().pool_part_shift, ONE_POOL_PART);
        assert_eq!(pool_shift_for(128 << 20, 128 << 20), ONE_POOL_PART);
        assert_eq!(pool_shift_for((128 << 20) + 1024, 128 << 20), 17);
        assert_eq!(pool_part_shift(128 << 20), 17);
        assert_eq!(pool_part_shift((128 << 20) - 1), 16);
        assert_eq!(pool_part_shift(u32::MAX as u64), 21);
        assert_eq!(pool_part_shift(u64::MAX), ONE_POOL_PART);
        assert_eq!(pool_part_shift(1), 0);
        let part = 4 * SLOT_BYTES;
        assert_eq!(split_write(part - SLOT_BYTES, SLOT_BYTES, part), vec![(0, 3 * SLOT_BYTES, 0..1024)]);
        assert_eq!(split_write(part, SLOT_BYTES, part), vec![(1, 0, 0..1024)]);
        let whole = 2 * part + part / 2;
        let (p, w) = (part as usize, whole as usize);
        assert_eq!(split_write(0, whole, part), vec![(0, 0, 0..p), (1, 0, p..2 * p), (2, 0, 2 * p..w)]);
        assert_eq!(split_write(5 * part, 8, part), vec![(3, 2 * part, 0..8)]);
        let ranges: Vec<_> = (0..POOL_PARTS).map(|i| part_range(i, whole, part)).collect();
        assert_eq!(ranges, vec![0..p, p..2 * p, 2 * p..w, w..w]);
        assert_eq!(part_range(3, 6 * part, part), 3 * p..6 * p);
    }

    /// The GPU world's buffers as `prepare_gpu_world` leaves them, on the CPU.
    #[derive(Default)]
    struct SimulatedGpu {
        top_cells: Option<Vec<u8>>,
        occupancy: Option<Vec<u8>>,
        pool: Option<Vec<u8>>,
        materials: Option<Vec<u8>>,
    }

    impl SimulatedGpu {
        /// Writes a batch the way `create_gpu_world` / `apply_uploads` do.
        fn drain(&mut self, batch: &mut PendingUploads) {
            if self.top_cells.is_none() && batch.prepare_creation().is_none() {
                return;
            }
            let size = |b: &Option<Vec<u8>>| b.as_ref().map(|b| b.len() as u64);
            let ops: Vec<BufferOp> = batch.top_cells.ops(size(&self.top_cells), Fit::Exact);
            run(&ops, &mut self.top_cells);
            run(&batch.occupancy.ops(size(&self.occupancy), Fit::Exact), &mut self.occupancy);
            run(&batch.pool.ops(size(&self.pool), Fit::Exact), &mut self.pool);
            run(&batch.materials.ops(size(&self.materials), Fit::AtLeast), &mut self.materials);
            *batch = PendingUploads::default();
        }

        fn assert_holds(&self, world: &VoxelWorld, order: &[Change]) {
            let top_cells = self.top_cells.as_ref().expect("top cells");
            assert_eq!(top_cells.as_slice(), bytemuck::cast_slice::<u32, u8>(world.grid.top_cells()), "{order:?}");
            let occupancy = self.occupancy.as_ref().expect("occupancy");
            let masks = world.grid.occupancy().masks();
            let expected: &[u8] = bytemuck::cast_slice(masks);
            assert_eq!(&occupancy[..expected.len()], expected, "occupancy after {order:?}");
            // The voxel masks of the slots in use (a free slot's is never read).
            for &raw in world.grid.top_cells() {
                if let BrickCell::Pooled(slot) = BrickCell::decode(raw) {
                    let first = (masks.len() + slot as usize * VOXEL_MASK_WORDS) * 8;
                    let expected: &[u8] = bytemuck::cast_slice(world.grid.voxel_mask(slot));
                    let held = &occupancy[first..first + expected.len()];
                    assert_eq!(held, expected, "voxel mask of slot {slot} after {order:?}");
                }
            }
            let pool = self.pool.as_ref().expect("pool");
            let expected = voxel_bytes(world.grid.pool());
            assert_eq!(&pool[..expected.len()], expected, "pool after {order:?}");
            let materials = self.materials.as_ref().expect("materials");
            let expected = gpu_materials(&world.palette);
            let expected: &[u8] = bytemuck::cast_slice(&expected);
            assert_eq!(&materials[..expected.len()], expected, "materials after {order:?}");
        }
    }

    fn voxel_bytes(voxels: &[Voxel]) -> &[u8] {
        bytemuck::cast_slice(voxels)
    }

    /// One change to the main world, each staged as its own frame's upload.
    #[derive(Clone, Copy, Debug)]
    enum Change {
        /// A voxel in one brick: a partial upload.
        Place(IVec3),
        /// More pooled bricks than the GPU pool holds: a full upload without a material table.
        Grow,
        /// A material's colour: the table alone.
        Recolour,
        /// A new, smaller world: a full upload with the table.
        Replace,
    }

    fn brick_corner(i: i32) -> IVec3 {
        IVec3::new(i % 9 * 8, 0, i / 9 * 8)
    }

    fn apply(change: Change, world: &mut VoxelWorld) {
        match change {
            Change::Place(at) => {
                world.apply(Edit::Place { at, material: 2 }).unwrap();
            }
            Change::Grow => {
                for i in 0..70 {
                    world.apply(Edit::Place { at: brick_corner(i) + IVec3::ONE, material: 1 }).unwrap();
                }
            }
            Change::Recolour => world.palette.materials[0].albedo[0] += 0.25,
            Change::Replace => *world = VoxelWorld::new(UVec3::new(72, 8, 80), world.palette.clone()),
        }
    }

    /// Full and partial world uploads queued in every order, drained in one or two batches, into a GPU world
    /// that exists already or is created by the first full upload in the batch: the GPU holds the CPU world's
    /// bytes. Partial uploads behind the creating full upload, and the material table across a full upload that
    /// only grew the pool, both survive.
    #[test]
    fn every_order_of_world_uploads_leaves_the_world_bytes() {
        let changes = [
            Change::Place(IVec3::new(3, 3, 3)),
            Change::Place(IVec3::new(20, 4, 12)),
            Change::Grow,
            Change::Recolour,
            Change::Replace,
        ];
        for order in permutations(&changes) {
            for split in 0..=order.len() {
                for created_before in [false, true] {
                    let mut world = VoxelWorld::new(UVec3::new(80, 8, 80), Palette::default_blocks());
                    let mut state = UploadState::default();
                    let mut gpu = SimulatedGpu::default();
                    let mut pending = PendingUploads::default();
                    pending.push(&stage_upload(&mut world, &mut state));
                    if created_before {
                        gpu.drain(&mut pending);
                    }
                    for (i, &change) in order.iter().enumerate() {
                        if i == split {
                            gpu.drain(&mut pending);
                            gpu.assert_holds(&world, &order[..i]);
                        }
                        apply(change, &mut world);
                        pending.push(&stage_upload(&mut world, &mut state));
                    }
                    gpu.drain(&mut pending);
                    gpu.assert_holds(&world, &order);
                }
            }
        }
    }
}
