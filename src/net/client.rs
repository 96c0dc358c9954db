//! The client's side: it receives the world in pieces, then applies the server's changes (edits, spawned objects,
//! new materials) in the server's order, its own among everyone else's. Its own requests (edits, spawns, undo and
//! redo) leave as asks instead of changing the world directly, so every client's world follows the one order the
//! server chose. Moving objects follow the server's clock.

use super::protocol::*;
use super::snapshot::Assembly;
use crate::dynamic::{BornAt, DynamicObject, model_for_world, spawn_object_in};
use crate::world::events::{ApplyEdits, EditApplied, EditRequest, EditsFromServer};
use crate::world::objects::SavedObject;
use crate::world::{Edit, Material, VoxelWorld};
use bevy::prelude::*;
use bevy_replicon::prelude::*;
use std::collections::VecDeque;
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
    /// Everyone playing, as last heard (in an endless world, positions in the window's coordinates).
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
    /// Ids of the server's palette as this client has it (materials past it are this client's own, not yet
    /// sent).
    pub palette_ids: usize,
    /// The server's object clock as this client reads it.
    pub clock: ServerClock,
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
        self.palette_ids = 0;
        self.clock = ServerClock::default();
        self.assembly = Assembly::default();
        self.early.clear();
    }

    /// Fraction of the world received.
    pub fn progress(&self) -> f32 {
        if self.loaded { 1.0 } else { self.assembly.progress() }
    }
}

/// The server's object clock read from here: `server - local` offsets sampled when a reading arrives (each is
/// the true offset less the message's delay, so the largest recent one is the closest), over a window short
/// enough that two machines' clocks cannot drift apart within it.
#[derive(Clone, Debug, Default)]
pub struct ServerClock {
    samples: VecDeque<(f64, f64)>,
}

/// Seconds of offset samples kept.
const CLOCK_WINDOW: f64 = 20.0;

impl ServerClock {
    /// A reading of the server's clock, `server` seconds, arriving at local time `local`.
    pub fn sample(&mut self, server: f64, local: f64) {
        if !server.is_finite() {
            return;
        }
        self.samples.push_back((local, server - local));
        while self.samples.front().is_some_and(|(at, _)| local - at > CLOCK_WINDOW) {
            self.samples.pop_front();
        }
    }

    /// The server's clock now, at local time `local`, once a reading has come.
    pub fn now(&self, local: f64) -> Option<f64> {
        let offset = self.samples.iter().map(|(_, offset)| *offset).reduce(f64::max)?;
        Some(local + offset)
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
                    // Before the server's edits: materials the game added for its requests (since the last frame's
                    // forwarding) leave the palette first, so the server's materials land at the server's ids.
                    forward_requests,
                    take_world_and_edits
                        .in_set(ApplyEdits)
                        .run_if(not(resource_exists::<super::endless_client::EndlessClient>)),
                    (take_clock, take_players, take_refusals, take_notices, take_welcome_back),
                    (take_server_time, follow_server_clock),
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

/// Applies one server change; a spawn is handed back (the object and its birth on the server's clock) for the
/// caller to add to the app's world.
fn apply_done(
    world: &mut VoxelWorld,
    done: &EditDone,
    applied: Option<&mut MessageWriter<EditApplied>>,
) -> Option<(SavedObject, f64)> {
    for material in &done.materials {
        world.palette.push(Material::from(material));
    }
    let edit = match &done.change {
        Change::Edit(edit) => Edit::from(edit),
        Change::Spawn { object, born } => return Some((object.clone(), *born)),
    };
    let (min, max) = edit.bounds();
    match world.apply(edit.clone()) {
        Ok(changed) if changed > 0 => {
            if let Some(applied) = applied {
                // No `before`: the server keeps the undo stacks.
                applied.write(EditApplied { edit, min, max, changed, before: None });
            }
        }
        Ok(_) => {}
        // The server applied it to the same world: refusing it here means the worlds differ.
        Err(e) => warn!("edit {} from the server does not apply here: {e}", done.seq),
    }
    None
}

/// Adds objects the server spawned, each following the server's clock from its birth.
fn spawn_from_server(app_world: &mut World, objects: &[(SavedObject, f64)]) {
    for (object, born) in objects {
        let spawned = {
            let mut world = app_world.resource_mut::<VoxelWorld>();
            model_for_world(&object.model, &mut world)
        }
        .and_then(|model| spawn_object_in(app_world, Arc::new(model), object.motion(), Vec3::from(object.anchor)));
        match spawned {
            Ok(entity) => {
                app_world.entity_mut(entity).insert(BornAt(*born));
            }
            Err(e) => warn!("object not shown: {e}"),
        }
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
    real: Res<Time<Real>>,
) {
    let client = &mut *client;
    let mut renet = renet;
    let mut fresh: Option<(u64, f64, VoxelWorld)> = None;
    for piece in pieces.read() {
        client.me = Some(piece.player);
        match client.assembly.add(piece.index, piece.count, &piece.bytes) {
            Ok(Some(world)) => fresh = Some((piece.seq, piece.clock, world)),
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
    if let Some((seq, clock, mut world)) = fresh {
        client.clock.sample(clock, real.elapsed_secs_f64());
        // The world's own objects, born their age before the clock it was copied at.
        let mut objects: Vec<(SavedObject, f64)> =
            world.objects.iter().flatten().map(|o| (o.clone(), clock - o.age as f64)).collect();
        // Edits that came before the last piece: those after the world's own number apply now, in order.
        for done in std::mem::take(&mut client.early).iter().filter(|d| d.seq > seq) {
            objects.extend(apply_done(&mut world, done, None));
            client.seq = done.seq;
        }
        client.seq = client.seq.max(seq);
        for done in edits.read() {
            if done.seq > client.seq {
                objects.extend(apply_done(&mut world, done, None));
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
        // The objects' models resolve in this palette (the server added their materials): it is the server's.
        client.palette_ids = world.palette.id_count();
        commands.insert_resource(world);
        commands.queue(move |app_world: &mut World| {
            let old: Vec<Entity> = app_world.query_filtered::<Entity, With<DynamicObject>>().iter(app_world).collect();
            old.into_iter().for_each(|e| {
                app_world.despawn(e);
            });
            spawn_from_server(app_world, &objects);
        });
        return;
    }
    match (client.loaded, world) {
        (true, Some(mut world)) => {
            for done in edits.read() {
                if done.seq <= client.seq {
                    continue;
                }
                if done.seq != client.seq + 1 {
                    warn!("edit {} arrived after {}: edits are missing", done.seq, client.seq);
                }
                let palette_is_servers = world.palette.id_count() == client.palette_ids;
                if let Some(spawn) = apply_done(&mut world, done, Some(&mut applied)) {
                    commands.queue(move |app_world: &mut World| spawn_from_server(app_world, &[spawn]));
                }
                if palette_is_servers {
                    client.palette_ids = world.palette.id_count();
                } else {
                    warn!("the palette holds materials the server did not send");
                }
                client.seq = done.seq;
            }
        }
        _ => client.early.extend(edits.read().cloned()),
    }
}

/// The player's edits (and undo's restores) go to the server instead of changing the world here. Materials the
/// game added to the palette for them (a dropped model's colours) go along and leave this palette: they come
/// back with the server's ids, in the server's order.
fn forward_requests(
    client: Res<NetClient>,
    mut requests: MessageReader<EditRequest>,
    mut asks: MessageWriter<EditAsk>,
    world: Option<ResMut<VoxelWorld>>,
    endless: Option<Res<super::endless_client::EndlessClient>>,
) {
    if requests.is_empty() {
        return;
    }
    // An endless world's edits travel in world coordinates, once its window is made.
    if let Some(endless) = endless {
        let Some(offset) = endless.offset() else {
            requests.clear();
            return;
        };
        for request in requests.read() {
            let edit = NetEdit::from(&request.edit.moved(offset));
            asks.write(EditAsk::plain(edit, request.undoable));
        }
        return;
    }
    let mut own = Vec::new();
    if let Some(mut world) = world
        && client.loaded
        && world.palette.id_count() > client.palette_ids
    {
        let known = client.palette_ids.max(1) - 1;
        own = world.palette.materials.drain(known..).map(|m| NetMaterial::from(&m)).collect();
    }
    let first_new = if own.is_empty() { 0 } else { client.palette_ids as u16 };
    for request in requests.read() {
        if client.loaded {
            let edit = NetEdit::from(&request.edit);
            asks.write(EditAsk { edit, undoable: request.undoable, first_new, materials: own.clone() });
        }
    }
}

fn take_server_time(mut times: MessageReader<ServerTime>, mut client: ResMut<NetClient>, real: Res<Time<Real>>) {
    let local = real.elapsed_secs_f64();
    for time in times.read() {
        client.clock.sample(time.seconds, local);
    }
}

/// Places the server's objects by the server's clock, whatever this client's frame rate.
fn follow_server_clock(
    client: Res<NetClient>,
    real: Res<Time<Real>>,
    mut objects: Query<(&mut DynamicObject, &BornAt, &mut Transform)>,
) {
    let Some(now) = client.clock.now(real.elapsed_secs_f64()) else { return };
    for (mut object, born, mut transform) in &mut objects {
        object.age = (now - born.0).max(0.0) as f32;
        transform.translation = object.anchor + object.motion.offset(object.age);
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

/// Everyone's poses, in this client's coordinates: an endless world's window's, once it is made.
fn take_players(
    mut lists: MessageReader<Players>,
    mut client: ResMut<NetClient>,
    endless: Option<Res<super::endless_client::EndlessClient>>,
) {
    if let Some(list) = lists.read().last() {
        client.players = list.players.clone();
        if let Some(offset) = endless.and_then(|e| e.offset()) {
            for pose in client.players.iter_mut().filter_map(|p| p.pose.as_mut()) {
                pose.position = (Vec3::from(pose.position) - offset.as_vec3()).into();
            }
        }
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
            // An endless world's window is made again around the player once the server welcomes it back.
            commands.remove_resource::<super::endless_client::EndlessClient>();
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
