//! The client's side: it receives the world in pieces, then applies the server's edits in the server's order
//! (its own come back like everyone else's, marked so undo records them). Its own requests (the player's edits,
//! undo and redo) leave as `EditAsk`s instead of changing the world directly, so every client's world follows the
//! one order the server chose.

use super::protocol::*;
use super::snapshot::Assembly;
use crate::world::events::{ApplyEdits, EditApplied, EditRequest, EditsFromServer};
use crate::world::{Edit, VoxelWorld};
use bevy::prelude::*;
use bevy_replicon::prelude::*;
use std::sync::Arc;

/// Where the client stands.
#[derive(Resource, Debug, Default)]
pub struct NetClient {
    /// The name it asks to be called.
    pub name: String,
    /// Its id on the server (known from the first world piece).
    pub me: Option<u64>,
    /// Whether the world has arrived.
    pub loaded: bool,
    /// Number of the last server edit applied.
    pub seq: u64,
    /// Everyone playing, as last heard.
    pub players: Vec<PlayerInfo>,
    /// Requests the server refused, and the last reason.
    pub refusals: u64,
    pub last_refusal: Option<String>,
    /// Lines from the server's operator, and how many have come.
    pub notices: u64,
    pub last_notice: Option<String>,
    /// Why the server sent this client away (kicked, banned), when it did.
    pub sent_away: Option<String>,
    /// Where the server says this player was when it last left (it returns there).
    pub returned_to: Option<Pose>,
    /// What went wrong with the server's data, if anything (the client then disconnects).
    pub error: Option<String>,
    assembly: Assembly,
    /// Edits that arrived before the world was complete.
    early: Vec<EditDone>,
}

impl NetClient {
    pub fn named(name: &str) -> Self {
        NetClient { name: name.to_string(), ..default() }
    }

    /// Forgets the connection's world and numbering for a new join; the name, the players and the server's
    /// words are kept.
    pub fn restart_join(&mut self) {
        self.me = None;
        self.loaded = false;
        self.seq = 0;
        self.returned_to = None;
        self.assembly = Assembly::default();
        self.early.clear();
    }

    /// Fraction of the world received.
    pub fn progress(&self) -> f32 {
        if self.loaded { 1.0 } else { self.assembly.progress() }
    }
}

pub struct NetClientPlugin;

impl Plugin for NetClientPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<NetClient>()
            .insert_resource(EditsFromServer)
            .add_systems(
                Update,
                (
                    say_hello.run_if(in_state(ClientState::Connected)),
                    take_world_and_edits.in_set(ApplyEdits),
                    (forward_requests, take_clock, take_players, take_refusals, take_notices, take_welcome_back),
                    rejoin_when_lost.run_if(resource_exists::<Join>),
                )
                    .chain(),
            )
            .init_resource::<Rejoin>();
    }
}

/// Says hello until the world starts arriving (a hello before the server authorized the client is dropped).
fn say_hello(client: Res<NetClient>, mut hello: MessageWriter<Hello>, mut since: Local<f32>, time: Res<Time>) {
    *since -= time.delta_secs();
    if client.me.is_none() && *since <= 0.0 {
        *since = 0.25;
        hello.write(Hello { name: client.name.clone() });
    }
}

fn apply_done(
    world: &mut VoxelWorld,
    done: &EditDone,
    me: Option<u64>,
    applied: Option<&mut MessageWriter<EditApplied>>,
) {
    let edit = Edit::from(&done.edit);
    let (min, max) = edit.bounds();
    let mine = me == Some(done.by) && done.undoable;
    let before = (mine && applied.is_some()).then(|| Arc::from(world.grid.read_box(min, max + IVec3::ONE)));
    match world.apply(edit.clone()) {
        Ok(changed) if changed > 0 => {
            if let Some(applied) = applied {
                applied.write(EditApplied { edit, min, max, changed, before });
            }
        }
        Ok(_) => {}
        // The server applied it to the same world: refusing it here means the worlds differ.
        Err(e) => warn!("edit {} from the server does not apply here: {e}", done.seq),
    }
}

#[allow(clippy::too_many_arguments)]
fn take_world_and_edits(
    mut commands: Commands,
    mut client: ResMut<NetClient>,
    mut pieces: MessageReader<WorldPiece>,
    mut edits: MessageReader<EditDone>,
    world: Option<ResMut<VoxelWorld>>,
    mut applied: MessageWriter<EditApplied>,
    renet: Option<ResMut<bevy_replicon_renet::RenetClient>>,
    gpu: Option<Res<bevy::render::renderer::RenderDevice>>,
) {
    let client = &mut *client;
    let mut renet = renet;
    let mut fresh: Option<(u64, VoxelWorld)> = None;
    for piece in pieces.read() {
        client.me = Some(piece.player);
        match client.assembly.add(piece.index, piece.count, &piece.bytes) {
            Ok(Some(world)) => fresh = Some((piece.seq, world)),
            Ok(None) => {}
            Err(e) => {
                error!("{e}");
                client.error = Some(e);
                if let Some(renet) = renet.as_mut() {
                    renet.disconnect();
                }
            }
        }
    }
    if let Some((seq, mut world)) = fresh {
        // Edits that came before the last piece: those after the world's own number apply now, in order.
        for done in std::mem::take(&mut client.early).iter().filter(|d| d.seq > seq) {
            apply_done(&mut world, done, client.me, None);
            client.seq = done.seq;
        }
        client.seq = client.seq.max(seq);
        for done in edits.read() {
            if done.seq > client.seq {
                apply_done(&mut world, done, client.me, None);
                client.seq = done.seq;
            }
        }
        // A world this GPU cannot bind would stop the renderer: leave with the reason instead.
        if let Some(Err(e)) = gpu.map(|gpu| crate::render::scene::world::fits_device(&world, &gpu)) {
            error!("{e}");
            client.error = Some(e);
            if let Some(renet) = renet.as_mut() {
                renet.disconnect();
            }
            return;
        }
        client.loaded = true;
        let objects = world.objects.clone().unwrap_or_default();
        commands.insert_resource(world);
        commands.queue(move |app_world: &mut World| {
            let old: Vec<Entity> =
                app_world.query_filtered::<Entity, With<crate::dynamic::DynamicObject>>().iter(app_world).collect();
            old.into_iter().for_each(|e| {
                app_world.despawn(e);
            });
            if let Err(e) = crate::dynamic::saved::spawn_saved(app_world, &objects) {
                warn!("objects not restored: {e}");
            }
        });
        return;
    }
    let me = client.me;
    match (client.loaded, world) {
        (true, Some(mut world)) => {
            for done in edits.read() {
                if done.seq <= client.seq {
                    continue;
                }
                if done.seq != client.seq + 1 {
                    warn!("edit {} arrived after {}: edits are missing", done.seq, client.seq);
                }
                apply_done(&mut world, done, me, Some(&mut applied));
                client.seq = done.seq;
            }
        }
        _ => client.early.extend(edits.read().cloned()),
    }
}

/// The player's edits (and undo's restores) go to the server instead of changing the world here.
fn forward_requests(
    client: Res<NetClient>,
    mut requests: MessageReader<EditRequest>,
    mut asks: MessageWriter<EditAsk>,
) {
    for request in requests.read() {
        if client.loaded {
            asks.write(EditAsk { edit: NetEdit::from(&request.edit), undoable: request.undoable });
        }
    }
}

fn take_clock(
    mut clock: MessageReader<ClockNow>,
    world: Option<ResMut<VoxelWorld>>,
    settings: Option<ResMut<crate::settings::RenderSettings>>,
) {
    let Some(now) = clock.read().last() else { return };
    if let Some(mut world) = world {
        world.bypass_change_detection().time_of_day = Some(now.hours);
    }
    if let Some(mut settings) = settings {
        settings.time = now.hours;
    }
}

fn take_players(mut lists: MessageReader<Players>, mut client: ResMut<NetClient>) {
    if let Some(list) = lists.read().last() {
        client.players = list.players.clone();
    }
}

fn take_refusals(mut refusals: MessageReader<Refused>, mut client: ResMut<NetClient>) {
    for refusal in refusals.read() {
        client.refusals += 1;
        client.last_refusal = Some(refusal.reason.clone());
    }
}

fn take_notices(mut notices: MessageReader<Notice>, mut client: ResMut<NetClient>) {
    for notice in notices.read() {
        let text: String = notice.text.chars().filter(|c| !c.is_control()).take(200).collect();
        if notice.farewell {
            client.sent_away = Some(text.clone());
        }
        client.notices += 1;
        client.last_notice = Some(text);
    }
}

fn take_welcome_back(mut back: MessageReader<WelcomeBack>, mut client: ResMut<NetClient>) {
    if let Some(back) = back.read().last() {
        let finite = back.pose.position.iter().all(|c| c.is_finite()) && back.pose.yaw.is_finite();
        client.returned_to = finite.then_some(back.pose);
    }
}

/// Dialing the server again after the connection was lost (or the first dial failed), with a growing wait.
#[derive(Resource, Debug, Default)]
pub struct Rejoin {
    /// Dials since the last join that brought the world.
    pub attempts: u32,
    /// Seconds until the next dial.
    pub wait: f32,
}

/// The wait before dial `attempt` (1, 2, ...): 1, 2, 4, 8, then 15 seconds.
pub fn rejoin_wait(attempt: u32) -> f32 {
    (1u32 << attempt.saturating_sub(1).min(4)).min(15) as f32
}

/// While the connection is down, dials the `Join`'s server again after `rejoin_wait`, as the same name; the world
/// then comes anew. Not after the server sent this client away or its data was bad.
fn rejoin_when_lost(
    mut commands: Commands,
    state: Res<State<ClientState>>,
    join: Res<Join>,
    mut rejoin: ResMut<Rejoin>,
    mut client: ResMut<NetClient>,
    channels: Res<RepliconChannels>,
    time: Res<Time>,
) {
    match state.get() {
        ClientState::Connected => {
            if client.loaded {
                *rejoin = Rejoin::default();
            }
            return;
        }
        ClientState::Connecting => return,
        ClientState::Disconnected => {}
    }
    if client.sent_away.is_some() || client.error.is_some() {
        return;
    }
    if rejoin.wait > 0.0 {
        rejoin.wait -= time.delta_secs();
        if rejoin.wait > 0.0 {
            return;
        }
    } else if rejoin.attempts == 0 {
        // Just lost: wait before the first dial.
        rejoin.attempts = 1;
        rejoin.wait = rejoin_wait(1);
        return;
    }
    match super::transport::client_transport(
        &channels,
        join.server,
        join.secret.as_deref(),
        super::transport::fresh_client_id(),
    ) {
        Ok((renet, transport)) => {
            // Removed first: the transport's plugin starts connecting when the client resource is added, and a
            // replaced one does not count as added.
            commands.remove_resource::<bevy_replicon_renet::RenetClient>();
            commands.remove_resource::<bevy_replicon_renet::netcode::NetcodeClientTransport>();
            commands.insert_resource(renet);
            commands.insert_resource(transport);
            client.restart_join();
        }
        Err(e) => warn!("cannot dial {} again: {e}", join.server),
    }
    rejoin.attempts += 1;
    rejoin.wait = rejoin_wait(rejoin.attempts);
}

/// Where a game joins, and as whom.
#[derive(Resource, Clone, Debug)]
pub struct Join {
    pub server: std::net::SocketAddr,
    pub secret: Option<String>,
    pub name: String,
    /// The view of the server's world to start at (default: its first).
    pub view: Option<String>,
}

/// The world a joining game shows until the server's has arrived: a small stone floor under the sky.
pub fn waiting_world() -> VoxelWorld {
    use crate::world::{Material, Palette};
    let mut world = VoxelWorld::new(UVec3::new(16, 8, 16), Palette::new(vec![Material::solid("stone", [0.5; 3])]));
    // The fill is inside the world and the material is in the palette.
    let _ = world.apply(Edit::FillBox { min: IVec3::ZERO, max: IVec3::new(15, 0, 15), material: 1 });
    // No objects until the server's arrive (not the game's default ones).
    world.objects = Some(Vec::new());
    world.views.push(crate::world::CameraView {
        name: "waiting".into(),
        origin: [8.0, 4.0, -6.0],
        direction: [0.0, -0.3, 1.0],
        fov_deg: 60.0,
    });
    world
}
