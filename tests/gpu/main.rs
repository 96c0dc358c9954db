//! The tests that need a GPU adapter, one binary (one link of Bevy) with a module per subject, under a harness
//! (`libtest-mimic`, the standard one's arguments but a single name filter) that asks once, before the tests
//! run, whether an adapter exists, exactly as the renderer asks Bevy for one (so `WGPU_BACKEND` and the like
//! count), and not at all when a filter leaves no GPU test:
//! - an adapter: every test runs, the quick bench and the quick stress soak included;
//! - none, and `GLOWBRICK_REQUIRE_GPU=1` (CI): every test fails and says why;
//! - none otherwise: every test is reported `ignored` in the summary, and one line after it says why and how to
//!   run them.
//!
//! Unlike the standard harness this one does not capture a test's output: the tests' measurements are printed as
//! they run.
//!
//! Each test runs in a child process of this binary (the same executable, told which test by `CHILD_TEST_VAR`):
//! a Bevy app and its software-Vulkan device do not hand all their memory back when dropped, and one process
//! running every test grew past this machine's 24 GiB (CI was killed by the OOM killer in the ReSTIR group).
//! A child's memory is freed when it exits, so the suite's peak is that of its two largest tests at once (about
//! 6.5 and 5.5 GiB, the GI warm-up and convergence tests).

// A test function left out of `tests()` below would never run: make that a compile error.
#![deny(dead_code)]

mod bench_quick;
mod cli;
mod common;
#[path = "../shared/compose.rs"]
mod compose;
#[path = "../shared/compute.rs"]
mod compute;
mod daylight;
mod denoise;
mod detail;
mod extreme_scenes;
mod gi;
mod gi_cell;
#[path = "../shared/gpu_world.rs"]
mod gpu_world;
mod headless;
mod nee_converges;
mod objects;
mod pass_keys;
mod primary_matches_cpu;
mod ray_budget;
mod restir;
mod smoke;
mod stress;
mod upscale;
#[path = "../shared/vox_scene.rs"]
mod vox_scene;
mod wgsl_twins;
mod world_after_edits;

use libtest_mimic::{Arguments, Completion, Failed, Trial};
use std::process::Command;
use std::sync::OnceLock;

/// Set in a child process to the one test (`module::test`) it runs.
const CHILD_TEST_VAR: &str = "GLOWBRICK_GPU_TEST_CHILD";

/// `(module::test, test)` for each listed test; a test left out of the list is a dead-code error.
macro_rules! gpu_tests {
    ($($module:ident: [$($test:ident),* $(,)?]),* $(,)?) => {
        vec![$($((concat!(stringify!($module), "::", stringify!($test)), $module::$test as fn())),*),*]
    };
}

fn tests() -> Vec<(&'static str, fn())> {
    gpu_tests![
        bench_quick: [quick_bench_writes_csv_markdown_and_plot],
        cli: [render_writes_exr_and_png_headless],
        daylight: [
            a_lamp_placed_at_night_lights_the_floor_in_the_frame_that_places_it,
            full_lighting_converges_to_the_reference_at_noon_dusk_and_night,
            the_clock_moved_in_a_running_game_moves_the_light,
        ],
        denoise: [
            a_denoised_frame_is_closer_to_the_reference_and_adds_little_bias,
            a_lamp_switched_off_leaves_no_ghost,
            a_moving_object_keeps_its_history,
            a_sliding_block_is_neither_brightened_nor_smeared,
            shadows_on_ground_seen_edge_on_stay_sharp,
            with_the_denoiser_off_none_of_its_passes_runs,
        ],
        extreme_scenes: [
            a_hundred_thousand_lights,
            a_light_one_voxel_above_the_floor,
            a_million_lights,
            a_room_in_the_far_corner_of_the_largest_world,
            a_world_past_one_gpu_binding_renders_through_pool_parts,
            a_single_light_behind_a_one_voxel_hole,
            emission_over_eight_decades_in_one_scene,
            lights_embedded_in_the_surface_the_camera_sees,
            lamps_lying_on_a_floor,
        ],
        gi_cell: [a_coarse_entry_samples_the_same_faces_whichever_face_inserted_it],
        gi: [
            a_fresh_cache_brings_in_the_bounces_during_its_warm_up,
            a_glowing_object_behind_a_wall_does_not_leak_through_it,
            an_edit_retraces_only_the_entries_its_bricks_can_reach_and_the_light_follows,
            the_gi_cache_converges_to_the_path_traced_reference_in_the_cornell_box,
            the_gi_cache_converges_to_the_path_traced_reference_in_the_window_room,
            the_gi_cache_converges_with_per_voxel_detail,
            the_indirect_view_is_the_caches_share_of_the_image,
            two_cameras_update_the_cache_once_per_frame,
            settled_entries_update_one_frame_in_their_period_unless_an_object_moves_near,
            freeing_entries_keeps_the_rest_of_their_probe_chains_reachable,
            the_cache_restarts_its_blends_only_when_the_light_changes,
            an_opened_doorway_lights_the_far_side_within_thirty_frames,
            a_coarse_entry_whose_face_an_edit_covers_is_freed_and_inserted_again,
            a_sky_seen_through_a_small_hole_is_averaged_over_fresh_directions,
            low_discrepancy_rays_hold_each_entrys_light_steadier,
            guided_rays_find_the_light_of_a_small_hole,
            wider_camera_cells_keep_fewer_entries,
            with_gi_off_no_gi_pass_runs,
            with_the_warm_up_off_a_fresh_cache_brings_in_its_bounces_slower,
            a_settled_entry_whose_light_still_rises_catches_up_at_the_fast_weight,
            a_lamp_placed_in_a_dark_room_lights_its_bounce_within_eight_frames,
        ],
        detail: [every_voxel_has_the_cpus_albedo_and_the_lit_frame_converges],
        headless: [a_broken_shader_fails_every_wait_at_once_with_its_pass_name],
        nee_converges: [
            gpu_nee_converges_to_the_cpu_reference_on_the_cornell_box,
            gpu_nee_converges_to_the_cpu_reference_on_the_letters,
        ],
        objects: [
            a_magicavoxel_lamp_lights_its_scene_under_restir,
            a_saved_world_shows_its_moving_objects_where_they_were,
            a_lanterns_light_reaches_the_floor_through_the_gi_cache,
            with_an_object_in_view_restir_converges_to_the_reference,
        ],
        pass_keys: [every_specialised_pipeline_set_compiles_and_renders],
        ray_budget: [the_game_frame_keeps_to_its_rays_per_pixel],
        primary_matches_cpu: [
            a_rendered_sequence_returns_each_frame_with_its_own_camera,
            gpu_primary_rays_match_cpu_traversal,
            lit_render_is_finite_and_shows_emission,
            the_game_frame_is_the_same_through_either_walk,
        ],
        restir: [
            a_removed_light_is_never_shaded,
            candidates_from_light_tiles_converge_as_candidates_from_the_alias_table,
            point_lights_give_hard_shadows_and_area_lights_converge,
            temporal_reuse_does_not_cross_a_face_normal_flip,
            unbiased_restir_converges_to_the_reference_on_the_cornell_box,
            unbiased_restir_converges_to_the_reference_on_the_letters,
            restir_with_temporal_reuse_converges_on_the_thesis_scenes_and_apartments,
            restir_with_temporal_reuse_converges_on_the_mountain,
            the_reservoir_view_of_a_world_without_lights_shows_empty_reservoirs,
            without_lights_only_the_shading_pass_runs,
            the_shading_pass_lights_a_world_whose_lamps_are_broken,
        ],
        smoke: [a_tiny_frame_matches_the_cpu_reference],
        stress: [quick_stress_run_finds_no_non_finite_value_and_no_drift],
        upscale: [
            at_half_scale_a_frame_is_about_as_close_to_the_reference_and_keeps_the_mean,
            the_sky_of_an_upscaled_frame_is_the_native_frames,
            a_face_narrower_than_a_render_pixel_takes_its_own_light,
            at_half_scale_the_lighting_passes_trace_under_a_ray_per_output_pixel,
        ],
        wgsl_twins: [
            the_light_hash_matches_the_cpu_light_index,
            the_spherical_rectangle_sampler_matches_the_cpu_reference,
        ],
        world_after_edits: [gpu_world_follows_edits, the_occupancy_walk_sees_a_pillar_built_above_the_occupied_box],
    ]
}

/// The probe's answer, asked once.
static ADAPTER: OnceLock<Result<String, String>> = OnceLock::new();

fn adapter() -> &'static Result<String, String> {
    ADAPTER.get_or_init(|| {
        let adapter = glowbrick::render::adapter::probe_adapter().map(|adapter| adapter.name);
        if let Ok(name) = &adapter {
            eprintln!("GPU tests on {name}");
        }
        adapter
    })
}

/// The child's side: run one test in this process (a panic fails it with a non-zero exit), then say how much
/// memory it took at its peak so a test that grows shows in the log.
fn run_child(name: &str) {
    let Some((_, test)) = tests().into_iter().find(|(n, _)| *n == name) else {
        eprintln!("no GPU test named {name}");
        std::process::exit(2);
    };
    test();
    if let Some(peak) = peak_memory_mib() {
        eprintln!("{name}: peak memory {peak} MiB");
    }
}

/// This process's peak resident memory (Linux's `VmHWM`), when the system says.
fn peak_memory_mib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    let line = status.lines().find(|l| l.starts_with("VmHWM:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib / 1024)
}

/// The parent's side: run `name` in a child process of this binary, its output going straight to ours.
fn run_in_child(name: &str) -> Result<(), Failed> {
    let exe = std::env::current_exe().map_err(|e| Failed::from(format!("cannot find the test binary: {e}")))?;
    let mut child = Command::new(exe);
    child.env(CHILD_TEST_VAR, name);
    // glibc gives each new thread (lavapipe's and Bevy's, new with every renderer) its own heap arena and keeps
    // what a dropped renderer freed in them: two arenas took the GI window-room test from 7.6 to 5.4 GiB at the
    // same speed (173 s / 168 s). Elsewhere the variable means nothing.
    if std::env::var_os("MALLOC_ARENA_MAX").is_none() {
        child.env("MALLOC_ARENA_MAX", "2");
    }
    let status = child.status().map_err(|e| Failed::from(format!("cannot start the test's process: {e}")))?;
    if status.success() { Ok(()) } else { Err(Failed::from(format!("the test's process ended with {status}"))) }
}

fn main() {
    if let Ok(name) = std::env::var(CHILD_TEST_VAR) {
        run_child(&name);
        return;
    }
    let args = Arguments::from_args();
    let require = common::require_gpu();
    let trials = tests()
        .into_iter()
        .map(|(name, _)| {
            Trial::ignorable_test(name, move || match adapter() {
                Ok(_) => run_in_child(name).map(|()| Completion::Completed),
                Err(why) if require => Err(Failed::from(format!("no GPU adapter and GLOWBRICK_REQUIRE_GPU=1: {why}"))),
                Err(_) => Ok(Completion::ignored_with("no GPU adapter")),
            })
        })
        .collect::<Vec<_>>();
    if !args.list && trials.iter().any(|t| !args.is_filtered_out(t)) {
        adapter();
    }
    let conclusion = libtest_mimic::run(&args, trials);
    if let Some(Err(why)) = ADAPTER.get()
        && !require
    {
        println!(
            "note: the GPU tests were ignored: no GPU adapter ({why}). Install a Vulkan driver to run them (Debian: \
             `apt-get install mesa-vulkan-drivers` gives software Vulkan); GLOWBRICK_REQUIRE_GPU=1 makes a missing \
             adapter a failure.\n"
        );
    }
    conclusion.exit()
}
