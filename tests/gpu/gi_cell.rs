//! The GI cache's coarse entries, through the library function that places their samples (`cell_point` of
//! `shaders/gi/direct.wgsl`) run on the GPU on a world of its own: a coarse entry stands for its whole cell, so
//! its points must not depend on which of the cell's faces inserted it (which face wins an insert is a race
//! between workgroups: docs/bench/gi.md).

use crate::gpu_world::{GpuWorld, world_layout};
use crate::{compose, compute};
use bevy::math::{IVec3, UVec3};
use bevy::render::renderer::initialize_renderer;
use bevy::render::settings::WgpuSettings;
use glowbrick::world::VoxelWorld;
use glowbrick::world::palette::{Material, Palette};

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
    let layout = world_layout(device, "gi_cell", &[(compute::INPUT_BINDING, true), (compute::OUTPUT_BINDING, false)]);
    let module = compose::compose(&mut compose::composer(), "gi_cell.wgsl", SHADER);
    let pipeline = compute::pipeline(device, "gi_cell", module, Some(&layout));
    let io = compute::Io::new(device, "gi_cell", bytemuck::cast_slice(queries), queries.len() as u64 * 16);
    let bind_group = io.bind_group(device, "gi_cell", &layout, gpu_world.entries());
    let answers = compute::run_and_read(device, queue, &pipeline, &bind_group, queries.len() as u32, &io);
    // Each answer is a vec4<i32>: the voxel, then padding.
    let words: Vec<i32> = answers.chunks_exact(4).map(bytemuck::pod_read_unaligned).collect();
    words.chunks_exact(4).map(|w| IVec3::new(w[0], w[1], w[2])).collect()
}

/// The face indices of +Y and -Y (0 +X, 1 -X, 2 +Y, 3 -Y, ...).
const UP: u32 = 2;
const DOWN: u32 = 3;

/// The white box's corner of trouble and a few columns around it. Under a ceiling slab at y = 11 a 2 x 2 block
/// hangs at y = 10 (x, z in 9..=10), so the downward faces of the coarse cells around it lie in two planes; a lone
/// voxel at (11, 8, 11) faces down below them; the ceiling has a hole at (14, 11, 14); a stack at (8, 7..=8, 11)
/// is covered from below. Beside them, a floor (y 0..=2) with a bump at (19, 3, 19) faces up. The entries of a
/// cell, inserted by any of its faces, sample the same voxels in each column: its outermost face seen from where
/// the face looks (the lone voxel before the ceiling; the block where it hangs; the bump on the floor); where
/// the column holds none that can be seen (the hole; the covered stack), the inserting face; at levels 1 to 3.
pub fn a_coarse_entry_samples_the_same_faces_whichever_face_inserted_it() {
    let mut palette = Palette::new(vec![]);
    let white = palette.push(Material::solid("white", [0.9, 0.9, 0.9]));
    let mut world = VoxelWorld::new(UVec3::new(24, 16, 24), palette);
    let mut fill = |lo: [i32; 3], hi: [i32; 3], id| world.grid.fill_box(IVec3::from(lo), IVec3::from(hi), id).unwrap();
    fill([0, 11, 0], [24, 12, 24], white);
    fill([9, 10, 9], [11, 11, 11], white);
    fill([11, 8, 11], [12, 9, 12], white);
    fill([14, 11, 14], [15, 12, 15], 0);
    fill([8, 7, 11], [9, 9, 12], white);
    fill([0, 0, 0], [24, 3, 24], white);
    fill([19, 3, 19], [20, 4, 20], white);
    // The voxel whose face each column of a cell shows (None: no face is seen there), by face and column.
    let seen = |face: u32, x: i32, z: i32| -> Option<i32> {
        if face == UP {
            return Some(if (x, z) == (19, 19) { 3 } else { 2 });
        }
        match (x, z) {
            (11, 11) => Some(8),
            (14, 14) | (8, 11) => None,
            _ if (9..=10).contains(&x) && (9..=10).contains(&z) => Some(10),
            _ => Some(11),
        }
    };
    let cases = [(DOWN, IVec3::new(9, 10, 9)), (UP, IVec3::new(19, 3, 19))];
    let mut queries = Vec::new();
    let mut expected = Vec::new();
    for (face, corner) in cases {
        for level in 1..=3u32 {
            let size = 1i32 << level;
            let cell_lo = (corner >> level) << level;
            let columns: Vec<(i32, i32)> =
                (0..size).flat_map(|i| (0..size).map(move |j| (cell_lo.z + i, cell_lo.x + j))).collect();
            let in_cell = |v: IVec3| (v.y >> level) << level == cell_lo.y;
            // The cell's faces of this orientation: every one may insert its entry.
            let faces: Vec<IVec3> = columns
                .iter()
                .filter_map(|&(z, x)| seen(face, x, z).map(|y| IVec3::new(x, y, z)))
                .filter(|&v| in_cell(v))
                .collect();
            assert!(faces.len() >= 2, "the cell holds faces in two planes at least");
            for &inserter in &faces {
                for (k, &(z, x)) in columns.iter().enumerate() {
                    // Face ±Y's in-plane axes are z then x (tangent_axes: (axis + 1) % 3, (axis + 2) % 3).
                    let (i, j) = (k as i32 / size, k as i32 % size);
                    let u = [(i as f32 + 0.5) / size as f32, (j as f32 + 0.5) / size as f32];
                    queries.push(Query { voxel: inserter.to_array(), face, u, level, _pad: 0 });
                    let want = match seen(face, x, z).map(|y| IVec3::new(x, y, z)) {
                        Some(v) if in_cell(v) => v,
                        _ => inserter,
                    };
                    expected.push((face, level, inserter, want));
                }
            }
        }
    }
    let sampled = sampled_voxels(&mut world, &queries);
    let wrong: Vec<_> = expected.iter().zip(&sampled).filter(|((.., want), got)| want != *got).collect();
    assert!(
        wrong.is_empty(),
        "{} of {} points sample another face than the one rays meet there (face, level, inserting voxel, want; \
         got): {:?}",
        wrong.len(),
        sampled.len(),
        &wrong[..wrong.len().min(6)]
    );
}
