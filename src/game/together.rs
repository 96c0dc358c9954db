//! The game's side of building together (`play --connect`): the connection's panel (joining progress, who is
//! playing), the camera's move into the server's world when it arrives, the clock keys asking the server, and the
//! other players drawn where they are (a small moving block each, named on the panel).

use super::hud::StatusLine;
use super::player::Player;
use crate::dynamic::{DynamicObject, Motion, ObjectClock, spawn_object};
use crate::net::client::Join;
use crate::net::client::NetClient;
use crate::net::endless_client::EndlessClient;
use crate::net::protocol::{ClockAsk, Pose};
use crate::world::VoxelWorld;
use bevy::prelude::*;
use bevy_replicon::prelude::{ClientState, RepliconChannels};
use std::sync::Arc;

/// Marks the figure drawn for another player.
#[derive(Component)]
struct Figure(u64);

#[derive(Component)]
struct PlayersText;

pub struct TogetherPlugin;

impl Plugin for TogetherPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Startup, (spawn_panel, connect_on_startup)).add_systems(
            Update,
            (
                send_pose,
                endless_window_follows_camera,
                show_refusals,
                enter_arrived_world,
                clock_keys,
                draw_figures,
                update_panel,
                say_when_lost,
            ),
        );
    }
}

fn spawn_panel(mut commands: Commands) {
    commands.spawn((
        Node { position_type: PositionType::Absolute, right: Val::Px(6.0), top: Val::Px(24.0), ..default() },
        Text::new(""),
        TextFont { font_size: FontSize::Px(14.0), ..default() },
        TextColor(Color::srgba(1.0, 1.0, 1.0, 0.85)),
        PlayersText,
    ));
}

/// When the server's world arrives, the camera moves to its first view, or where the server says this player was
/// when it last left; when it arrives again after a lost connection, the camera stays where the player is.
#[allow(clippy::too_many_arguments)]
fn enter_arrived_world(
    client: Res<NetClient>,
    join: Res<Join>,
    world: Res<VoxelWorld>,
    mut seen: Local<Option<u64>>,
    mut joined_before: Local<bool>,
    mut camera: Query<(&mut Transform, &mut Player)>,
    mut settings: ResMut<crate::settings::RenderSettings>,
    mut status: ResMut<StatusLine>,
    endless: Option<Res<EndlessClient>>,
) {
    // The waiting world is the first one seen; the next is the server's.
    if *seen == Some(world.instance) {
        return;
    }
    *seen = Some(world.instance);
    if !client.loaded {
        return;
    }
    // An endless world's window is made around where the player starts (again after a lost connection: its
    // coordinates are new), and its first view is there.
    if let Some(endless) = endless {
        let view = world.view(None).cloned().unwrap_or_else(|| world.overview());
        if let Ok((mut transform, mut player)) = camera.single_mut() {
            *transform = crate::world::view_transform(&view);
            *player = Player { walking: player.walking, ..Player::looking(&view) };
        }
        settings.time = world.time_of_day.unwrap_or(settings.time);
        *joined_before = true;
        status.show(format!("joined the endless world of seed {}: edits near you are shared", endless.seed()));
        return;
    }
    if std::mem::replace(&mut *joined_before, true) {
        status.show("joined again: the server's world as it is now".into());
        return;
    }
    let named = join.view.as_deref().and_then(|name| world.view(Some(name)));
    let mut view = named.or(world.view(None)).cloned().unwrap_or_else(|| world.overview());
    if let Some(pose) = client.returned_to {
        view.origin = pose.position;
        view.direction = [pose.yaw.sin(), 0.0, pose.yaw.cos()];
    }
    if let Ok((mut transform, mut player)) = camera.single_mut() {
        *transform = crate::world::view_transform(&view);
        *player = Player { walking: player.walking, ..Player::looking(&view) };
    }
    if let Some(hours) = world.time_of_day {
        settings.time = hours;
    }
    let size = world.grid.size();
    let mut joined = format!("joined: a world of {}x{}x{} voxels", size.x, size.y, size.z);
    if let (Some(name), None) = (&join.view, named) {
        let names: Vec<&str> = world.views.iter().map(|v| v.name.as_str()).collect();
        joined += &format!("; it has no view '{name}' (its views: {})", names.join(", "));
    }
    status.show(joined);
}

/// T / Shift+T ask the server to move the clock (everyone sees the same time of day).
fn clock_keys(
    keys: Res<ButtonInput<KeyCode>>,
    settings: Res<crate::settings::RenderSettings>,
    mut asks: MessageWriter<ClockAsk>,
) {
    if keys.just_pressed(KeyCode::KeyT) {
        let back = keys.pressed(KeyCode::ShiftLeft) || keys.pressed(KeyCode::ShiftRight);
        asks.write(ClockAsk { hours: super::step_clock(settings.time, if back { -1.0 } else { 1.0 }) });
    }
}

/// Where a figure's minimum corner is from its player's eye: a column of two voxels with its head at the eye.
const FIGURE_EYE: Vec3 = Vec3::new(0.5, super::player::EYE_HEIGHT, 0.5);

/// A player's figure: two voxels, a body and a head, of the world's first two building materials (only the
/// server's own materials: one the server lacks would have another id in another client's palette).
fn figure_model(world: &VoxelWorld) -> Result<crate::dynamic::model::VoxelModel, String> {
    let palette = &world.palette;
    let mut solid = (1..palette.id_count() as u16).filter(|&m| !palette.is_emissive(m)).filter_map(|m| palette.get(m));
    let body = solid.next().ok_or("the world has no building material")?;
    let head = solid.next().unwrap_or(body);
    let text = format!(
        "(name: \"figure\", legend: {{\"b\": {:?}, \"h\": {:?}}}, layers: [[\"b\"], [\"h\"]])",
        body.name, head.name
    );
    crate::dynamic::model::VoxelModel::from_ron(&text, "a player's figure", palette)
}

/// Players nearer than this (voxels) are not drawn: two players who join at the same view would each see the
/// inside of the other's figure.
const NEAREST_FIGURE: f32 = 2.5;

/// Keeps one figure per other player, at its camera.
#[allow(clippy::too_many_arguments)]
fn draw_figures(
    mut commands: Commands,
    client: Res<NetClient>,
    world: Option<Res<VoxelWorld>>,
    mut clock: ResMut<ObjectClock>,
    mut figures: Query<(Entity, &Figure, &mut DynamicObject)>,
    objects: Query<(), With<DynamicObject>>,
    camera: Query<&Transform, With<Player>>,
    mut model: Local<Option<(u64, Arc<crate::dynamic::model::VoxelModel>)>>,
) {
    let Some(world) = world else { return };
    if !client.loaded {
        return;
    }
    let here = camera.single().map(|t| t.translation).unwrap_or(Vec3::splat(f32::MAX));
    let apart = |p: &&crate::net::protocol::PlayerInfo| {
        p.pose.is_some_and(|pose| Vec3::from(pose.position).distance(here) >= NEAREST_FIGURE)
    };
    let others: Vec<_> = client.players.iter().filter(|p| Some(p.id) != client.me).filter(apart).collect();
    for (entity, figure, mut object) in &mut figures {
        match others.iter().find(|p| p.id == figure.0).and_then(|p| p.pose) {
            Some(pose) => object.anchor = Vec3::from(pose.position) - FIGURE_EYE,
            None => commands.entity(entity).despawn(),
        }
    }
    for player in others {
        if figures.iter().any(|(_, f, _)| f.0 == player.id) {
            continue;
        }
        if model.as_ref().is_none_or(|(instance, _)| *instance != world.instance) {
            match figure_model(&world) {
                Ok(m) => *model = Some((world.instance, Arc::new(m))),
                Err(e) => {
                    warn!("no figure for other players: {e}");
                    return;
                }
            }
        }
        let Some((_, figure_model)) = model.as_ref() else { return };
        let at = Vec3::from(player.pose.map_or([0.0; 3], |p| p.position)) - FIGURE_EYE;
        if let Ok(entity) =
            spawn_object(&mut commands, &mut clock, objects.iter().count(), figure_model.clone(), Motion::Still, at)
        {
            commands.entity(entity).insert(Figure(player.id));
        }
    }
}

fn update_panel(
    client: Res<NetClient>,
    endless: Option<Res<EndlessClient>>,
    camera: Query<&Transform, With<Player>>,
    state: Res<State<ClientState>>,
    mut text: Query<&mut Text, With<PlayersText>>,
) {
    let Ok(mut text) = text.single_mut() else { return };
    let here = camera.single().map(|t| t.translation).unwrap_or_default();
    let shown = if !client.loaded {
        match (state.get(), endless.as_deref()) {
            (ClientState::Connected, Some(endless)) => {
                format!("making the world around you: {} regions", endless.held_count())
            }
            (ClientState::Connected, None) => format!("receiving the world: {:.0}%", client.progress() * 100.0),
            _ => "connecting...".to_string(),
        }
    } else {
        let mut lines = vec![format!("{} playing", client.players.len())];
        for p in &client.players {
            let name = &p.name;
            lines.push(match (Some(p.id) == client.me, p.pose) {
                (true, _) => format!("{name} (you)"),
                (false, Some(pose)) => format!("{name}  {:.0} m", Vec3::from(pose.position).distance(here)),
                (false, None) => name.clone(),
            });
        }
        lines.join("\n")
    };
    if text.0 != shown {
        text.0 = shown;
    }
}

/// Says so when the server goes away (edits then go nowhere; the world stays as it was).
fn say_when_lost(
    state: Res<State<ClientState>>,
    client: Res<NetClient>,
    mut status: ResMut<StatusLine>,
    mut was: Local<bool>,
) {
    let connected = *state.get() == ClientState::Connected;
    if *was && !connected {
        let why = client.error.clone().or_else(|| client.sent_away.clone());
        let again = why.is_none();
        let why = why.unwrap_or_else(|| "the server closed the connection or stopped answering".into());
        status.show(if again {
            format!("disconnected: {why}; joining again...")
        } else {
            format!("disconnected: {why}")
        });
    }
    *was = connected;
}

/// Opens the connection of the game's `Join` (a startup system: the channels are known once the plugins are built).
fn connect_on_startup(
    mut commands: Commands,
    join: Res<Join>,
    channels: Res<RepliconChannels>,
    mut status: ResMut<StatusLine>,
) {
    let id = crate::net::transport::fresh_client_id();
    match crate::net::transport::client_transport(&channels, join.server, join.secret.as_deref(), id) {
        Ok((client, transport)) => {
            commands.insert_resource(client);
            commands.insert_resource(transport);
            status.show(format!("joining {} as {}...", join.server, join.name));
        }
        Err(e) => status.show(e),
    }
}

/// The player's camera, ten times a second.
fn send_pose(
    time: Res<Time>,
    mut since: Local<f32>,
    client: Res<NetClient>,
    camera: Query<&Transform, With<Player>>,
    mut poses: MessageWriter<Pose>,
    endless: Option<Res<EndlessClient>>,
) {
    *since += time.delta_secs();
    // An endless world's client sends its pose in world coordinates itself.
    if *since < 0.1 || !client.loaded || endless.is_some() {
        return;
    }
    *since = 0.0;
    if let Ok(transform) = camera.single() {
        let forward = transform.forward();
        poses.write(Pose { position: transform.translation.into(), yaw: forward.x.atan2(forward.z) });
    }
}

/// In an endless world, the window follows the camera (and the server hears where it is from there).
fn endless_window_follows_camera(camera: Query<&Transform, With<Player>>, endless: Option<ResMut<EndlessClient>>) {
    let (Some(mut endless), Ok(transform)) = (endless, camera.single()) else { return };
    if endless.started() {
        let forward = transform.forward();
        endless.at = transform.translation;
        endless.yaw = forward.x.atan2(forward.z);
    }
}

/// The server's last refusal, and its operator's last line, on the status line.
fn show_refusals(client: Res<NetClient>, mut shown: Local<(u64, u64)>, mut status: ResMut<StatusLine>) {
    if client.refusals != shown.0 {
        shown.0 = client.refusals;
        if let Some(reason) = &client.last_refusal {
            status.show(format!("the server refused: {reason}"));
        }
    }
    if client.notices != shown.1 {
        shown.1 = client.notices;
        if let Some(text) = &client.last_notice {
            status.show(text.clone());
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_figure_is_two_voxels_of_the_worlds_own_building_materials() {
        let world = crate::world::recipe::generated_world(1, UVec3::new(64, 48, 64)).unwrap();
        let ids = world.palette.id_count();
        let figure = figure_model(&world).unwrap();
        assert_eq!(figure.size, UVec3::new(1, 2, 1));
        assert_eq!(world.palette.id_count(), ids, "no material added");
        let stone = crate::world::VoxelWorld::new(UVec3::splat(8), crate::world::Palette::new(vec![]));
        assert!(figure_model(&stone).is_err(), "a palette without building materials has no figure");
    }
}
