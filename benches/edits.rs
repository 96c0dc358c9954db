//! The cost of an edit follows the edit, not the world: one voxel and a 64^3 box fill in a 256^3 world and in a
//! 1024 x 256 x 1024 world, each measured as CPU apply + light-pool update + GPU upload staging. The bytes each
//! edit sends to the GPU are printed once per world. Run: `cargo bench --bench edits`.

use bevy::math::{IVec3, UVec3};
use criterion::{BenchmarkId, Criterion, black_box, criterion_group, criterion_main};
use glowbrick::lights::LightPool;
use glowbrick::render::scene::world::{UploadState, stage_upload};
use glowbrick::world::{Edit, Palette, VoxelWorld};

/// A world with a stone floor (8 voxels thick) and a lamp every 16 voxels on it.
fn floored_world(size: UVec3) -> VoxelWorld {
    let mut world = VoxelWorld::new(size, Palette::default_blocks());
    let s = size.as_ivec3();
    world.apply(Edit::FillBox { min: IVec3::ZERO, max: IVec3::new(s.x - 1, 7, s.z - 1), material: 1 }).unwrap();
    for z in (4..s.z).step_by(16) {
        for x in (4..s.x).step_by(16) {
            world.apply(Edit::Place { at: IVec3::new(x, 8, z), material: 10 }).unwrap();
        }
    }
    world
}

/// One edit through the game's path: apply, update the lights around it, stage the GPU upload.
fn edit_once(world: &mut VoxelWorld, pool: &mut LightPool, state: &mut UploadState, edit: Edit) -> u64 {
    let (min, max) = edit.bounds();
    world.apply(edit).unwrap();
    pool.update_region(world, min, max);
    stage_upload(world, state).bytes()
}

fn bench_edits(c: &mut Criterion) {
    let mut group = c.benchmark_group("edits");
    group.sample_size(20);
    for size in [UVec3::new(256, 256, 256), UVec3::new(1024, 256, 1024)] {
        let label = format!("{}x{}x{}", size.x, size.y, size.z);
        let mut world = floored_world(size);
        let mut pool = LightPool::from_world(&world);
        let mut state = UploadState::default();
        stage_upload(&mut world, &mut state); // the first, full upload
        let at = IVec3::new(100, 20, 100);
        let place = Edit::Place { at, material: 7 };
        let (lo, hi) = (IVec3::new(64, 9, 64), IVec3::new(127, 72, 127));
        let fill = Edit::FillBox { min: lo, max: hi, material: 7 };
        let clear = Edit::FillBox { min: lo, max: hi, material: 0 };
        let voxel_bytes = edit_once(&mut world, &mut pool, &mut state, place.clone())
            + edit_once(&mut world, &mut pool, &mut state, Edit::Break { at });
        let fill_bytes = edit_once(&mut world, &mut pool, &mut state, fill.clone());
        edit_once(&mut world, &mut pool, &mut state, clear.clone());
        println!("{label}: place+break uploads {voxel_bytes} bytes, 64^3 fill uploads {fill_bytes} bytes");
        group.bench_function(BenchmarkId::new("place_and_break", &label), |b| {
            b.iter(|| {
                edit_once(&mut world, &mut pool, &mut state, place.clone());
                black_box(edit_once(&mut world, &mut pool, &mut state, Edit::Break { at }))
            })
        });
        group.bench_function(BenchmarkId::new("fill_64_cubed_and_clear", &label), |b| {
            b.iter(|| {
                edit_once(&mut world, &mut pool, &mut state, fill.clone());
                black_box(edit_once(&mut world, &mut pool, &mut state, clear.clone()))
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_edits);
criterion_main!(benches);
