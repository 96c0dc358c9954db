//! The light pool follows the world exactly and incrementally; stale references are detected; the alias table
//! samples in proportion to power.

use bevy::math::{IVec3, UVec3};
use glowbrick::lights::{AliasTable, LightKey, LightPool};
use glowbrick::world::{Edit, Material, Palette, VoxelWorld};
use proptest::prelude::*;
use std::collections::BTreeSet;

const STONE: u16 = 1;
const WARM: u16 = 2;
const BLUE: u16 = 3;

fn palette() -> Palette {
    Palette::new(vec![
        Material::solid("stone", [0.5; 3]),
        Material::emissive("warm", [0.9; 3], [1.0, 0.7, 0.4], 5.0),
        Material::emissive("blue", [0.5; 3], [0.2, 0.4, 1.0], 0.5),
    ])
}

/// The pool as a comparable set: (key, min, size, material, exposed area).
fn as_set(pool: &LightPool) -> BTreeSet<(bool, [i32; 3], i32, u16, u32)> {
    pool.lights()
        .map(|(_, l)| {
            (matches!(l.key, LightKey::Brick(_)), l.min.to_array(), l.size, l.material, l.exposed_area as u32)
        })
        .collect()
}

/// Applies an edit and updates the pool incrementally, as the game's edit path does.
fn edit(world: &mut VoxelWorld, pool: &mut LightPool, e: Edit) {
    let (min, max) = e.bounds();
    if world.apply(e).unwrap() > 0 {
        pool.update_region(world, min, max);
    }
}

fn edit_strategy() -> impl Strategy<Value = Edit> {
    let pos = (0..24, 0..24, 0..24).prop_map(|(x, y, z)| IVec3::new(x, y, z));
    let material = prop_oneof![Just(0u16), Just(STONE), Just(WARM), Just(BLUE)];
    prop_oneof![
        4 => (pos.clone(), material.clone()).prop_map(|(at, m)| if m == 0 { Edit::Break { at } } else { Edit::Place { at, material: m } }),
        1 => (pos.clone(), (0..5, 0..5, 0..5), material.clone()).prop_map(|(min, e, m)| {
            Edit::FillBox { min, max: (min + IVec3::new(e.0, e.1, e.2)).min(IVec3::splat(23)), material: m }
        }),
        // Whole aligned bricks make and unmake brick lights.
        1 => ((0..3, 0..3, 0..3), material).prop_map(|(b, m)| {
            let min = IVec3::new(b.0, b.1, b.2) * 8;
            Edit::FillBox { min, max: min + IVec3::splat(7), material: m }
        }),
    ]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(150))]

    #[test]
    fn incremental_pool_equals_full_rescan(edits in prop::collection::vec(edit_strategy(), 1..50)) {
        let mut world = VoxelWorld::new(UVec3::splat(24), palette());
        let mut pool = LightPool::from_world(&world);
        for e in edits {
            edit(&mut world, &mut pool, e);
        }
        let mut rescan = LightPool::from_world(&world);
        prop_assert_eq!(as_set(&pool), as_set(&rescan));
        prop_assert_eq!(pool.counts(), rescan.counts());
        // The light bricks (what lets ReSTIR skip its local-light scan) are those of a rescan, and mark every
        // light's brick.
        prop_assert_eq!(pool.light_bricks(), rescan.light_bricks());
        let bricks = pool.light_bricks().clone();
        for (_, light) in pool.lights() {
            prop_assert!(bricks.contains(light.min >> 3_i32));
        }
        // The light index (what ReSTIR's local candidates look up) finds every light at its own slot after the
        // edits, and nothing where there is no light.
        let index = pool.light_index().clone();
        let alias = pool.alias().clone();
        let cube = |slot: u32| pool.cube(slot);
        for (slot, light) in pool.lights() {
            let column = index.find(&alias, cube, light.min, light.size);
            prop_assert_eq!(column.map(|c| alias.entries[c as usize].slot), Some(slot));
        }
        for x in 0..24 {
            for y in 0..24 {
                let p = IVec3::new(x, y, 7);
                let is_light = pool.find(LightKey::Voxel(p)).is_some();
                prop_assert_eq!(index.find(&alias, cube, p, 1).is_some(), is_light);
            }
        }
    }
}

#[test]
fn reused_slot_gets_a_new_generation_and_old_refs_go_stale() {
    let mut world = VoxelWorld::new(UVec3::splat(16), palette());
    let mut pool = LightPool::from_world(&world);
    edit(&mut world, &mut pool, Edit::Place { at: IVec3::new(2, 2, 2), material: WARM });
    let old = pool.find(LightKey::Voxel(IVec3::new(2, 2, 2))).unwrap();
    assert_eq!(pool.get(old).unwrap().material, WARM);
    edit(&mut world, &mut pool, Edit::Break { at: IVec3::new(2, 2, 2) });
    assert!(pool.get(old).is_none(), "a removed light is stale");
    edit(&mut world, &mut pool, Edit::Place { at: IVec3::new(9, 9, 9), material: BLUE });
    let new = pool.find(LightKey::Voxel(IVec3::new(9, 9, 9))).unwrap();
    assert_eq!(new.slot, old.slot, "the freed slot is reused");
    assert_ne!(new.generation, old.generation);
    assert!(pool.get(old).is_none(), "the old reference does not see the new light in its slot");
    assert_eq!(pool.get(new).unwrap().material, BLUE);
    // Recolouring updates in place: same slot, same generation, new material.
    edit(&mut world, &mut pool, Edit::Place { at: IVec3::new(9, 9, 9), material: WARM });
    assert_eq!(pool.find(LightKey::Voxel(IVec3::new(9, 9, 9))), Some(new));
    assert_eq!(pool.get(new).unwrap().material, WARM);
}

#[test]
fn aligned_emissive_brick_is_one_light_until_broken() {
    let mut world = VoxelWorld::new(UVec3::splat(32), palette());
    let mut pool = LightPool::from_world(&world);
    edit(&mut world, &mut pool, Edit::FillBox { min: IVec3::splat(8), max: IVec3::splat(15), material: WARM });
    assert_eq!(pool.counts(), (0, 1));
    let brick = pool.lights().next().unwrap().1;
    assert_eq!((brick.key, brick.min, brick.size), (LightKey::Brick(IVec3::ONE), IVec3::splat(8), 8));
    assert_eq!(brick.exposed_area, 6.0 * 64.0);
    // Breaking the top-centre voxel: 296 surface voxels minus the broken one plus the interior one under it.
    edit(&mut world, &mut pool, Edit::Break { at: IVec3::new(11, 15, 11) });
    assert_eq!(pool.counts(), (296, 0));
    assert_eq!(as_set(&pool), as_set(&LightPool::from_world(&world)));
    // Restoring it brings the single brick light back.
    edit(&mut world, &mut pool, Edit::Place { at: IVec3::new(11, 15, 11), material: WARM });
    assert_eq!(pool.counts(), (0, 1));
    // A brick light buried in stone is no light at all.
    edit(&mut world, &mut pool, Edit::FillBox { min: IVec3::splat(0), max: IVec3::splat(23), material: STONE });
    edit(&mut world, &mut pool, Edit::FillBox { min: IVec3::splat(8), max: IVec3::splat(15), material: WARM });
    assert_eq!(pool.counts(), (0, 0));
}

/// Deterministic uniform numbers in [0, 1) (SplitMix64).
struct Rng(u64);
impl Rng {
    fn next_u32(&mut self) -> u32 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        ((z ^ (z >> 31)) >> 32) as u32
    }
    fn next(&mut self) -> f32 {
        (self.next_u32() >> 8) as f32 / (1u64 << 24) as f32
    }
}

/// Chi-square critical value at p = 0.001 (Wilson-Hilferty; exact 10.83 for one degree of freedom).
fn chi_square_critical(df: usize) -> f64 {
    if df == 1 {
        return 10.828;
    }
    let k = df as f64;
    let z = 3.0902;
    k * (1.0 - 2.0 / (9.0 * k) + z * (2.0 / (9.0 * k)).sqrt()).powi(3)
}

/// Draws 10^6 samples and tests the counts against the power distribution, pooling small expected counts.
fn check_alias(powers: &[f32]) {
    let lights: Vec<(u32, f32)> = powers.iter().enumerate().map(|(i, &p)| (i as u32 * 3 + 1, p)).collect();
    let table = AliasTable::build(&lights);
    let total: f64 = powers.iter().map(|&p| p as f64).sum();
    let draws = 1_000_000u32;
    let mut counts = vec![0u64; powers.len()];
    let mut rng = Rng(powers.len() as u64);
    for _ in 0..draws {
        let (slot, pdf) = table.sample(rng.next_u32(), rng.next()).unwrap();
        let index = ((slot - 1) / 3) as usize;
        assert!((pdf as f64 - powers[index] as f64 / total).abs() <= 1e-6 * (pdf as f64).max(1e-30) + 1e-12);
        counts[index] += 1;
    }
    // Pool bins in order of expected count until each group expects at least 20 draws.
    let mut order: Vec<usize> = (0..powers.len()).collect();
    order.sort_by(|&a, &b| powers[a].total_cmp(&powers[b]));
    let (mut chi2, mut groups) = (0.0, 0usize);
    let (mut expected, mut observed) = (0.0f64, 0u64);
    for (k, &i) in order.iter().enumerate() {
        expected += draws as f64 * powers[i] as f64 / total;
        observed += counts[i];
        if expected >= 20.0 || k + 1 == order.len() {
            chi2 += (observed as f64 - expected).powi(2) / expected.max(1e-12);
            groups += 1;
            expected = 0.0;
            observed = 0;
        }
    }
    if groups <= 1 {
        assert_eq!(counts.iter().sum::<u64>(), draws as u64);
        return;
    }
    let critical = chi_square_critical(groups - 1);
    assert!(chi2 < critical, "{} lights: chi2 {chi2:.1} >= {critical:.1} with {groups} groups", powers.len());
}

#[test]
fn alias_table_samples_in_proportion_to_power() {
    check_alias(&[3.0]);
    check_alias(&[1.0, 1.0e6]);
    check_alias(&[2.0, 5.0]);
    let mut rng = Rng(7);
    // Powers spread log-uniformly over six decades.
    let spread = |n: usize, rng: &mut Rng| (0..n).map(|_| 10f32.powf(rng.next() * 6.0)).collect::<Vec<_>>();
    check_alias(&spread(1000, &mut rng));
    check_alias(&spread(100_000, &mut rng));
}

#[test]
fn alias_table_falls_back_to_uniform() {
    let table = AliasTable::build(&[(4, 0.0), (9, f32::NAN), (11, 0.0)]);
    assert!(table.uniform);
    let p = table.column_probabilities();
    assert!(p.iter().all(|&x| (x - 1.0 / 3.0).abs() < 1e-6), "{p:?}");
    assert_eq!(table.sample(1 << 31, 0.99).map(|s| s.1), Some(1.0 / 3.0));
    assert!(AliasTable::build(&[]).sample(1 << 31, 0.5).is_none());
}

#[test]
fn cornell_has_256_brick_lights() {
    let cornell = glowbrick::world::recipe::load_scene("cornell").unwrap();
    let pool = LightPool::from_world(&cornell);
    assert_eq!(pool.counts(), (0, 256));
    // Each brick light shows its bottom face (64 voxel faces) to the room; the front row also its open front.
    let front = pool.lights().filter(|(_, l)| l.exposed_area == 128.0).count();
    let inner = pool.lights().filter(|(_, l)| l.exposed_area == 64.0).count();
    assert_eq!((front, inner), (16, 240));
}

/// Through the game's edit path: the first frame uploads every slot, later frames only the changed ones, and
/// the alias table only when the pool changed.
#[test]
fn light_upload_sends_changed_slots_only() {
    use bevy::prelude::*;
    use glowbrick::lights::plugin::LightsPlugin;
    use glowbrick::render::scene::lights::{LightUpload, LightUploadPlugin};
    use glowbrick::world::events::{EditRequest, WorldEditPlugin};

    let mut world = VoxelWorld::new(UVec3::splat(16), palette());
    world.apply(Edit::Place { at: IVec3::new(1, 1, 1), material: WARM }).unwrap();
    world.apply(Edit::Place { at: IVec3::new(5, 1, 1), material: BLUE }).unwrap();
    let mut app = App::new();
    app.add_plugins((WorldEditPlugin, LightsPlugin, LightUploadPlugin)).insert_resource(world);
    app.update();
    let upload = app.world().resource::<LightUpload>().clone();
    assert_eq!(upload.light_count, 2);
    assert!(upload.full.is_some() && upload.alias.as_ref().is_some_and(|a| a.len() == 2));

    app.update();
    assert!(app.world().resource::<LightUpload>().is_empty(), "no change, nothing to send");

    app.world_mut().write_message(EditRequest::player(Edit::Place { at: IVec3::new(9, 9, 9), material: WARM }));
    app.update();
    let upload = app.world().resource::<LightUpload>().clone();
    assert!(upload.full.is_none());
    assert_eq!(upload.slots.len(), 1);
    assert_eq!(upload.slots[0].1.min, [9, 9, 9]);
    assert_eq!((upload.light_count, upload.alias.map(|a| a.len())), (3, Some(3)));

    // A stone placed far from every light changes no light and sends nothing.
    app.world_mut().write_message(EditRequest::player(Edit::Place { at: IVec3::new(14, 14, 1), material: STONE }));
    app.update();
    assert!(app.world().resource::<LightUpload>().is_empty());
}

#[test]
fn every_column_gets_its_share_of_codes_at_a_million_lights_and_past_two_to_the_24() {
    use glowbrick::lights::alias::column_of;
    for n in [3u32, 1_000_003, (1 << 24) + 5, u32::MAX] {
        // Column c owns the codes r with floor(r n / 2^32) = c: from ceil(c 2^32 / n). Every column's count is
        // floor or ceil of 2^32 / n (a 24-bit float u gave 16 or 17 codes per column at 10^6, -4.4% / +1.6%).
        let first = |c: u64| (c << 32).div_ceil(n as u64);
        let (lo, hi) = ((1u64 << 32) / n as u64, (1u64 << 32).div_ceil(n as u64));
        let columns: Vec<u64> = if n < 4096 {
            (0..n as u64).collect()
        } else {
            (0..n as u64).step_by(9973).chain([n as u64 - 1]).collect()
        };
        for c in columns {
            let count = first(c + 1) - first(c);
            assert!(count == lo || count == hi, "n {n}, column {c}: {count} codes");
            assert_eq!(column_of(first(c) as u32, n), c as u32, "n {n}: first code of column {c}");
            if c > 0 {
                assert_eq!(column_of((first(c) - 1) as u32, n), c as u32 - 1, "n {n}: code before column {c}");
            }
        }
        assert_eq!(column_of(u32::MAX, n), n - 1, "the last column is reachable");
        assert_eq!(column_of(0, n), 0);
    }
}
