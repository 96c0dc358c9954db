//! RON world files: lossless round trip, atomic save, and one clear error (never a panic) for broken files.

use bevy::math::{IVec3, UVec3};
use glowbrick::world::format::{load_world, parse_world, save_world, world_to_string};
use glowbrick::world::recipe::{generated_world, load_scene, parse_recipe};
use glowbrick::world::source::load_path;
use glowbrick::world::{Edit, VoxelWorld};
use std::path::PathBuf;

fn temp_dir(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("glowbrick-test-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

fn same_world(a: &VoxelWorld, b: &VoxelWorld) {
    assert_eq!(a.grid.size(), b.grid.size());
    assert_eq!(a.palette, b.palette);
    assert_eq!(a.views, b.views);
    let s = a.grid.size().as_ivec3();
    for z in 0..s.z {
        for y in 0..s.y {
            for x in 0..s.x {
                let p = IVec3::new(x, y, z);
                assert_eq!(a.grid.get(p), b.grid.get(p), "voxel {p}");
            }
        }
    }
}

fn sample_world() -> VoxelWorld {
    let mut world = generated_world(3, UVec3::new(40, 24, 36)).unwrap();
    world.apply(Edit::Place { at: IVec3::new(39, 23, 35), material: 10 }).unwrap();
    world.apply(Edit::FillBox { min: IVec3::new(0, 16, 0), max: IVec3::new(15, 23, 7), material: 7 }).unwrap();
    world
}

#[test]
fn round_trip_is_lossless() {
    let world = sample_world();
    let text = world_to_string(&world);
    let loaded = parse_world(&text, "memory").unwrap();
    same_world(&world, &loaded);
    assert_eq!(world.summary(), loaded.summary());
    // Saving again gives the same text: the encoding is canonical.
    assert_eq!(world_to_string(&loaded), text);
}

#[test]
fn save_is_atomic_and_load_reads_it_back() {
    let dir = temp_dir("save");
    let path = dir.join("w.ron");
    let world = sample_world();
    save_world(&world, &path).unwrap();
    same_world(&world, &load_world(&path).unwrap());
    // No temporary file is left behind.
    let names: Vec<_> = std::fs::read_dir(&dir).unwrap().map(|e| e.unwrap().file_name()).collect();
    assert_eq!(names, vec![std::ffi::OsString::from("w.ron")]);
}

/// Each broken file gives an error naming the problem and its place, and leaves the file untouched.
#[test]
fn broken_files_give_one_clear_error() {
    let dir = temp_dir("broken");
    let good = world_to_string(&sample_world());
    let small = "(format: \"glowbrick-world\", version: 1, size: (16, 16, 16), palette: [(name: \"a\", albedo: (0.5, 0.5, 0.5))], views: [], bricks: [BRICKS])";
    let with_bricks = |b: &str| small.replace("BRICKS", b);
    let small = with_bricks("");
    let cases: Vec<(&str, String, &str)> = vec![
        ("truncated", good[..good.len() / 2].to_string(), "w.ron:"),
        ("empty", String::new(), "w.ron:"),
        ("mistyped", good.replacen("version: 1", "version: \"one\"", 1), "Expected integer"),
        ("wrong version", good.replacen("version: 1", "version: 99", 1), "version 99"),
        ("wrong format", good.replacen("glowbrick-world", "other-world", 1), "format"),
        ("oversized", small.replace("(16, 16, 16)", "(100000, 16, 16)"), "size.x = 100000"),
        ("zero size", small.replace("(16, 16, 16)", "(16, 0, 16)"), "size.y = 0"),
        ("id out of range", with_bricks("(at: (0, 0, 0), fill: Uniform(2))"), "bricks[0] at (0, 0, 0): material id 2"),
        (
            "run id out of range",
            with_bricks("(at: (1, 0, 1), fill: Runs([(12, 1), (500, 7)]))"),
            "run 1: material id 7",
        ),
        ("short runs", with_bricks("(at: (0, 1, 0), fill: Runs([(12, 1), (300, 0)]))"), "runs cover 312 voxels"),
        ("long runs", with_bricks("(at: (0, 1, 0), fill: Runs([(500, 1), (300, 0)]))"), "more than 512"),
        ("brick outside", with_bricks("(at: (2, 0, 0), fill: Uniform(1))"), "outside the world"),
        (
            "duplicate brick",
            with_bricks("(at: (1, 1, 1), fill: Uniform(1)), (at: (1, 1, 1), fill: Uniform(0))"),
            "listed twice",
        ),
        ("duplicate key", small.replace("version: 1,", "version: 1, version: 1,"), "version"),
        ("unknown key", small.replace("version: 1,", "version: 1, colour: 3,"), "colour"),
        ("nan albedo", small.replace("(0.5, 0.5, 0.5)", "(NaN, 0.5, 0.5)"), "albedo"),
        ("deep nesting", format!("{}{}", "[".repeat(5000), "]".repeat(5000)), "w.ron:"),
    ];
    for (name, text, expected) in cases {
        let path = dir.join("w.ron");
        std::fs::write(&path, &text).unwrap();
        let err = load_world(&path).expect_err(name).to_string();
        assert!(err.contains(expected), "{name}: message '{err}' lacks '{expected}'");
        assert!(!err.contains('\n'), "{name}: message is not one line: {err}");
        assert_eq!(std::fs::read_to_string(&path).unwrap(), text, "{name}: the file was modified");
    }
    // Syntax errors carry line:column.
    let err = parse_world("(format: \"glowbrick-world\",\n version: ,)", "x.ron").unwrap_err().to_string();
    assert!(err.starts_with("x.ron:2:"), "{err}");
}

#[test]
fn bundled_scenes_build() {
    let cornell = load_scene("cornell").unwrap();
    let summary = cornell.summary();
    assert_eq!(summary.brick_lights, 256, "{summary}");
    assert_eq!(summary.voxel_lights, 0, "{summary}");
    assert!(cornell.view(Some("front")).is_some());
    let room = load_scene("test-room").unwrap();
    assert!(room.summary().voxels > 0);
    assert!(load_scene("../Cargo").is_err());
    assert!(load_scene("no-such-scene").unwrap_err().to_string().contains("cornell"));
}

#[test]
fn example_save_opens() {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("saves/example.ron");
    let world = load_path(&path).unwrap();
    assert!(world.summary().voxel_lights > 0, "the example world has lamps");
}

/// The thesis-like recipes build, with the emitters each is meant to have.
#[test]
fn thesis_like_recipes_build_with_their_lights() {
    let lights = |name: &str| {
        let world = load_scene(name).unwrap();
        assert!(!world.views.is_empty(), "{name} has camera views");
        let s = world.summary();
        (s.voxel_lights, s.brick_lights)
    };
    let (letters, _) = lights("letters");
    assert!((1000..3000).contains(&letters), "letters: {letters} voxel lights");
    let (apartments, _) = lights("apartments");
    assert!((2000..6000).contains(&apartments), "apartments: {apartments} voxel lights");
    // 1,500 lamps of three voxels each, all exposed.
    assert_eq!(lights("mountain"), (4500, 0));
    // The daylight panel outside the window is 4 x 8 aligned bricks.
    assert_eq!(lights("window-room"), (0, 32));
    // Half of a 448 x 448 layer, every lamp alone among air and its four diagonal neighbours.
    assert_eq!(lights("lamp-checkerboard"), (100_352, 0));
}

/// `Checker` fills the even cells of its box only, and refuses a box outside the world.
#[test]
fn checker_fills_every_other_voxel() {
    let recipe = |ops: &str| {
        format!(
            "(size: (8, 4, 8), materials: [(name: \"lamp\", albedo: (1.0, 1.0, 1.0), emission: (1.0, 1.0, 1.0), strength: \
             1.0)], ops: [{ops}])"
        )
    };
    let world = parse_recipe(&recipe("Checker(min: (1, 1, 1), max: (5, 2, 4), material: \"lamp\")"), "c.ron").unwrap();
    let mut filled = Vec::new();
    world.grid.for_each_solid(|p, _| filled.push(p));
    assert_eq!(filled.len(), 6, "{filled:?}");
    assert!(filled.iter().all(|p| (p.x + p.y + p.z) % 2 == 0 && p.y == 1), "{filled:?}");
    let outside = parse_recipe(&recipe("Checker(min: (0, 0, 0), max: (9, 1, 1), material: \"lamp\")"), "c.ron");
    assert!(outside.unwrap_err().to_string().contains("inside the world"));
}
