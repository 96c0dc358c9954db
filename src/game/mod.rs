//! The playable game: a window, the voxel renderer, a fly camera, and saving with F5.

pub mod fly_camera;

use crate::render::camera::voxel_camera_bundle;
use crate::settings::RenderSettings;
use crate::world::format::save_world;
use crate::world::{CameraView, VoxelWorld};
use bevy::core_pipeline::tonemapping::Tonemapping;
use bevy::prelude::*;
use std::path::PathBuf;

/// Where F5 saves the world.
#[derive(Resource, Clone, Debug)]
pub struct SavePath(pub PathBuf);

/// Opens the game window on `world` and runs until the window closes.
pub fn run_game(world: VoxelWorld, settings: RenderSettings, save_path: PathBuf) -> AppExit {
    let view = world.view(None).cloned().unwrap_or_else(|| world.overview());
    App::new()
        .add_plugins(DefaultPlugins.set(WindowPlugin {
            primary_window: Some(Window {
                title: "glowbrick".into(),
                resolution: (1280u32, 720u32).into(),
                ..default()
            }),
            ..default()
        }))
        .insert_resource(world)
        .insert_resource(settings)
        .insert_resource(SavePath(save_path))
        .add_plugins((crate::GlowbrickCorePlugin, fly_camera::FlyCameraPlugin))
        .add_systems(Startup, move |mut commands: Commands| {
            commands.spawn((
                voxel_camera_bundle(&view),
                Tonemapping::AcesFitted,
                fly_camera::FlyCamera::looking(&view),
            ));
        })
        .add_systems(Update, (save_on_f5, toggle_debug_view))
        .run()
}

/// F5 saves the world, with the player's camera as its first view ("player") so reopening starts there.
fn save_on_f5(
    keys: Res<ButtonInput<KeyCode>>,
    mut world: ResMut<VoxelWorld>,
    path: Res<SavePath>,
    camera: Single<(&Transform, &Projection), With<fly_camera::FlyCamera>>,
) {
    if keys.just_pressed(KeyCode::F5) {
        let (transform, projection) = *camera;
        let fov = match projection {
            Projection::Perspective(p) => p.fov.to_degrees(),
            _ => 60.0,
        };
        let player = CameraView {
            name: "player".into(),
            origin: transform.translation.into(),
            direction: transform.forward().as_vec3().into(),
            fov_deg: fov,
        };
        world.views.retain(|v| v.name != "player");
        world.views.insert(0, player);
        match save_world(&world, &path.0) {
            Ok(()) => info!("saved {}", path.0.display()),
            Err(e) => error!("could not save {}: {e}", path.0.display()),
        }
    }
}

/// F3 cycles the debug views (lit, albedo, normal, depth).
fn toggle_debug_view(keys: Res<ButtonInput<KeyCode>>, mut settings: ResMut<RenderSettings>) {
    use crate::settings::DebugView;
    if keys.just_pressed(KeyCode::F3) {
        settings.debug = match settings.debug {
            DebugView::None => DebugView::Albedo,
            DebugView::Albedo => DebugView::Normal,
            DebugView::Normal => DebugView::Depth,
            _ => DebugView::None,
        };
        info!("debug view: {:?}", settings.debug);
    }
}
