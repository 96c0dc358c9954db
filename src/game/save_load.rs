//! Saving and loading in game: F5 saves the world (with the player's camera as its first view, the time of day
//! and the moving objects at their phase) to the save path with an atomic write, keeping one `.bak` of the
//! previous save; F9 loads the save path (its objects replace the live ones; a file saved before objects were
//! keeps them). A failed load leaves the current world as it is and says why on the HUD.

use super::hud::StatusLine;
use super::player::Player;
use crate::dynamic::DynamicObject;
use crate::dynamic::saved::saved_objects;
pub use crate::world::format::{backup_path, save_with_backup};
use crate::world::source::load_path;
use crate::world::{CameraView, VoxelWorld};
use bevy::prelude::*;
use std::path::PathBuf;

/// Where F5 saves and F9 loads.
#[derive(Resource, Clone, Debug)]
pub struct SavePath(pub PathBuf);

/// Asks to save or load.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub enum SaveAction {
    Save,
    Load,
}

pub struct SaveLoadPlugin;

impl Plugin for SaveLoadPlugin {
    fn build(&self, app: &mut App) {
        // An endless world saves and loads its regions instead (`game::endless`).
        app.add_message::<SaveAction>()
            .add_systems(Update, save_or_load.run_if(not(resource_exists::<super::endless::EndlessPlay>)));
    }
}

/// F5 saves, F9 loads. Needs a window.
pub fn save_load_keys(keys: Res<ButtonInput<KeyCode>>, mut actions: MessageWriter<SaveAction>) {
    if keys.just_pressed(KeyCode::F5) {
        actions.write(SaveAction::Save);
    }
    if keys.just_pressed(KeyCode::F9) {
        actions.write(SaveAction::Load);
    }
}

/// The player's camera as a view named "player".
pub fn player_view(transform: &Transform, fov_deg: f32) -> CameraView {
    CameraView {
        name: "player".into(),
        origin: transform.translation.into(),
        direction: transform.forward().as_vec3().into(),
        fov_deg,
    }
}

#[allow(clippy::too_many_arguments)]
fn save_or_load(
    mut actions: MessageReader<SaveAction>,
    mut commands: Commands,
    world: Option<ResMut<VoxelWorld>>,
    path: Res<SavePath>,
    mut camera: Query<(&mut Transform, &mut Player, &Projection)>,
    mut status: ResMut<StatusLine>,
    mut settings: Option<ResMut<crate::settings::RenderSettings>>,
    objects: Query<(Entity, &DynamicObject)>,
    gpu: Option<Res<bevy::render::renderer::RenderDevice>>,
) {
    let Some(mut world) = world else { return };
    for action in actions.read() {
        match action {
            SaveAction::Save => {
                if let Ok((transform, _, projection)) = camera.single() {
                    let fov = match projection {
                        Projection::Perspective(p) => p.fov.to_degrees(),
                        _ => 60.0,
                    };
                    world.views.retain(|v| v.name != "player");
                    world.views.insert(0, player_view(transform, fov));
                }
                if let Some(settings) = &settings {
                    world.time_of_day = Some(settings.time);
                }
                world.objects = Some(saved_objects(objects.iter().map(|(_, o)| o)));
                let start = std::time::Instant::now();
                match save_with_backup(&world, &path.0) {
                    Ok(()) => status.show(format!(
                        "saved {} ({:.1} MB in {:.2} s)",
                        path.0.display(),
                        std::fs::metadata(&path.0).map_or(0, |m| m.len()) as f64 / 1e6,
                        start.elapsed().as_secs_f64()
                    )),
                    Err(e) => status.show(format!("could not save {}: {e}", path.0.display())),
                }
            }
            SaveAction::Load => {
                let start = std::time::Instant::now();
                // A world this GPU cannot bind would stop the renderer: keep the one being played.
                let fits = |loaded: VoxelWorld| match &gpu {
                    Some(gpu) => crate::render::scene::world::fits_device(&loaded, gpu).map(|()| loaded),
                    None => Ok(loaded),
                };
                match load_path(&path.0).map_err(|e| e.to_string()).and_then(fits) {
                    Ok(loaded) => {
                        if let (Some(view), Ok((mut transform, mut player, _))) =
                            (loaded.view(None), camera.single_mut())
                        {
                            *transform = crate::world::view_transform(view);
                            *player = Player { walking: player.walking, ..Player::looking(view) };
                        }
                        if let (Some(settings), Some(hours)) = (settings.as_mut(), loaded.time_of_day) {
                            settings.time = hours;
                        }
                        status.show(format!("loaded {} in {:.2} s", path.0.display(), start.elapsed().as_secs_f64()));
                        let saved = loaded.objects.clone();
                        commands.insert_resource(loaded);
                        if let Some(saved) = saved {
                            objects.iter().for_each(|(entity, _)| commands.entity(entity).despawn());
                            commands.queue(move |app_world: &mut World| {
                                super::objects::spawn_saved_or_report(app_world, &saved)
                            });
                        }
                    }
                    Err(e) => status.show(format!("load failed, world unchanged: {e}")),
                }
            }
        }
    }
}
