//! glowbrick: a voxel sandbox lit by Voxel ReSTIR direct lighting and a per-voxel-face GI cache.
//!
//! Layers, bottom up (a module imports only from its own layer and those below; `tests/cpu/layers.rs` checks it,
//! and that this line and the README's agree with its table):
//! `colour` / `image_io` / `progress` / `alloc_watch` -> `world` (the brick grid, its files, traversal, camera
//! math) -> `lights` / `dynamic` / `reference` (CPU only) -> `render` / `settings` / `core_plugin` / `net` ->
//! `game` (the playable app) / `headless` (rendering without a window) -> `bench` / `stress` -> `cli`.

pub mod alloc_watch;
pub mod bench;
pub mod cli;
pub mod colour;
pub mod core_plugin;
pub mod dynamic;
pub mod game;
pub mod headless;
pub mod image_io;
pub mod lights;
pub mod net;
pub mod progress;
pub mod reference;
pub mod render;
pub mod settings;
pub mod stress;
pub mod world;

pub use core_plugin::GlowbrickCorePlugin;
