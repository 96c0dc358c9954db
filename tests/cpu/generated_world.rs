//! The generated world of `glowbrick play`: the same world for a seed however many threads build it, and the
//! places it promises (houses with lamps under roofs, trees, caves, crystals) where its views say they are.

use bevy::math::{IVec3, UVec3, Vec3};
use glowbrick::world::format::world_to_string;
use glowbrick::world::generate::generate_world;
use glowbrick::world::traversal::{Ray, trace};

const SIZE: UVec3 = UVec3::new(256, 96, 256);

#[test]
fn the_same_seed_gives_the_same_world_on_any_thread_count() {
    let (parallel, _) = generate_world(5, SIZE).unwrap();
    let one_thread = rayon::ThreadPoolBuilder::new().num_threads(1).build().unwrap();
    let (serial, _) = one_thread.install(|| generate_world(5, SIZE).unwrap());
    assert!(world_to_string(&parallel) == world_to_string(&serial), "thread count changed the world");
    let (other, _) = generate_world(6, SIZE).unwrap();
    assert!(world_to_string(&parallel) != world_to_string(&other), "the seed changed nothing");
}

#[test]
fn the_world_holds_a_village_trees_caves_and_crystals() {
    let (world, report) = generate_world(1, SIZE).unwrap();
    assert!(report.houses >= 4, "{} houses", report.houses);
    assert!(report.trees >= 50, "{} trees", report.trees);
    assert!(report.crystals >= 10, "{} crystal voxels", report.crystals);
    for name in ["village", "house", "lantern", "overview", "cave"] {
        assert!(world.view(Some(name)).is_some(), "no view '{name}'");
    }
    assert_eq!(world.views[0].name, "village", "the game starts at the first view");
    let id = |name: &str| world.palette.id_of(name).unwrap();
    let trace_from = |origin: Vec3, dir: Vec3| trace(&world.grid, &Ray::new(origin, dir), 1.0e4);

    // Inside the house: a roof overhead, a floor of planks below, a lamp hanging under the ridge.
    let house = world.view(Some("house")).unwrap();
    let up = trace_from(house.origin(), Vec3::Y).expect("open sky above the house view");
    assert!(up.distance < 10.0 && [id("roof"), id("wood"), id("lamp-warm")].contains(&up.material), "{up:?}");
    let down = trace_from(house.origin(), -Vec3::Y).expect("no floor");
    assert_eq!(down.material, id("planks"));
    let lamps_inside = (0..8).any(|k| {
        let p = house.origin() + house.direction() * k as f32;
        (0..8).any(|h| world.grid.get((p + Vec3::Y * h as f32).floor().as_ivec3()) == id("lamp-warm"))
    });
    assert!(lamps_inside, "no lamp above the house view's line of sight");

    // The cave view looks straight at a crystal, with rock overhead.
    let cave = world.view(Some("cave")).unwrap();
    let seen = trace_from(cave.origin(), cave.direction()).expect("the cave view sees nothing");
    assert!([id("crystal-cyan"), id("crystal-violet")].contains(&seen.material), "{seen:?}");
    assert!(trace_from(cave.origin(), Vec3::Y).is_some(), "the cave view is under the open sky");

    // Caves: air below the surface of many columns (the surface is the top solid voxel).
    let mut carved_columns = 0;
    for z in (0..SIZE.z as i32).step_by(4) {
        for x in (0..SIZE.x as i32).step_by(4) {
            let top = (0..SIZE.y as i32).rev().find(|&y| world.grid.get(IVec3::new(x, y, z)) != 0).unwrap_or(0);
            if (3..top - 4).any(|y| world.grid.get(IVec3::new(x, y, z)) == 0) {
                carved_columns += 1;
            }
        }
    }
    assert!(carved_columns >= 100, "{carved_columns} of 4096 sampled columns have a cave");
}

#[test]
fn tiny_and_flat_worlds_generate_without_a_village() {
    for size in [UVec3::ONE, UVec3::new(24, 16, 24), UVec3::new(300, 8, 20)] {
        let (world, report) = generate_world(2, size).unwrap();
        assert_eq!(report.houses, 0, "{size}");
        assert!(!world.views.is_empty(), "{size}: no start view");
        assert!(world.grid.contains(world.views[0].origin().floor().as_ivec3()), "{size}: start outside the world");
    }
}

/// F5 / F9 of the default world: the save loads back voxel for voxel with its views and materials (per-voxel
/// variation included), and a save cut short or with a damaged brick is one error, not a panic.
#[test]
fn the_default_world_saves_and_loads_back_and_a_damaged_save_is_one_error() {
    let _alone = crate::EXCLUSIVE.lock().unwrap_or_else(|e| e.into_inner());
    use glowbrick::world::format::{load_world, parse_world, save_world};
    let (world, _) = generate_world(1, UVec3::new(1024, 192, 1024)).unwrap();
    let dir = std::env::temp_dir().join(format!("glowbrick-test-default-save-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("world.ron");
    save_world(&world, &path).unwrap();
    let bytes = std::fs::metadata(&path).unwrap().len();
    assert!(bytes < 64_000_000, "a {bytes}-byte save of the default world");
    let loaded = load_world(&path).unwrap();
    // Pool slots are handed out in load order, so compare bricks, not top cells.
    assert_eq!(loaded.grid.pooled_bricks(), world.grid.pooled_bricks());
    for b in 0..world.grid.top_cells().len() as u32 {
        let at = world.grid.brick_coord(b);
        assert!(loaded.grid.brick_voxels(at) == world.grid.brick_voxels(at), "brick {at} differs");
    }
    assert_eq!(loaded.palette, world.palette);
    assert_eq!(loaded.views, world.views);

    let text = std::fs::read_to_string(&path).unwrap();
    let cut = parse_world(&text[..text.len() / 2], "cut");
    assert!(cut.as_ref().is_err_and(|e| !e.to_string().contains('\n')), "half a save: {:?}", cut.err());
    // A brick's run lengths that no longer add up to its 512 voxels, three quarters into the file.
    let runs = text[text.len() * 3 / 4..].find("Runs([(").unwrap() + text.len() * 3 / 4 + "Runs([(".len();
    let damaged = format!("{}9{}", &text[..runs], &text[runs..]);
    let error = parse_world(&damaged, "damaged").expect_err("a save with a damaged brick is refused");
    assert!(!error.to_string().contains('\n'), "{error}");
    let _ = std::fs::remove_dir_all(&dir);
}
