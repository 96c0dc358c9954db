//! Light pool costs: one edit's incremental update at 10^3 and 10^5 lights (should not grow with the pool), and
//! the alias-table rebuild at 10^5 lights. Run: `cargo bench --bench light_pool`.

use bevy::math::{IVec3, UVec3};
use criterion::{BenchmarkId, Criterion, black_box, criterion_group, criterion_main};
use glowbrick::lights::LightPool;
use glowbrick::world::{Edit, Material, Palette, VoxelWorld};

const LAMP: u16 = 1;

/// A world of isolated single-voxel lamps on a lattice (spacing 2 in x and z, 4 in y), so each is one light.
fn lattice_world(size: UVec3) -> VoxelWorld {
    let palette = Palette::new(vec![Material::emissive("lamp", [0.9; 3], [1.0, 0.8, 0.6], 4.0)]);
    let mut world = VoxelWorld::new(size, palette);
    let s = size.as_ivec3();
    for z in (0..s.z).step_by(2) {
        for y in (0..s.y).step_by(4) {
            for x in (0..s.x).step_by(2) {
                world.apply(Edit::Place { at: IVec3::new(x, y, z), material: LAMP }).unwrap();
            }
        }
    }
    world.grid.take_dirty();
    world
}

fn apply(world: &mut VoxelWorld, pool: &mut LightPool, edit: Edit) {
    let (min, max) = edit.bounds();
    world.apply(edit).unwrap();
    pool.update_region(world, min, max);
}

fn bench_pool(c: &mut Criterion) {
    let mut group = c.benchmark_group("light_pool");
    for size in [UVec3::new(40, 16, 40), UVec3::new(160, 64, 160)] {
        let mut world = lattice_world(size);
        let mut pool = LightPool::from_world(&world);
        let lights = pool.len();
        // One edit pair per iteration: place a lamp in a gap of the lattice, then break it (pool size stays put).
        let at = IVec3::new(size.x as i32 / 2 + 1, 2, size.z as i32 / 2 + 1);
        group.bench_function(BenchmarkId::new("place_and_break_update", lights), |b| {
            b.iter(|| {
                apply(&mut world, &mut pool, Edit::Place { at, material: LAMP });
                apply(&mut world, &mut pool, Edit::Break { at });
                black_box(pool.len())
            })
        });
        group.bench_function(BenchmarkId::new("alias_rebuild", lights), |b| {
            b.iter(|| {
                pool.rebuild_alias();
                black_box(pool.alias().len())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_pool);
criterion_main!(benches);
