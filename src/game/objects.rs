//! Moving objects in the game: a drifting lantern and a swinging block near the start view, and O to spawn
//! another drifting lantern in front of the player.

use super::hud::StatusLine;
use crate::dynamic::{DynamicObject, Motion, ObjectClock, model_for_world, spawn_object};
use crate::world::VoxelWorld;
use bevy::prelude::*;
use std::sync::Arc;

/// Spawns the default objects around `centre` (a point in front of the start view): a lantern drifting in a
/// circle and a block swinging like a pendulum.
pub fn spawn_default_objects(
    commands: &mut Commands,
    clock: &mut ObjectClock,
    world: &mut VoxelWorld,
    centre: Vec3,
) -> Result<(), String> {
    let lantern = Arc::new(model_for_world("lantern", world)?);
    let block = Arc::new(model_for_world("block", world)?);
    let size = world.grid.size().as_vec3();
    let inside = |p: Vec3| p.clamp(Vec3::splat(4.0), (size - 8.0).max(Vec3::splat(4.0)));
    spawn_object(
        commands,
        clock,
        0,
        lantern,
        Motion::Drift { radius: 5.0, period: 12.0 },
        inside(centre + Vec3::Y * 3.0),
    )?;
    let swing = Motion::Swing { length: 7.0, amplitude: 0.7, period: 5.0 };
    spawn_object(commands, clock, 1, block, swing, inside(centre + Vec3::new(6.0, 10.0, 0.0)))?;
    Ok(())
}

/// The world's saved objects, or (for a world saved before objects were) the default ones.
fn spawn_at_start(
    mut commands: Commands,
    mut clock: ResMut<ObjectClock>,
    mut world: ResMut<VoxelWorld>,
    mut status: ResMut<StatusLine>,
) {
    if let Some(saved) = world.objects.clone() {
        commands.queue(move |app_world: &mut World| spawn_saved_or_report(app_world, &saved));
        return;
    }
    // A generated world marks where its objects hang (over the village's fountain, the swinging block from the
    // frame at `world::generate::SWING_PIVOT`); otherwise they float in front of the start view.
    let centre = match world.view(Some("lantern")) {
        Some(marker) => marker.origin() - Vec3::Y * 3.0,
        None => {
            let view = world.view(None).cloned().unwrap_or_else(|| world.overview());
            view.origin() + view.direction().normalize_or_zero() * 14.0
        }
    };
    if let Err(e) = spawn_default_objects(&mut commands, &mut clock, &mut world, centre) {
        status.show(e);
    }
}

/// Spawns saved objects; a failure (a model whose materials no longer fit the palette) shows on the status line.
pub fn spawn_saved_or_report(app_world: &mut World, saved: &[crate::world::objects::SavedObject]) {
    if let Err(e) = crate::dynamic::saved::spawn_saved(app_world, saved) {
        app_world.resource_mut::<StatusLine>().show(format!("objects not restored: {e}"));
    }
}

/// Where O puts a lantern: 8 voxels in front of the camera (the model's minimum corner), drifting in a circle.
fn lantern_in_front(camera: &Transform) -> (Vec3, Motion) {
    (camera.translation + *camera.forward() * 8.0 - Vec3::splat(1.5), Motion::Drift { radius: 3.0, period: 8.0 })
}

/// O spawns a drifting lantern 8 voxels in front of the player.
fn spawn_key(
    keys: Res<ButtonInput<KeyCode>>,
    mut commands: Commands,
    mut clock: ResMut<ObjectClock>,
    mut world: ResMut<VoxelWorld>,
    camera: Query<&Transform, With<super::player::Player>>,
    objects: Query<(), With<DynamicObject>>,
    mut status: ResMut<StatusLine>,
) {
    if !keys.just_pressed(KeyCode::KeyO) {
        return;
    }
    let Ok(t) = camera.single() else { return };
    let result = model_for_world("lantern", &mut world).and_then(|model| {
        let (at, motion) = lantern_in_front(t);
        spawn_object(&mut commands, &mut clock, objects.iter().count(), Arc::new(model), motion, at)
    });
    match result {
        Ok(_) => status.show(format!("spawned a lantern ({} objects)", objects.iter().count() + 1)),
        Err(e) => status.show(e),
    }
}

/// O on a server: the server spawns the lantern for everyone (it comes back in the edits' order).
fn ask_spawn_key(
    keys: Res<ButtonInput<KeyCode>>,
    camera: Query<&Transform, With<super::player::Player>>,
    mut asks: MessageWriter<crate::net::protocol::SpawnAsk>,
    mut status: ResMut<StatusLine>,
) {
    if !keys.just_pressed(KeyCode::KeyO) {
        return;
    }
    let Ok(t) = camera.single() else { return };
    let (at, motion) = lantern_in_front(t);
    let object = crate::world::objects::SavedObject::new("lantern", &motion, at, 0.0);
    asks.write(crate::net::protocol::SpawnAsk { object });
    status.show("asked the server for a lantern".into());
}

/// Default objects at start, and the spawn key (needs a window).
pub struct GameObjectsPlugin;

impl Plugin for GameObjectsPlugin {
    fn build(&self, app: &mut App) {
        // On a server, objects are the server's: a lantern spawned here would be in no one else's world, so O asks
        // the server.
        let local = not(resource_exists::<crate::world::events::EditsFromServer>);
        let on_server = resource_exists::<crate::world::events::EditsFromServer>;
        app.add_systems(Startup, spawn_at_start)
            .add_systems(Update, (spawn_key.run_if(local), ask_spawn_key.run_if(on_server)));
    }
}
