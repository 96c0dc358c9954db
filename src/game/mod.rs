//! The playable game: a window, the voxel renderer, the player, building, undo, save/load and the HUD.
//!
//! `GameLogicPlugin` holds everything that needs no window (so tests drive it headless through messages);
//! `run_game` adds the window, input mapping and HUD on top.

pub mod dynamic_resolution;
pub mod endless;
pub mod frame_pacing;
pub mod hud;
pub mod interaction;
pub mod models;
pub mod objects;
pub mod player;
pub mod save_load;
pub mod settings_file;
pub mod settings_panel;
pub mod together;
pub mod undo;
pub mod window_fit;

use crate::render::camera::voxel_camera_bundle;
use crate::settings::RenderSettings;
use crate::world::VoxelWorld;
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use bevy::render::pipelined_rendering::PipelinedRenderingPlugin;
use std::path::PathBuf;

/// Game rules without input devices or UI: targeting, actions to edits, undo/redo, save/load.
pub struct GameLogicPlugin;

impl Plugin for GameLogicPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<hud::StatusLine>().add_plugins((
            interaction::InteractionPlugin,
            models::ModelPlugin,
            undo::UndoPlugin,
            save_load::SaveLoadPlugin,
        ));
    }
}

/// The clock `hours` moved by `step` hours, wrapping around midnight (0 and 24 are the same time; 24 reads 0).
pub fn step_clock(hours: f32, step: f32) -> f32 {
    (hours + step).rem_euclid(24.0)
}

/// Opens the game window on `world` and runs until the window closes. F5 and F9 use `save_path`; V drops
/// `model`, when given. With `join`, the game plays on a server instead: `world` shows until the server's
/// arrives, edits go to the server, and F9, V and the local clock are the server's business (F5 still saves a
/// copy of the shared world). With `endless`, `world` is its window, which follows the player, and F5 and F9
/// save and load its regions instead.
pub fn run_game(
    world: VoxelWorld,
    settings: RenderSettings,
    save_path: PathBuf,
    model: Option<models::ModelToPlace>,
    join: Option<crate::net::client::Join>,
    endless: Option<endless::EndlessPlay>,
) -> AppExit {
    let view = world.view(None).cloned().unwrap_or_else(|| world.overview());
    let mut app = App::new();
    if let Some(model) = model {
        app.insert_resource(model);
    }
    // V places a model's own colours in the grid; an endless world's region files hold the generator's palette.
    let models_placeable = endless.is_none();
    if let Some(endless) = endless {
        app.insert_resource(endless).add_plugins(endless::EndlessPlugin);
    }
    let plugins = DefaultPlugins.set(WindowPlugin {
        primary_window: Some(Window {
            title: "glowbrick".into(),
            resolution: (window_fit::PREFERRED_SIZE.x as u32, window_fit::PREFERRED_SIZE.y as u32).into(),
            resizable: true,
            ..default()
        }),
        ..default()
    });
    // With pacing on, the frame that reads a key also renders it: pipelined rendering would render the frame before
    // it first, one more frame of latency (docs/latency.md), for an overlap of CPU work the GPU-bound frame hides.
    let plugins = if settings.pacing { plugins.disable::<PipelinedRenderingPlugin>() } else { plugins };
    app.add_plugins(plugins)
        .insert_resource(world)
        .insert_resource(settings)
        .insert_resource(settings_file::SettingsFile(settings_file::beside(&save_path)))
        .insert_resource(save_load::SavePath(save_path))
        .add_plugins((
            crate::core_plugin::GlowbrickCorePlugin,
            GameLogicPlugin,
            player::PlayerPlugin,
            interaction::InteractionInputPlugin,
            hud::HudPlugin,
            settings_panel::SettingsPanelPlugin,
            objects::GameObjectsPlugin,
            frame_pacing::FramePacingPlugin,
            dynamic_resolution::DynamicResolutionPlugin,
        ))
        .add_systems(Startup, move |mut commands: Commands| {
            commands.spawn((voxel_camera_bundle(&view), Tonemapping::AcesFitted, player::Player::looking(&view)));
        })
        .add_systems(
            Update,
            (undo::history_keys, lighting_toggle_keys, debug_view_key, window_fit::fit_window_to_screen),
        );
    // A settings change shows the generic pipelines' frame while its own compile, never a blank one.
    if let Some(render_app) = app.get_sub_app_mut(bevy::render::RenderApp) {
        render_app.insert_resource(crate::render::frame::GenericFallback);
    }
    match join {
        Some(join) => {
            let name = join.name.clone();
            app.insert_resource(join)
                .insert_resource(crate::net::client::NetClient::named(&name))
                .add_plugins((
                    crate::net::NetworkingPlugin,
                    crate::net::client::NetClientPlugin,
                    crate::net::endless_client::EndlessClientPlugin,
                    together::TogetherPlugin,
                ))
                .add_systems(Update, save_key_only);
        }
        None => {
            app.add_systems(Update, (save_load::save_load_keys, clock_keys));
            if models_placeable {
                app.add_systems(Update, models::model_key);
            }
        }
    }
    app.run()
}

/// F5 in a joined game saves a copy of a bounded shared world (F9 would load a world the others do not have); an
/// endless world is saved by its server.
fn save_key_only(
    keys: Res<ButtonInput<KeyCode>>,
    mut actions: MessageWriter<save_load::SaveAction>,
    endless: Option<Res<crate::net::endless_client::EndlessClient>>,
    mut status: ResMut<hud::StatusLine>,
) {
    if keys.just_pressed(KeyCode::F5) {
        match endless {
            Some(_) => status.show("the server saves the endless world: every change is kept there".into()),
            None => {
                actions.write(save_load::SaveAction::Save);
            }
        }
    }
}

/// T moves the clock an hour on (Shift+T back).
fn clock_keys(keys: Res<ButtonInput<KeyCode>>, mut settings: ResMut<RenderSettings>) {
    if keys.just_pressed(KeyCode::KeyT) {
        let back = keys.pressed(KeyCode::ShiftLeft) || keys.pressed(KeyCode::ShiftRight);
        settings.time = step_clock(settings.time, if back { -1.0 } else { 1.0 });
        info!("time of day: {:.1} h", settings.time);
    }
}

/// G turns the GI cache on and off, N the denoiser.
fn lighting_toggle_keys(keys: Res<ButtonInput<KeyCode>>, mut settings: ResMut<RenderSettings>) {
    if keys.just_pressed(KeyCode::KeyG) {
        settings.gi.enabled = !settings.gi.enabled;
        info!("{}", settings.summary());
    }
    if keys.just_pressed(KeyCode::KeyN) {
        settings.denoise = !settings.denoise;
        info!("{}", settings.summary());
    }
}

/// F6 cycles the debug views (lit, albedo, normal, depth, the denoiser's variance and history, the GI cache's
/// light).
fn debug_view_key(keys: Res<ButtonInput<KeyCode>>, mut settings: ResMut<RenderSettings>) {
    use crate::settings::DebugView;
    if keys.just_pressed(KeyCode::F6) {
        settings.debug = match settings.debug {
            DebugView::None => DebugView::Albedo,
            DebugView::Albedo => DebugView::Normal,
            DebugView::Normal => DebugView::Depth,
            DebugView::Depth => DebugView::Variance,
            DebugView::Variance => DebugView::History,
            DebugView::History => DebugView::Indirect,
            _ => DebugView::None,
        };
        info!("debug view: {:?}", settings.debug);
    }
}
