//! An endless world's window that scrolls (`BrickGrid::scroll_window`): the storage wraps, so a scroll rewrites
//! only the bricks that entered, and afterwards the grid reads, masks and traces exactly as a grid made at the new
//! window does, with the wrap in the middle of it.

use bevy::math::{IVec3, UVec3, Vec3};
use glowbrick::world::grid::{BrickCell, BrickGrid, Voxel, WINDOW_STEP};
use glowbrick::world::terrain::hash_u32;
use glowbrick::world::traversal::{Ray, trace, trace_occupancy};

const SIZE: UVec3 = UVec3::new(256, 40, 256);

fn hash(p: IVec3) -> u32 {
    hash_u32(p.x as u32 ^ hash_u32(p.y as u32 ^ hash_u32(p.z as u32).rotate_left(11)).rotate_left(7))
}

/// A world with every kind of brick: solid stone below 8 (homogeneous), hills of two materials (pooled), empty
/// sky above and scattered floating voxels, a function of world coordinates alone.
fn land(p: IVec3) -> Voxel {
    let hill = 10 + (hash(IVec3::new(p.x.div_euclid(6), 0, p.z.div_euclid(5))) % 14) as i32;
    match p.y {
        y if y < 8 => 1,
        y if y < hill => 2 + (hash(p) % 2) as Voxel,
        y if y < 36 && hash(p) % 211 == 0 => 4,
        _ => 0,
    }
}

/// The voxels of `land` in the box `[lo, lo + size)`, as a grid in the box's own coordinates.
fn area(lo: IVec3, size: IVec3) -> BrickGrid {
    let mut grid = BrickGrid::new(size.as_uvec3());
    let voxels: Vec<Voxel> = (0..size.z)
        .flat_map(|z| (0..size.y).flat_map(move |y| (0..size.x).map(move |x| IVec3::new(x, y, z))))
        .map(|q| land(lo + q))
        .collect();
    grid.write_box(IVec3::ZERO, size, &voxels).unwrap();
    grid
}

/// A grid made at the window starting at `lo`, every voxel written there.
fn made_at(lo: IVec3) -> BrickGrid {
    let mut grid = BrickGrid::new(SIZE);
    grid.scroll_window(lo).unwrap();
    let source = area(lo, SIZE.as_ivec3());
    for b in bricks_of(lo, lo + SIZE.as_ivec3()) {
        grid.put_brick(b, &source, b - (lo >> 3_i32));
    }
    grid
}

fn bricks_of(lo: IVec3, hi: IVec3) -> impl Iterator<Item = IVec3> {
    let (bl, bh) = (lo >> 3_i32, hi >> 3_i32);
    (bl.z..bh.z).flat_map(move |z| (bl.y..bh.y).flat_map(move |y| (bl.x..bh.x).map(move |x| IVec3::new(x, y, z))))
}

/// Scrolls `grid` to `lo` and writes the bricks that entered; returns the bricks it marked changed.
fn scroll(grid: &mut BrickGrid, lo: IVec3) -> Vec<IVec3> {
    let old = grid.window().0;
    grid.take_dirty();
    grid.scroll_window(lo).unwrap();
    for (box_lo, box_hi) in BrickGrid::entered_boxes(SIZE, old, lo) {
        let source = area(box_lo, box_hi - box_lo);
        for b in bricks_of(box_lo, box_hi) {
            grid.put_brick(b, &source, b - (box_lo >> 3_i32));
        }
    }
    grid.take_dirty().into_iter().map(|i| grid.brick_coord(i)).collect()
}

fn assert_same_grid(scrolled: &BrickGrid, fresh: &BrickGrid) {
    let (lo, hi) = fresh.window();
    assert_eq!(scrolled.window(), (lo, hi));
    for b in bricks_of(lo, hi) {
        let (a, f) = (scrolled.cell(b), fresh.cell(b));
        match (a, f) {
            (BrickCell::Pooled(sa), BrickCell::Pooled(sf)) => {
                assert_eq!(scrolled.pool_brick(sa), fresh.pool_brick(sf), "brick {b}'s voxels");
                assert_eq!(scrolled.voxel_mask(sa), fresh.voxel_mask(sf), "brick {b}'s voxel mask");
            }
            _ => assert_eq!(a, f, "brick {b}"),
        }
    }
    for p in [lo, hi - 1, IVec3::new(lo.x + 131, 9, hi.z - 77)] {
        assert_eq!(scrolled.get(p), land(p), "voxel {p}");
    }
    assert!(!scrolled.contains(lo - IVec3::X) && !scrolled.contains(hi));
    // Bricks, sectors and regions are stored at the same places, so every mask is the same word.
    assert_eq!(scrolled.occupancy().masks(), fresh.occupancy().masks(), "occupancy masks");
    assert_eq!(scrolled.pooled_bricks(), fresh.pooled_bricks(), "no pool slot leaked");
}

fn assert_same_hits(scrolled: &BrickGrid, fresh: &BrickGrid, seed: u32) {
    let (lo, hi) = fresh.window();
    let (lo, hi) = (lo.as_vec3(), hi.as_vec3());
    let mut state = seed;
    let mut next = || {
        state = hash_u32(state.wrapping_add(0x9E37_79B9));
        state as f32 / u32::MAX as f32
    };
    let mut hits = 0;
    for i in 0..1500 {
        let origin = lo + (hi - lo) * Vec3::new(next(), 0.6 + 0.4 * next(), next());
        let dir = Vec3::new(next() - 0.5, -next(), next() - 0.5);
        let ray = Ray::new(origin, dir);
        let walk = trace_occupancy(scrolled, &ray, f32::INFINITY);
        assert_eq!(walk, trace_occupancy(fresh, &ray, f32::INFINITY), "ray {i}: occupancy walk");
        assert_eq!(trace(scrolled, &ray, f32::INFINITY), trace(fresh, &ray, f32::INFINITY), "ray {i}: DDA");
        if let Some(hit) = walk {
            assert_eq!(hit.material, land(hit.voxel), "ray {i} hit what the land holds");
            hits += 1;
        }
    }
    assert!(hits > 1000, "the rays hit the land ({hits})");
}

#[test]
fn a_scrolled_window_reads_masks_and_traces_as_one_made_there() {
    let mut grid = made_at(IVec3::ZERO);
    let capacity = grid.pool_capacity();
    // Along +x (the storage now wraps at x = 256, in the middle of the window), then -z, then a jump that keeps
    // nothing, then back over the origin.
    let steps = [IVec3::new(128, 0, 0), IVec3::new(128, 0, -128), IVec3::new(-1024, 0, 640), IVec3::new(-128, 0, 0)];
    for (k, lo) in steps.into_iter().enumerate() {
        let old = grid.window();
        let changed = scroll(&mut grid, lo);
        let fresh = made_at(lo);
        assert_same_grid(&grid, &fresh);
        assert_same_hits(&grid, &fresh, k as u32);
        // Only bricks that entered were written (the stone below 8 is the same everywhere, so it is not).
        let entered = BrickGrid::entered_boxes(SIZE, old.0, lo);
        for b in &changed {
            let p = *b * 8;
            assert!(
                entered.iter().any(|(l, h)| p.cmpge(*l).all() && p.cmplt(*h).all()),
                "step {k}: brick {b} changed outside what entered"
            );
        }
        assert!(!changed.is_empty());
    }
    // The slots the bricks that left freed are reused: the pool does not grow with travel.
    assert!(
        grid.pool_capacity() <= capacity * 11 / 10,
        "pool {} slots after travel, {capacity} at first",
        grid.pool_capacity()
    );
}

#[test]
fn entered_boxes_are_the_new_window_less_the_old() {
    let size = SIZE.as_ivec3();
    for (old, new) in [
        (IVec3::ZERO, IVec3::new(128, 0, 0)),
        (IVec3::ZERO, IVec3::new(-128, 0, 128)),
        (IVec3::new(256, 0, 0), IVec3::new(0, 0, -128)),
        (IVec3::ZERO, IVec3::new(1024, 0, 0)),
        (IVec3::ZERO, IVec3::ZERO),
    ] {
        let boxes = BrickGrid::entered_boxes(SIZE, old, new);
        let inside = |p: IVec3, lo: IVec3| p.cmpge(lo).all() && p.cmplt(lo + size).all();
        let mut count = 0i64;
        for (i, &(lo, hi)) in boxes.iter().enumerate() {
            assert!(inside(lo, new) && inside(hi - 1, new), "{old} -> {new}: box {i} in the new window");
            assert!(!inside(lo, old) && !inside(hi - 1, old), "{old} -> {new}: box {i} outside the old one");
            count += ((hi - lo).x as i64) * ((hi - lo).y as i64) * ((hi - lo).z as i64);
            for &(l2, h2) in &boxes[i + 1..] {
                assert!(h2.cmple(lo).any() || hi.cmple(l2).any(), "{old} -> {new}: boxes overlap");
            }
        }
        let overlap = (old + size).min(new + size) - old.max(new);
        let kept =
            if overlap.cmpgt(IVec3::ZERO).all() { overlap.x as i64 * overlap.y as i64 * overlap.z as i64 } else { 0 };
        assert_eq!(count, size.x as i64 * size.y as i64 * size.z as i64 - kept, "{old} -> {new}");
    }
}

#[test]
fn a_window_scrolls_only_by_whole_occupancy_regions() {
    let mut grid = BrickGrid::new(SIZE);
    for bad in [IVec3::new(64, 0, 0), IVec3::new(0, 8, 0), IVec3::new(0, 0, -1)] {
        assert!(grid.scroll_window(bad).is_err(), "{bad}");
    }
    assert_eq!(grid.window().0, IVec3::ZERO, "a refused scroll moves nothing");
    assert!(grid.scroll_window(IVec3::new(-WINDOW_STEP, 0, 3 * WINDOW_STEP)).is_ok());
    let mut odd = BrickGrid::new(UVec3::new(200, 40, 256));
    let error = odd.scroll_window(IVec3::new(128, 0, 0)).unwrap_err().to_string();
    assert!(error.contains("200x40x256") && error.contains("multiples of 128"), "{error}");
}

/// The light pool follows a scrolling window incrementally (`LightPool::follow_window`, then `update_region` on
/// what entered): the same lights as a pool made from the scrolled world, stored where the grid stores their
/// bricks, and a lamp that stays in the window keeps its slot.
#[test]
fn the_light_pool_follows_the_window() {
    use bevy::math::IVec2;
    use glowbrick::lights::{LightKey, LightPool};
    use glowbrick::world::generate::endless::EndlessGenerator;
    use std::collections::HashMap;

    let generator = EndlessGenerator::new(2, 64).unwrap();
    let site = generator.village_site(IVec2::ZERO).expect("a village at the start");
    let village = EndlessGenerator::region_of(site.centre.0, site.centre.1);
    // The village in the middle of the window; two regions on, part of it stays; two more, it is gone; then back.
    let mut window = generator.window(village, 4, None).unwrap();
    let mut pool = LightPool::from_world(&window.world);
    let lamps = pool.len();
    assert!(lamps > 0, "the village's lamps are lights");
    for (step, centre) in [village + IVec2::new(2, 0), village + IVec2::new(4, 0), village].into_iter().enumerate() {
        let before: HashMap<LightKey, u32> = pool.lights().map(|(slot, l)| (l.key, slot)).collect();
        let old = window.world.grid.window().0;
        window.scroll_to(centre, |keys| Ok(generator.regions(keys))).unwrap();
        let world = &window.world;
        pool.follow_window(world);
        for (lo, hi) in BrickGrid::entered_boxes(world.grid.size(), old, world.grid.window().0) {
            pool.update_region(world, lo, hi - IVec3::ONE);
        }
        let mut fresh = LightPool::from_world(world);
        let lights = |p: &LightPool| {
            let mut v: Vec<String> = p.lights().map(|(_, l)| format!("{l:?}")).collect();
            v.sort();
            v
        };
        assert_eq!(lights(&pool), lights(&fresh), "step {step}: the lights of the scrolled window");
        assert_eq!(pool.light_bricks().words(), fresh.light_bricks().words(), "step {step}: light bricks");
        let mut stayed = 0;
        for (slot, light) in pool.lights() {
            if let Some(&was) = before.get(&light.key) {
                assert_eq!(slot, was, "step {step}: a lamp that stayed keeps its slot");
                stayed += 1;
            }
        }
        eprintln!("step {step}: {} lights, {stayed} stayed, {} before", pool.len(), before.len());
        if step == 0 {
            assert!(stayed > 0 && stayed < before.len(), "part of the village stays ({stayed} of {})", before.len());
        }
        if step == 2 {
            assert_eq!(pool.len(), lamps, "back where it started, the same lights");
        }
    }
}

/// `WindowFollower` scrolls the window after a moving point once the regions that enter are made, two regions at
/// a time, and the window it leaves is voxel for voxel the window made at its centre.
#[test]
fn the_follower_scrolls_the_window_after_the_player() {
    use bevy::math::IVec2;
    use glowbrick::world::follow::{SCROLL_REGIONS, WindowFollower};
    use glowbrick::world::generate::endless::{EndlessGenerator, REGION_EDGE};
    use std::sync::Arc;

    let generator = Arc::new(EndlessGenerator::new(4, 48).unwrap());
    let start = IVec2::new(-3, 7);
    let (mut follower, window) = WindowFollower::start(generator.clone(), start, 4, 3, 2);
    let (mut world, min) = (window.world, window.min);
    assert_eq!(follower.centre(&world), start);
    // One region on along x and z: no scroll (the step is two).
    let near = Vec3::new(2.5 * REGION_EDGE as f32 + 3.0, 30.0, 2.5 * REGION_EDGE as f32 + 3.0);
    let budget = std::time::Duration::from_millis(3);
    let once = follower.follow(&mut world, near, budget);
    assert!(once.began.is_none() && once.finished.is_none());
    // Three regions on along x, one back along z: the window moves two regions along x once they are made.
    let far = Vec3::new(5.5 * REGION_EDGE as f32, 30.0, 1.5 * REGION_EDGE as f32);
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(60);
    let (mut began, mut written, mut ticks) = (None, 0, 0);
    let scroll = loop {
        let followed = follower.follow(&mut world, far, budget);
        began = began.or(followed.began);
        written += followed.regions_written;
        if began.is_some() && followed.finished.is_none() {
            ticks += 1;
            // Under way: the window is what the old and new ones share, the regions being written outside it.
            let (lo, hi) = world.grid.window();
            assert_eq!((hi - lo).x, 2 * REGION_EDGE, "tick {ticks}: the window shrank to the shared part");
        }
        if let Some(scroll) = followed.finished {
            break scroll;
        }
        assert!(std::time::Instant::now() < deadline, "the regions to scroll in were never made");
        std::thread::sleep(std::time::Duration::from_millis(10));
    };
    assert_eq!(follower.centre(&world), start + IVec2::new(SCROLL_REGIONS, 0));
    assert_eq!(scroll.keys.len(), 2 * 4, "a strip of two regions by the window's four");
    assert_eq!(Some(&scroll), began.as_ref(), "the scroll finished is the one begun");
    assert_eq!(written, 8, "each region written once");
    let fresh = generator.window(follower.centre(&world), 4, None).unwrap();
    let (lo, hi) = world.grid.window();
    let offset = IVec3::new(min.x - fresh.min.x, 0, min.y - fresh.min.y);
    assert!(world.grid.read_box(lo, hi) == fresh.world.grid.read_box(lo + offset, hi + offset));
}
