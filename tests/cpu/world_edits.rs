//! The brick grid against a dense reference array: random edits keep every voxel equal, bricks collapse and
//! re-expand, and the dirty set holds exactly the touched bricks.

use bevy::math::{IVec3, UVec3};
use glowbrick::world::grid::{BrickCell, BrickGrid, Voxel};
use glowbrick::world::{Edit, EditError, Palette, VoxelWorld};
use proptest::prelude::*;
use std::collections::BTreeSet;

/// A dense copy of the world, the obvious way.
struct Dense {
    size: IVec3,
    voxels: Vec<Voxel>,
}

impl Dense {
    fn new(size: IVec3) -> Self {
        Dense { size, voxels: vec![0; (size.x * size.y * size.z) as usize] }
    }
    fn index(&self, p: IVec3) -> usize {
        (p.x + self.size.x * (p.y + self.size.y * p.z)) as usize
    }
    fn set(&mut self, p: IVec3, v: Voxel) {
        let i = self.index(p);
        self.voxels[i] = v;
    }
}

#[derive(Clone, Debug)]
enum Op {
    Set(IVec3, Voxel),
    Fill(IVec3, IVec3, Voxel),
    /// Writes seeded pseudo-random voxels into a box (the undo path).
    Restore(IVec3, IVec3, u32),
}

const SIZE: IVec3 = IVec3::new(21, 17, 19); // not a multiple of 8: border bricks are partial

fn op_strategy() -> impl Strategy<Value = Op> {
    let pos = (0..SIZE.x, 0..SIZE.y, 0..SIZE.z).prop_map(|(x, y, z)| IVec3::new(x, y, z));
    let mat = prop_oneof![Just(0u16), 1u16..4];
    prop_oneof![
        3 => (pos.clone(), mat.clone()).prop_map(|(p, m)| Op::Set(p, m)),
        1 => (pos.clone(), pos.clone(), mat).prop_map(|(a, b, m)| Op::Fill(a.min(b), a.max(b), m)),
        1 => (pos.clone(), (0..6, 0..6, 0..6), any::<u32>()).prop_map(|(a, e, seed)| {
            Op::Restore(a, (a + IVec3::new(e.0, e.1, e.2)).min(SIZE - 1), seed)
        }),
    ]
}

fn world_with_palette(size: IVec3) -> VoxelWorld {
    let mut palette = Palette::default();
    for i in 0..3 {
        palette.push(glowbrick::world::Material::solid(&format!("m{i}"), [0.5; 3]));
    }
    VoxelWorld::new(size.as_uvec3(), palette)
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn random_edits_match_dense_reference(ops in prop::collection::vec(op_strategy(), 1..60)) {
        let mut world = world_with_palette(SIZE);
        let mut dense = Dense::new(SIZE);
        for op in &ops {
            let before: Vec<Voxel> = dense.voxels.clone();
            let (edit, lo, hi, voxels): (Edit, IVec3, IVec3, Vec<Voxel>) = match *op {
                Op::Set(p, m) => (if m == 0 { Edit::Break { at: p } } else { Edit::Place { at: p, material: m } }, p, p, vec![m]),
                Op::Fill(a, b, m) => {
                    let n = ((b - a + 1).x * (b - a + 1).y * (b - a + 1).z) as usize;
                    (Edit::FillBox { min: a, max: b, material: m }, a, b, vec![m; n])
                }
                Op::Restore(a, b, seed) => {
                    let n = ((b - a + 1).x * (b - a + 1).y * (b - a + 1).z) as usize;
                    // Runs of equal voxels, so some bricks end uniform and must collapse.
                    let voxels: Vec<Voxel> = (0..n).map(|i| (glowbrick::world::terrain::hash_u32(seed ^ (i as u32 / 37)) % 4) as Voxel).collect();
                    (Edit::Restore { min: a, max: b, voxels: voxels.clone().into() }, a, b, voxels)
                }
            };
            let mut i = 0;
            for z in lo.z..=hi.z { for y in lo.y..=hi.y { for x in lo.x..=hi.x { dense.set(IVec3::new(x, y, z), voxels[i]); i += 1; } } }
            world.grid.take_dirty();
            let changed = world.apply(edit).unwrap();
            // The reported change count and the dirty set follow exactly the voxels that changed.
            let mut expected_dirty = BTreeSet::new();
            let mut expected_changed = 0;
            for (i, (&a, &b)) in before.iter().zip(&dense.voxels).enumerate() {
                if a != b {
                    expected_changed += 1;
                    let i = i as i32;
                    let p = IVec3::new(i % SIZE.x, (i / SIZE.x) % SIZE.y, i / (SIZE.x * SIZE.y));
                    expected_dirty.insert(world.grid.brick_index(p >> 3_i32) as u32);
                }
            }
            prop_assert_eq!(changed, expected_changed);
            let dirty: BTreeSet<u32> = world.grid.take_dirty().into_iter().collect();
            prop_assert_eq!(dirty, expected_dirty);
        }
        for z in 0..SIZE.z { for y in 0..SIZE.y { for x in 0..SIZE.x {
            let p = IVec3::new(x, y, z);
            prop_assert_eq!(world.grid.get(p), dense.voxels[dense.index(p)], "voxel {:?}", p);
        } } }
        // No pooled brick is uniform: uniform bricks always collapse.
        for &raw in world.grid.top_cells() {
            if let BrickCell::Pooled(slot) = BrickCell::decode(raw) {
                let v = world.grid.pool_brick(slot);
                prop_assert!(v.iter().any(|&x| x != v[0]), "pooled brick {} is uniform", slot);
            }
        }
    }
}

#[test]
fn bricks_collapse_and_re_expand() {
    let mut grid = BrickGrid::new(UVec3::splat(16));
    let b = IVec3::ZERO;
    grid.fill_box(IVec3::ZERO, IVec3::splat(8), 2).unwrap();
    assert_eq!(grid.cell(b), BrickCell::Homogeneous(2));
    assert_eq!(grid.pooled_bricks(), 0);
    // Changing one voxel expands the brick into the pool.
    assert!(grid.set(IVec3::new(3, 4, 5), 1).unwrap());
    assert!(matches!(grid.cell(b), BrickCell::Pooled(_)));
    assert_eq!(grid.pooled_bricks(), 1);
    assert_eq!(grid.get(IVec3::new(3, 4, 5)), 1);
    assert_eq!(grid.get(IVec3::new(3, 4, 6)), 2);
    // Restoring it collapses the brick again and frees the slot for reuse.
    assert!(grid.set(IVec3::new(3, 4, 5), 2).unwrap());
    assert_eq!(grid.cell(b), BrickCell::Homogeneous(2));
    assert_eq!(grid.pooled_bricks(), 0);
    assert_eq!(grid.pool_capacity(), 1);
    grid.set(IVec3::new(9, 9, 9), 3).unwrap();
    assert_eq!(grid.pool_capacity(), 1, "the freed slot is reused");
    // Clearing a brick voxel by voxel ends as an empty cell.
    grid.set(IVec3::new(9, 9, 9), 0).unwrap();
    assert_eq!(grid.cell(IVec3::ONE), BrickCell::Empty);
    // A whole-brick fill never touches the pool.
    grid.fill_box(IVec3::splat(8), IVec3::splat(16), 4).unwrap();
    assert_eq!(grid.cell(IVec3::ONE), BrickCell::Homogeneous(4));
    assert_eq!(grid.pooled_bricks(), 0);
}

#[test]
fn box_fill_marks_exactly_the_touched_bricks() {
    let mut world = world_with_palette(IVec3::new(128, 80, 128));
    let changed =
        world.apply(Edit::FillBox { min: IVec3::new(3, 5, 7), max: IVec3::new(66, 68, 70), material: 1 }).unwrap();
    assert_eq!(changed, 64 * 64 * 64);
    let dirty = world.grid.take_dirty();
    // x 3..=66 spans bricks 0..=8, y 5..=68 bricks 0..=8, z 7..=70 bricks 0..=8: 9^3 bricks.
    assert_eq!(dirty.len(), 9 * 9 * 9);
    for index in dirty {
        let b = world.grid.brick_coord(index);
        assert!(b.cmple(IVec3::splat(8)).all(), "brick {b} outside the box");
    }
    // Refilling with the same material changes nothing and dirties nothing.
    assert_eq!(
        world.apply(Edit::FillBox { min: IVec3::new(3, 5, 7), max: IVec3::new(66, 68, 70), material: 1 }).unwrap(),
        0
    );
    assert!(world.grid.take_dirty().is_empty());
}

#[test]
fn bad_edits_are_refused_without_changing_the_world() {
    let mut world = world_with_palette(IVec3::new(16, 16, 16));
    world.apply(Edit::Place { at: IVec3::new(1, 1, 1), material: 1 }).unwrap();
    world.grid.take_dirty();
    let out = world.apply(Edit::Place { at: IVec3::new(16, 0, 0), material: 1 });
    assert!(matches!(out, Err(EditError::OutOfWorld(_))));
    let out = world.apply(Edit::Place { at: IVec3::new(-1, 0, 0), material: 1 });
    assert!(matches!(out, Err(EditError::OutOfWorld(_))));
    let out = world.apply(Edit::FillBox { min: IVec3::ZERO, max: IVec3::new(4, 4, 99), material: 1 });
    assert!(matches!(out, Err(EditError::OutOfWorld(_))));
    let out = world.apply(Edit::Place { at: IVec3::ZERO, material: 9 });
    assert_eq!(out, Err(EditError::UnknownMaterial { id: 9, palette_ids: 4 }));
    assert!(world.grid.take_dirty().is_empty());
    assert_eq!(world.summary().voxels, 1);
}
