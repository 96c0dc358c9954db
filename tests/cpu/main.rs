//! The tests that need no GPU, one binary (one link of Bevy) with a module per subject. The GPU tests are in
//! `tests/gpu`.

mod cli;
mod code_shape;
#[path = "../shared/compose.rs"]
mod compose;
mod daylight;
mod endless_play;
mod game_building;
mod generated_world;
mod hostile_files;
mod imports;
mod layers;
mod light_pool;
mod net;
mod net_endless;
mod reference_converges;
mod save_survives_kill;
mod saved_objects;
mod server_ops;
mod shaders_validate;
mod shared_objects;
mod smoke;
mod travel;
mod traversal_matches_brute_force;
#[path = "../shared/vox_scene.rs"]
mod vox_scene;
mod window_scroll;
mod world_edits;
mod world_files;
mod world_upload;

/// Held by the tests whose measurement a busy neighbour would skew (the save-kill test spreads its kills over a
/// save cycle it timed once) and by the heaviest ones (the default world's save), so the two never overlap.
pub static EXCLUSIVE: std::sync::Mutex<()> = std::sync::Mutex::new(());

/// The counting allocator of the `glowbrick` binary, so the fuzz tests can bound what an input allocates.
#[global_allocator]
static ALLOCATOR: glowbrick::alloc_watch::WatchingAllocator = glowbrick::alloc_watch::WatchingAllocator;
