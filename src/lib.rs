//! glowbrick: a voxel sandbox lit by Voxel ReSTIR direct lighting and a per-voxel-face GI cache.
//!
//! Layers, bottom up: `world` (the brick grid and its files), `render` (GPU upload and passes as Bevy systems),
//! `game` (the playable app), `headless` (rendering to files without a window).

pub mod bench;
pub mod cli;
pub mod dynamic;
pub mod game;
pub mod headless;
pub mod image_io;
pub mod lights;
pub mod reference;
pub mod render;
pub mod settings;
pub mod stress;
pub mod world;

/// Everything a running world needs besides a window: the edit path, the light pool and the renderer.
pub struct GlowbrickCorePlugin;

impl bevy::app::Plugin for GlowbrickCorePlugin {
    fn build(&self, app: &mut bevy::app::App) {
        app.add_plugins((
            world::events::WorldEditPlugin,
            lights::plugin::LightsPlugin,
            render::VoxelRenderPlugin,
            dynamic::DynamicObjectsPlugin,
        ));
    }
}
