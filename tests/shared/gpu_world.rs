//! A world's GPU buffers for a compute shader run outside the renderer (the GPU rays bench, GPU tests of library
//! functions that read the world): group 0's world bindings filled as the renderer fills them, the brick pool in
//! the renderer's parts.

use glowbrick::render::gpu_types::WorldInfo;
use glowbrick::render::scene::world::{UploadState, fits_gpu, split_pool, stage_upload, world_info, world_interface};
use wgpu::util::DeviceExt;

/// The GPU's copy of one world: the buffers of group 0 that `trace` and `voxel_at` read (the world's part of
/// `world_interface`, by name).
pub struct GpuWorld {
    buffers: Vec<(u32, wgpu::Buffer)>,
}

impl GpuWorld {
    /// The world's buffers, or why the adapter cannot bind them.
    pub fn new(device: &wgpu::Device, world: &mut glowbrick::world::VoxelWorld) -> Result<GpuWorld, String> {
        let upload = stage_upload(world, &mut UploadState::default());
        let full = upload.full.expect("a first upload is a full one");
        let materials = upload.materials.expect("a first upload holds the materials");
        let limit = device.limits().max_storage_buffer_binding_size;
        fits_gpu(world, limit)?;
        // The pool in as many parts as the renderer makes on this adapter.
        let pool: &[u8] = bytemuck::cast_slice(&full.pool[..]);
        let (parts, pool_part_shift) = split_pool(pool, limit);
        let info = WorldInfo { pool_part_shift, ..world_info(&full, 0) };
        let storage = |label: &str, bytes: &[u8]| {
            device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
                label: Some(label),
                contents: bytes,
                usage: wgpu::BufferUsages::STORAGE,
            })
        };
        let uniform = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("gpu_world_world_info"),
            contents: bytemuck::bytes_of(&info),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let group = world_interface();
        let buffers = [
            ("world_info", uniform),
            ("top_cells", storage("gpu_world_top_cells", bytemuck::cast_slice(&full.top_cells[..]))),
            ("brick_pool", storage("gpu_world_pool", parts[0])),
            ("brick_pool_1", storage("gpu_world_pool_1", parts[1])),
            ("brick_pool_2", storage("gpu_world_pool_2", parts[2])),
            ("brick_pool_3", storage("gpu_world_pool_3", parts[3])),
            ("occupancy", storage("gpu_world_occupancy", bytemuck::cast_slice(&full.occupancy[..]))),
            ("materials", storage("gpu_world_materials", bytemuck::cast_slice(&materials[..]))),
        ];
        Ok(GpuWorld { buffers: buffers.into_iter().map(|(name, buffer)| (group.binding(name), buffer)).collect() })
    }

    /// Its bind group entries.
    pub fn entries(&self) -> Vec<wgpu::BindGroupEntry<'_>> {
        self.buffers
            .iter()
            .map(|(binding, buffer)| wgpu::BindGroupEntry { binding: *binding, resource: buffer.as_entire_binding() })
            .collect()
    }
}

/// Group 0's layout: the world's bindings (`GpuWorld`) and the caller's own storage buffers, (binding, read only).
pub fn world_layout(device: &wgpu::Device, label: &str, own: &[(u32, bool)]) -> wgpu::BindGroupLayout {
    let entry = |binding: u32, ty: wgpu::BufferBindingType| wgpu::BindGroupLayoutEntry {
        binding,
        visibility: wgpu::ShaderStages::COMPUTE,
        ty: wgpu::BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: None },
        count: None,
    };
    let storage = |read_only| wgpu::BufferBindingType::Storage { read_only };
    let group = world_interface();
    let mut entries = vec![entry(group.binding("world_info"), wgpu::BufferBindingType::Uniform)];
    let grid = ["top_cells", "brick_pool", "brick_pool_1", "brick_pool_2", "brick_pool_3", "occupancy", "materials"];
    entries.extend(grid.map(|name| entry(group.binding(name), storage(true))));
    entries.extend(own.iter().map(|&(binding, read_only)| entry(binding, storage(read_only))));
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor { label: Some(label), entries: &entries })
}
