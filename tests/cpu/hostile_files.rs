//! Hostile input: corrupted real files through every loader (the runner of `glowbrick stress --fuzz N`, a
//! million inputs in docs/bench/stress.md; a few thousand here) give a valid world or one clear error line,
//! never a panic, a hang or a huge allocation.

use bevy::math::UVec3;
use glowbrick::alloc_watch::{HeapMark, is_installed};
use glowbrick::stress::fuzz::corpus::seeds;
use glowbrick::stress::fuzz::{FuzzConfig, MAX_INPUT_HEAP, Target, input, run_fuzz};
use glowbrick::world::format::{parse_world, world_to_string};
use glowbrick::world::recipe::generated_world;

#[test]
fn corrupted_inputs_to_every_loader_load_or_fail_in_one_line() {
    let config = FuzzConfig {
        inputs: 6 * 600,
        targets: Target::ALL.to_vec(),
        seed: 7,
        threads: 2,
        findings_dir: std::env::temp_dir().join(format!("glowbrick-fuzz-{}", std::process::id())),
    };
    let report = run_fuzz(&config).unwrap();
    assert_eq!(report.failure(), None, "{report}");
    assert!(report.heap_watched, "the test binary installs the counting allocator");
    for t in &report.targets {
        assert_eq!(t.inputs, 600);
        assert_eq!(t.loaded + t.errors, t.inputs, "{report}");
        // The corruptions are neither all harmless nor all fatal: both paths of every loader are exercised
        // (a world file is strict, brick runs must cover 512 voxels: about 1 in 300 of its inputs loads; an endless
        // world's world.ron is short and checks every field: a few in 600 load).
        let least_loaded = match t.target {
            Target::World => 0,
            Target::Endless => 1,
            _ => 10,
        };
        assert!(
            t.loaded >= least_loaded && t.errors >= 60,
            "{}: {} loaded, {} errors",
            t.target.name(),
            t.loaded,
            t.errors
        );
        assert!(t.peak_heap > 0 && t.peak_heap < MAX_INPUT_HEAP, "{report}");
    }
}

#[test]
fn every_loader_has_real_seeds_and_an_input_is_a_function_of_its_number() {
    for target in Target::ALL {
        let (seeds, _left_out) = seeds(target).unwrap();
        assert!(!seeds.is_empty(), "{target:?}");
        assert_eq!(input(&seeds, target, 3, 41), input(&seeds, target, 3, 41));
        assert_ne!(input(&seeds, target, 3, 41), input(&seeds, target, 3, 42));
    }
}

/// A file that claims the largest world and holds nothing gets the world's brick index (64 MiB), never the
/// voxels it claims (8 GiB).
#[test]
fn a_file_claiming_a_2048_cubed_world_does_not_get_its_voxels() {
    let small = generated_world(4, UVec3::new(24, 16, 24)).unwrap();
    let text = world_to_string(&small).replacen("size: (24, 16, 24)", "size: (2048, 2048, 2048)", 1);
    let mark = HeapMark::now();
    let loaded = parse_world(&text, "huge.ron").unwrap();
    let held = mark.peak_bytes();
    assert!(is_installed());
    assert_eq!(loaded.grid.size(), UVec3::splat(2048));
    assert!(held < 256 << 20, "held {} MiB", held >> 20);
}

/// Found by the fuzzer (`stress --fuzz 5000000 --seed 2`, recipe input 520195): a terrain frequency of 7e36
/// panicked inside the noise crate. Now one error line.
#[test]
fn a_terrain_of_absurd_frequency_is_one_error_line() {
    let recipe = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/assets/scenes/mountain.ron")).unwrap();
    assert!(recipe.contains("frequency: "), "the mountain recipe has a terrain");
    let start = recipe.find("frequency: ").unwrap() + "frequency: ".len();
    let end = start + recipe[start..].find([',', ')']).unwrap();
    let hostile = format!("{}7.1e36{}", &recipe[..start], &recipe[end..]);
    let error = glowbrick::world::recipe::parse_recipe(&hostile, "r.ron").unwrap_err().to_string();
    assert!(error.contains("terrain frequency 7100000000000000000000000000000000000 must be within"), "{error}");
}
