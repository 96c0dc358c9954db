//! The plugin every running world needs, window or not: the layers below `game` and `headless`, wired once.

/// Everything a running world needs besides a window: the edit path, the light pool and the renderer.
pub struct GlowbrickCorePlugin;

impl bevy::app::Plugin for GlowbrickCorePlugin {
    fn build(&self, app: &mut bevy::app::App) {
        app.add_plugins((
            crate::world::events::WorldEditPlugin,
            crate::lights::plugin::LightsPlugin,
            crate::render::VoxelRenderPlugin,
            crate::dynamic::DynamicObjectsPlugin,
        ));
    }
}
