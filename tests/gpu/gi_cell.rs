//! The GI cache's coarse entries, through the library function that places their samples (`cell_point` of
//! `shaders/gi/direct.wgsl`) run on the GPU on a world of its own: a coarse entry stands for its whole cell, so
//! its points must not depend on which of the cell's faces inserted it (which face wins an insert is a race
//! between workgroups: docs/bench/gi.md).

use crate::compose;
use crate::gpu_world::{GpuWorld, world_layout};
use bevy::math::{IVec3, UVec3};
use bevy::render::renderer::initialize_renderer;
use bevy::render::settings::WgpuSettings;
use glowbrick::world::VoxelWorld;
use glowbrick::world::palette::{Material, Palette};
use std::borrow::Cow;
use wgpu::util::DeviceExt;

/// One query per thread: an entry (inserting voxel, face, level) and a point `u` across its cell; the answer is
/// the voxel whose face `cell_point` samples there.
const SHADER: &str = "
#import glowbrick::gi::cache::GiEntry
#import glowbrick::gi::direct::cell_point

struct Query {
    voxel: vec3<i32>,
    face: u32,
    u: vec2<f32>,
    level: u32,
    _pad: u32,
}

@group(0) @binding(100) var<storage, read> queries: array<Query>;
@group(0) @binding(101) var<storage, read_write> answers: array<vec4<i32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&queries) {
        return;
    }
    let q = queries[id.x];
    var e: GiEntry;
    e.voxel = q.voxel;
    e.face = q.face;
    e.level = q.level;
    answers[id.x] = vec4(cell_point(e, q.u).voxel, 0);
}
";

/// `Query` of the shader.
#[derive(Clone, Copy, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct Query {
    voxel: [i32; 3],
    face: u32,
    u: [f32; 2],
    level: u32,
    _pad: u32,
}

/// The voxels `cell_point` samples for `queries` in `world`.
fn sampled_voxels(world: &mut VoxelWorld, queries: &[Query]) -> Vec<IVec3> {
    let settings = WgpuSettings::default();
    let backends = settings.backends.expect("a wgpu backend");
    let resources = bevy::tasks::block_on(initialize_renderer(backends, None, &settings));
    let (device, queue) = (resources.0.wgpu_device(), &resources.1);
    let gpu_world = GpuWorld::new(device, world).expect("a small world fits");
    let layout = world_layout(device, "gi_cell", &[(100, true), (101, false)]);
    let module = compose::compose(&mut compose::composer(), "gi_cell.wgsl", SHADER);
    let shader = device.create_shader_module(wgpu::ShaderModuleDescriptor {
        label: Some("gi_cell"),
        source: wgpu::ShaderSource::Naga(Cow::Owned(module)),
    });
    let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some("gi_cell"),
        bind_group_layouts: &[Some(&layout)],
        immediate_size: 0,
    });
    let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
        label: Some("gi_cell"),
        layout: Some(&pipeline_layout),
        module: &shader,
        entry_point: Some("main"),
        compilation_options: Default::default(),
        cache: None,
    });
    let input = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
        label: Some("gi_cell_queries"),
        contents: bytemuck::cast_slice(queries),
        usage: wgpu::BufferUsages::STORAGE,
    });
    let bytes = queries.len() as u64 * 16;
    let output = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("gi_cell_answers"),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
        mapped_at_creation: false,
    });
    let readback = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("gi_cell_readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut entries = gpu_world.entries();
    entries.push(wgpu::BindGroupEntry { binding: 100, resource: input.as_entire_binding() });
    entries.push(wgpu::BindGroupEntry { binding: 101, resource: output.as_entire_binding() });
    let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("gi_cell"),
        layout: &layout,
        entries: &entries,
    });
    let mut encoder = device.create_command_encoder(&Default::default());
    {
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups((queries.len() as u32).div_ceil(64), 1, 1);
    }
    encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, bytes);
    queue.submit([encoder.finish()]);
    readback.slice(..).map_async(wgpu::MapMode::Read, |mapped| mapped.expect("readback maps"));
    device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }).expect("the GPU finishes");
    let words: Vec<i32> = bytemuck::cast_slice(&readback.slice(..).get_mapped_range()).to_vec();
    words.chunks(4).map(|w| IVec3::new(w[0], w[1], w[2])).collect()
}

/// The face index of -Y (0 +X, 1 -X, 2 +Y, 3 -Y, ...).
const DOWN: u32 = 3;

/// The white box's corner of trouble: a ceiling slab at y = 11 with a 2 x 2 block hanging under it at y = 10
/// (x, z in 9..=10), so the downward faces of the coarse cells around it lie in two planes. Their entries,
/// inserted by the block's underside or by the ceiling, sample the same voxels: the block where it hangs, the
/// ceiling elsewhere; at levels 1 to 3, over every column of the cell.
pub fn a_coarse_entry_samples_the_same_faces_whichever_face_inserted_it() {
    let mut palette = Palette::new(vec![]);
    let white = palette.push(Material::solid("white", [0.9, 0.9, 0.9]));
    let mut world = VoxelWorld::new(UVec3::new(24, 16, 24), palette);
    world.grid.fill_box(IVec3::new(0, 11, 0), IVec3::new(24, 12, 24), white).unwrap();
    world.grid.fill_box(IVec3::new(9, 10, 9), IVec3::new(11, 11, 11), white).unwrap();
    let hangs = |x: i32, z: i32| (9..=10).contains(&x) && (9..=10).contains(&z);
    let mut queries = Vec::new();
    let mut expected = Vec::new();
    for level in 1..=3u32 {
        let size = 1i32 << level;
        let cell_lo = (IVec3::new(9, 10, 9) >> level) << level;
        // The block's underside and a ceiling face away from the block, both in the cell.
        let ceiling = (cell_lo.x..cell_lo.x + size)
            .flat_map(|x| (cell_lo.z..cell_lo.z + size).map(move |z| IVec3::new(x, 11, z)))
            .find(|v| !hangs(v.x, v.z))
            .expect("the cell holds ceiling beside the block");
        for inserter in [IVec3::new(9, 10, 9), ceiling] {
            for i in 0..size {
                for j in 0..size {
                    // Face -Y's in-plane axes are z then x (tangent_axes: (axis + 1) % 3, (axis + 2) % 3).
                    let u = [(i as f32 + 0.5) / size as f32, (j as f32 + 0.5) / size as f32];
                    let (z, x) = (cell_lo.z + i, cell_lo.x + j);
                    queries.push(Query { voxel: inserter.to_array(), face: DOWN, u, level, _pad: 0 });
                    expected.push((level, inserter, IVec3::new(x, if hangs(x, z) { 10 } else { 11 }, z)));
                }
            }
        }
    }
    let sampled = sampled_voxels(&mut world, &queries);
    let wrong: Vec<_> = expected.iter().zip(&sampled).filter(|((_, _, want), got)| want != *got).collect();
    assert!(
        wrong.is_empty(),
        "{} of {} points sample another face than the one rays meet there (level, inserting voxel, want; got): {:?}",
        wrong.len(),
        sampled.len(),
        &wrong[..wrong.len().min(6)]
    );
}
