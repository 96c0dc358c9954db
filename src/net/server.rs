//! The server's side: it owns the world, takes edits from clients as requests, checks them, applies them in one
//! order and sends each applied edit to every client with its number. A joining client gets the world as it is
//! (after edit number `seq`) in pieces, then every edit after it. Spawned objects and materials clients bring ride
//! in the same numbered order. The server keeps the time of day, the objects' clock and every player's undo
//! history, and saves the world as the game does. It has no log subscriber (a headless app): what its operator
//! should see (joins, leaves, names, saves) is printed to its console.

use super::console::{BanList, ConsoleCommand, same_name};
use super::materials::{Taken, take_materials};
use super::protocol::*;
use super::snapshot;
use crate::world::events::{ApplyEdits, EditApplied};
use crate::world::format::save_with_backup;
use crate::world::objects::{MAX_SAVED_OBJECTS, SavedObject};
use crate::world::{Edit, VoxelWorld};
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task};
use bevy_replicon::prelude::*;
use bevy_replicon::shared::backend::connected_client::NetworkId;
use bevy_replicon_renet::netcode::NetcodeServerTransport;
use std::net::IpAddr;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Duration;

/// What the server allows a client.
#[derive(Resource, Clone, Debug)]
pub struct ServerRules {
    /// The largest box (voxels) one edit may touch: a 64-voxel cube, the player's reach.
    pub max_box_voxels: u64,
    /// Edits a client may make per second on average, and in one burst.
    pub edits_per_second: f32,
    pub edit_burst: f32,
    /// World pieces sent to one joining client per tick (each up to `snapshot::PIECE_BYTES`).
    pub pieces_per_tick: usize,
    /// Where and how often the world is saved (also on request and on exit); `None` keeps it in memory only.
    pub save_path: Option<PathBuf>,
    pub save_every: Duration,
    /// Materials one connection may add to the palette, and the most ids the palette may reach.
    pub materials_per_player: usize,
    pub max_material_ids: usize,
    /// What one spawn costs of a client's edit allowance (a spawn is a larger change than a block).
    pub spawn_cost: f32,
}

impl Default for ServerRules {
    fn default() -> Self {
        ServerRules {
            max_box_voxels: 64 * 64 * 64,
            edits_per_second: 30.0,
            edit_burst: 120.0,
            pieces_per_tick: 4,
            save_path: None,
            save_every: Duration::from_secs(60),
            materials_per_player: 32,
            max_material_ids: 4096,
            spawn_cost: 10.0,
        }
    }
}

/// What the server has done, for its log, the tests and the bench.
#[derive(Resource, Clone, Debug, Default)]
pub struct ServerStats {
    /// Number of the last applied edit.
    pub seq: u64,
    pub refused: u64,
    pub joins: u64,
    pub world_bytes_sent: u64,
    pub saves: u64,
    pub last_save_error: Option<String>,
}

/// A connected, authorized client.
#[derive(Component, Clone, Debug)]
pub struct Peer {
    pub name: String,
    pub pose: Option<Pose>,
    /// Edits it may still make now (refilled at `edits_per_second` up to `edit_burst`).
    pub(crate) tokens: f32,
    /// Seconds until it may be told of another refusal (a flood gets one reply a second, not one per message).
    pub(crate) quiet: f32,
    /// Number of the last edit when it was authorized: the world it is sent is at least this recent.
    joined_at: u64,
    /// Whether its hello has arrived (its world is sent only then, so a banned name gets nothing).
    greeted: bool,
    /// Materials it has added to the palette.
    materials_added: usize,
}

/// How long the server remembers where a player who left was, so that returning under the same name puts them
/// back there.
pub const REMEMBER_LEFT: Duration = Duration::from_secs(10 * 60);

/// Most players remembered at once (the oldest are forgotten first).
const MAX_LEFT_PLAYERS: usize = 4096;

/// Where players who left were (by name, without regard to case), and when they left (server seconds).
#[derive(Resource, Clone, Debug, Default)]
pub struct LeftPlayers(pub Vec<(String, Pose, f64)>);

/// Voxels of undo history the server keeps for one player (2 bytes each: 4 MiB), and for everyone together.
pub const HISTORY_VOXELS_PER_PLAYER: usize = 1 << 21;
pub const HISTORY_VOXELS: usize = 1 << 25;

/// Every player's undo and redo stacks, by name without regard to case: kept while they play and for
/// `REMEMBER_LEFT` after they leave, so a player who reconnects (or restarts the game) can still undo.
#[derive(Resource, Default)]
pub struct Histories {
    players: std::collections::HashMap<String, PlayerHistory>,
    voxels: usize,
}

struct PlayerHistory {
    stacks: crate::world::history::EditHistory,
    /// When the player left (server seconds); `None` while playing.
    left: Option<f64>,
}

impl Histories {
    /// `name`'s stacks, made empty on first use.
    fn of(&mut self, name: &str) -> &mut PlayerHistory {
        self.players.entry(name.to_lowercase()).or_insert_with(|| PlayerHistory {
            stacks: crate::world::history::EditHistory::new(HISTORY_VOXELS_PER_PLAYER),
            left: None,
        })
    }

    /// Undo batches `name` has on the server.
    pub fn undo_len(&self, name: &str) -> usize {
        self.players.get(&name.to_lowercase()).map_or(0, |p| p.stacks.undo_len())
    }

    pub(crate) fn record(&mut self, name: &str, edit: Edit, before: Arc<[crate::world::Voxel]>) {
        let (min, max) = edit.bounds();
        let stacks = &mut self.of(name).stacks;
        let held = stacks.voxels();
        stacks.record(edit, min, max, before);
        let now = stacks.voxels();
        self.voxels = self.voxels + now - held;
        self.make_room();
    }

    /// Takes back or applies again `name`'s latest batch: the edit to apply.
    pub(crate) fn step(&mut self, name: &str, redo: bool) -> Option<Edit> {
        let stacks = &mut self.players.get_mut(&name.to_lowercase())?.stacks;
        let held = stacks.voxels();
        let edit = if redo { stacks.redo() } else { stacks.undo() };
        let now = stacks.voxels();
        self.voxels = self.voxels + now - held;
        self.make_room();
        edit
    }

    /// Over the server's budget, the oldest batches go: those of players who left first (longest gone first),
    /// then those of the largest history.
    fn make_room(&mut self) {
        while self.voxels > HISTORY_VOXELS {
            let victim = self
                .players
                .iter()
                .filter(|(_, p)| p.stacks.undo_len() > 0)
                .max_by(|a, b| {
                    let key = |p: &PlayerHistory| (p.left.map(|t| -t), p.stacks.voxels());
                    key(a.1).partial_cmp(&key(b.1)).unwrap_or(std::cmp::Ordering::Equal)
                })
                .map(|(name, _)| name.clone());
            let Some(stacks) = victim.and_then(|name| self.players.get_mut(&name)).map(|p| &mut p.stacks) else {
                return;
            };
            let held = stacks.voxels();
            stacks.forget_oldest();
            self.voxels -= held - stacks.voxels();
        }
    }

    fn left(&mut self, name: &str, now: f64) {
        if let Some(player) = self.players.get_mut(&name.to_lowercase()) {
            player.left = Some(now);
        }
        let expired: Vec<String> = (self.players.iter())
            .filter(|(_, p)| p.left.is_some_and(|t| now - t > REMEMBER_LEFT.as_secs_f64()))
            .map(|(name, _)| name.clone())
            .collect();
        for name in expired {
            if let Some(player) = self.players.remove(&name) {
                self.voxels -= player.stacks.voxels();
            }
        }
    }

    fn back(&mut self, name: &str) {
        if let Some(player) = self.players.get_mut(&name.to_lowercase()) {
            player.left = None;
        }
    }
}

/// Who may not play here, and where that list is kept (`None`: in memory only).
#[derive(Resource, Clone, Debug, Default)]
pub struct Bans {
    pub list: BanList,
    pub path: Option<PathBuf>,
}

/// The world on its way to a client.
#[derive(Component)]
struct Sending {
    seq: u64,
    clock: f64,
    pieces: Arc<Vec<Vec<u8>>>,
    next: usize,
}

/// A client waiting for the world. It hears every edit after number `since` (it was authorized then), so any
/// world as of `since` or later will do: it applies the edits after the world's own number.
#[derive(Component)]
pub(crate) struct WantsWorld {
    since: u64,
}

/// A world encoded as of edit `seq` and object clock `clock`.
struct Encoded {
    seq: u64,
    clock: f64,
    pieces: Arc<Vec<Vec<u8>>>,
}

/// The last world encoded, reused while it is recent enough for every client waiting.
#[derive(Resource, Default)]
struct EncodedWorld(Option<Encoded>);

/// A world being encoded off the server's tick (the default world's 32 MB of RON take about a second), as of
/// edit number `seq` and object clock `clock`.
#[derive(Resource, Default)]
struct Encoding(Option<(u64, f64, Task<Vec<Vec<u8>>>)>);

/// Asks the server to save now (the console's `save`, and exit).
#[derive(Message, Clone, Copy, Debug)]
pub struct SaveNow;

/// The time of day, in hours.
#[derive(Resource, Clone, Copy, Debug)]
pub struct WorldClock(pub f32);

/// The objects' clock: seconds the server has run them. Every object's age grows with it, and clients place
/// objects by it (`ServerTime`), whatever their frame rate.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct ObjectClockSeconds(pub f64);

/// When each of the world's objects was born on the object clock (same order as `VoxelWorld::objects`; the
/// server only appends to both). Ages are worked out from these in f64: an f32 age summed a tick at a time stops
/// growing after some days of uptime.
#[derive(Resource, Clone, Debug, Default)]
pub struct ObjectBirths(pub Vec<f64>);

pub struct NetServerPlugin;

impl Plugin for NetServerPlugin {
    fn build(&self, app: &mut App) {
        let world = app.world().get_resource::<VoxelWorld>();
        let hours = world.and_then(|w| w.time_of_day).unwrap_or(12.0);
        let births = world
            .and_then(|w| w.objects.as_ref())
            .map_or_else(Vec::new, |objects| objects.iter().map(|o| -(o.age as f64)).collect());
        app.init_resource::<ServerRules>()
            .init_resource::<ServerStats>()
            .init_resource::<Bans>()
            .init_resource::<Histories>()
            .init_resource::<LeftPlayers>()
            .init_resource::<EncodedWorld>()
            .init_resource::<Encoding>()
            .init_resource::<Saving>()
            .insert_resource(WorldClock(hours))
            .init_resource::<ObjectClockSeconds>()
            .insert_resource(ObjectBirths(births))
            .add_message::<SaveNow>()
            .add_observer(welcome)
            .add_observer(farewell)
            .add_systems(
                Update,
                (
                    (refill_tokens, take_hellos, take_poses, take_clock_asks),
                    // A bounded world's; an endless world's server has its own (`endless_server`).
                    (apply_edit_asks, apply_history_asks, apply_spawn_asks)
                        .chain()
                        .in_set(ApplyEdits)
                        .run_if(resource_exists::<VoxelWorld>),
                    (
                        (advance_objects, start_sending_world, send_world_pieces)
                            .chain()
                            .run_if(resource_exists::<VoxelWorld>),
                        send_players,
                        send_server_time,
                        save_on_schedule.run_if(resource_exists::<VoxelWorld>),
                    )
                        .chain(),
                )
                    .chain()
                    .in_set(NetServerSystems),
            );
    }
}

/// Every system of `NetServerPlugin`: an endless world's server runs its own after them.
#[derive(SystemSet, Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct NetServerSystems;

pub fn player_id(client: ClientId) -> u64 {
    client.entity().map_or(0, Entity::to_bits)
}

/// The address a client plays from, where the transport knows it (in-process test clients have none).
fn address_of(id: Option<&NetworkId>, transport: Option<&NetcodeServerTransport>) -> Option<IpAddr> {
    Some(transport?.client_addr(id?.get())?.ip())
}

/// `address_of` a client of `world`.
pub fn client_address(world: &World, client: Entity) -> Option<IpAddr> {
    address_of(world.get::<NetworkId>(client), world.get_resource::<NetcodeServerTransport>())
}

fn welcome(
    add: On<Add, AuthorizedClient>,
    mut commands: Commands,
    rules: Res<ServerRules>,
    mut stats: ResMut<ServerStats>,
) {
    stats.joins += 1;
    let name = format!("player {}", stats.joins);
    println!("{name} joined");
    let peer = Peer {
        name,
        pose: None,
        tokens: rules.edit_burst,
        quiet: 0.0,
        joined_at: stats.seq,
        greeted: false,
        materials_added: 0,
    };
    commands.entity(add.entity).insert(peer);
}

/// Tells one client why, then disconnects it (after the notice has left).
pub fn send_away(world: &mut World, client: Entity, why: &str) {
    world.write_message(ToClients {
        targets: SendTargets::Single(client.into()),
        message: Notice { text: why.into(), farewell: true },
    });
    world.write_message(DisconnectRequest { client });
}

fn farewell(
    remove: On<Remove, Peer>,
    peers: Query<&Peer>,
    time: Res<Time>,
    mut left: ResMut<LeftPlayers>,
    mut histories: ResMut<Histories>,
) {
    let Ok(peer) = peers.get(remove.entity) else { return };
    println!("{} left", peer.name);
    let now = time.elapsed_secs_f64();
    histories.left(&peer.name, now);
    left.0.retain(|(name, _, when)| !same_name(name, &peer.name) && now - when < REMEMBER_LEFT.as_secs_f64());
    if let Some(pose) = peer.pose {
        left.0.push((peer.name.clone(), pose, now));
    }
    // A flood of short visits cannot grow it without bound.
    let excess = left.0.len().saturating_sub(MAX_LEFT_PLAYERS);
    left.0.drain(..excess);
}

fn refill_tokens(time: Res<Time>, rules: Res<ServerRules>, mut peers: Query<&mut Peer>) {
    let dt = time.delta_secs();
    for mut peer in &mut peers {
        peer.tokens = (peer.tokens + dt * rules.edits_per_second).min(rules.edit_burst);
        peer.quiet = (peer.quiet - dt).max(0.0);
    }
}

/// Most characters of a player's name.
pub const MAX_NAME_CHARS: usize = 24;

/// A name as others see it: printable, trimmed, at most `MAX_NAME_CHARS`; `None` when nothing is left.
pub fn clean_name(name: &str) -> Option<String> {
    let clean: String = name.chars().filter(|c| !c.is_control()).take(MAX_NAME_CHARS).collect();
    let clean = clean.trim().to_string();
    (!clean.is_empty()).then_some(clean)
}

/// A client's hello names it; the first one also checks the ban list and starts sending it the world.
#[allow(clippy::too_many_arguments)]
fn take_hellos(
    mut commands: Commands,
    mut hellos: MessageReader<FromClient<Hello>>,
    mut peers: Query<(&mut Peer, Option<&NetworkId>)>,
    bans: Res<Bans>,
    transport: Option<Res<NetcodeServerTransport>>,
    (mut notices, mut welcome_back): (MessageWriter<ToClients<Notice>>, MessageWriter<ToClients<WelcomeBack>>),
    mut disconnects: MessageWriter<DisconnectRequest>,
    (time, mut left, mut histories): (Res<Time>, ResMut<LeftPlayers>, ResMut<Histories>),
) {
    for hello in hellos.read() {
        let Some(client) = hello.client_id.entity() else { continue };
        let Ok((mut peer, id)) = peers.get_mut(client) else { continue };
        if let Some(name) = clean_name(&hello.name).filter(|n| *n != peer.name) {
            println!("{} is called {name}", peer.name);
            peer.name = name;
        }
        if peer.greeted {
            continue;
        }
        peer.greeted = true;
        let now = time.elapsed_secs_f64();
        let back = left
            .0
            .iter()
            .rposition(|(name, _, when)| same_name(name, &peer.name) && now - when < REMEMBER_LEFT.as_secs_f64());
        if bans.list.refuses(Some(&peer.name), address_of(id, transport.as_deref())) {
            println!("{} is banned: sent away", peer.name);
            let text = "you are banned from this server".to_string();
            let message = Notice { text, farewell: true };
            notices.write(ToClients { targets: SendTargets::Single(hello.client_id), message });
            disconnects.write(DisconnectRequest { client });
        } else {
            histories.back(&peer.name);
            commands.entity(client).insert(WantsWorld { since: peer.joined_at });
            if let Some(i) = back {
                let (_, pose, _) = left.0.remove(i);
                println!("{} is back", peer.name);
                peer.pose = Some(pose);
                welcome_back
                    .write(ToClients { targets: SendTargets::Single(hello.client_id), message: WelcomeBack { pose } });
            }
        }
    }
}

fn take_poses(mut poses: MessageReader<FromClient<Pose>>, mut peers: Query<&mut Peer>) {
    for pose in poses.read() {
        let finite = pose.position.iter().all(|c| c.is_finite() && c.abs() < 1e7) && pose.yaw.is_finite();
        if let (true, Some(entity)) = (finite, pose.client_id.entity())
            && let Ok(mut peer) = peers.get_mut(entity)
        {
            peer.pose = Some(pose.message);
        }
    }
}

fn take_clock_asks(
    mut asks: MessageReader<FromClient<ClockAsk>>,
    mut clock: ResMut<WorldClock>,
    mut peers: Query<&mut Peer>,
    mut now: MessageWriter<ToClients<ClockNow>>,
) {
    for ask in asks.read() {
        let Some(mut peer) = ask.client_id.entity().and_then(|e| peers.get_mut(e).ok()) else { continue };
        if !(0.0..=24.0).contains(&ask.hours) || peer.tokens < 1.0 {
            continue;
        }
        peer.tokens -= 1.0;
        clock.0 = ask.hours % 24.0;
        now.write(ToClients { targets: SendTargets::CLIENTS_ONLY, message: ClockNow { hours: clock.0 } });
    }
}

/// Why the server will not apply `edit` for a client (before the world's own checks).
pub fn edit_problem(edit: &Edit, rules: &ServerRules) -> Option<String> {
    let (min, max) = edit.bounds();
    let extent = (max.as_i64vec3() - min.as_i64vec3() + 1).max(bevy::math::I64Vec3::ZERO);
    let volume = (extent.x as u64).saturating_mul(extent.y as u64).saturating_mul(extent.z as u64);
    (volume > rules.max_box_voxels)
        .then(|| format!("a box of {volume} voxels is larger than the server allows ({})", rules.max_box_voxels))
}

#[allow(clippy::too_many_arguments)]
fn apply_edit_asks(
    mut asks: MessageReader<FromClient<EditAsk>>,
    mut world: ResMut<VoxelWorld>,
    rules: Res<ServerRules>,
    mut stats: ResMut<ServerStats>,
    mut peers: Query<&mut Peer>,
    mut applied: MessageWriter<EditApplied>,
    mut done: MessageWriter<ToClients<EditDone>>,
    mut refused: MessageWriter<ToClients<Refused>>,
    mut histories: ResMut<Histories>,
) {
    for ask in asks.read() {
        let Some(mut peer) = ask.client_id.entity().and_then(|e| peers.get_mut(e).ok()) else { continue };
        let problem = if peer.tokens < 1.0 {
            Some(format!("too many edits: the server takes {} a second", rules.edits_per_second))
        } else {
            peer.tokens -= 1.0;
            edit_problem(&Edit::from(&ask.edit), &rules)
        };
        let result = match problem {
            Some(problem) => Err(problem),
            None => apply_with_materials(&mut world, ask, &rules, peer.materials_added),
        };
        match result {
            Ok(None) => {}
            Ok(Some((taken, edit, changed, before))) => {
                stats.seq += 1;
                peer.materials_added += taken.added.len();
                if let Some(before) = before {
                    histories.record(&peer.name, edit.clone(), before);
                }
                let (min, max) = edit.bounds();
                applied.write(EditApplied { edit, min, max, changed, before: None });
                let message = EditDone {
                    seq: stats.seq,
                    by: player_id(ask.client_id),
                    undoable: ask.undoable,
                    materials: taken.added,
                    change: Change::Edit(taken.edit),
                };
                done.write(ToClients { targets: SendTargets::CLIENTS_ONLY, message });
            }
            Err(reason) => refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused),
        }
    }
}

/// Tells a client why its request was refused, at most once a second.
pub(crate) fn refuse(
    stats: &mut ServerStats,
    peer: &mut Peer,
    client: ClientId,
    reason: String,
    refused: &mut MessageWriter<ToClients<Refused>>,
) {
    stats.refused += 1;
    if peer.quiet <= 0.0 {
        peer.quiet = 1.0;
        refused.write(ToClients { targets: SendTargets::Single(client), message: Refused { reason } });
    }
}

/// Adds the materials an ask brings (`net::materials`), then applies its edit; a refused edit takes its new
/// materials back out of the palette, so no client is told of materials that are not the server's. `None`: the
/// edit changed nothing. An undoable edit also hands back what its box held before.
#[allow(clippy::type_complexity)]
fn apply_with_materials(
    world: &mut VoxelWorld,
    ask: &EditAsk,
    rules: &ServerRules,
    added_before: usize,
) -> Result<Option<(Taken, Edit, u64, Option<Arc<[crate::world::Voxel]>>)>, String> {
    let palette_before = world.palette.materials.len();
    let allowance = rules.materials_per_player.saturating_sub(added_before);
    let taken = take_materials(
        &mut world.palette,
        ask.edit.clone(),
        ask.first_new,
        &ask.materials,
        allowance,
        rules.max_material_ids,
    )?;
    let edit = Edit::from(&taken.edit);
    let (min, max) = edit.bounds();
    let before = (ask.undoable && world.grid.contains(min) && world.grid.contains(max))
        .then(|| Arc::from(world.grid.read_box(min, max + IVec3::ONE)));
    match world.apply(edit.clone()) {
        Ok(0) => {
            world.palette.materials.truncate(palette_before);
            Ok(None)
        }
        Ok(changed) => Ok(Some((taken, edit, changed, before))),
        Err(e) => {
            world.palette.materials.truncate(palette_before);
            Err(e.to_string())
        }
    }
}

/// Undoes or redoes the asking player's latest batch (the server's stacks for that name).
#[allow(clippy::too_many_arguments)]
fn apply_history_asks(
    mut asks: MessageReader<FromClient<HistoryAsk>>,
    mut world: ResMut<VoxelWorld>,
    mut stats: ResMut<ServerStats>,
    mut peers: Query<&mut Peer>,
    mut histories: ResMut<Histories>,
    mut applied: MessageWriter<EditApplied>,
    mut done: MessageWriter<ToClients<EditDone>>,
    mut refused: MessageWriter<ToClients<Refused>>,
) {
    for ask in asks.read() {
        let Some(mut peer) = ask.client_id.entity().and_then(|e| peers.get_mut(e).ok()) else { continue };
        if peer.tokens < 1.0 {
            let reason = "too many edits: wait a moment".to_string();
            refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused);
            continue;
        }
        peer.tokens -= 1.0;
        let Some(edit) = histories.step(&peer.name, ask.redo) else {
            let reason = format!("nothing to {}", if ask.redo { "redo" } else { "undo" });
            refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused);
            continue;
        };
        match world.apply(edit.clone()) {
            Ok(0) => {}
            Ok(changed) => {
                stats.seq += 1;
                let (min, max) = edit.bounds();
                let change = Change::Edit(NetEdit::from(&edit));
                applied.write(EditApplied { edit, min, max, changed, before: None });
                let message = EditDone {
                    seq: stats.seq,
                    by: player_id(ask.client_id),
                    undoable: false,
                    materials: vec![],
                    change,
                };
                done.write(ToClients { targets: SendTargets::CLIENTS_ONLY, message });
            }
            Err(e) => refuse(&mut stats, &mut peer, ask.client_id, e.to_string(), &mut refused),
        }
    }
}

/// Spawns the objects clients ask for, in the edits' numbered order, with the models' materials the palette
/// lacks added first (as the game does for its own lanterns).
#[allow(clippy::too_many_arguments)]
fn apply_spawn_asks(
    mut asks: MessageReader<FromClient<SpawnAsk>>,
    mut world: ResMut<VoxelWorld>,
    rules: Res<ServerRules>,
    (clock, mut births): (Res<ObjectClockSeconds>, ResMut<ObjectBirths>),
    mut stats: ResMut<ServerStats>,
    mut peers: Query<&mut Peer>,
    mut done: MessageWriter<ToClients<EditDone>>,
    mut refused: MessageWriter<ToClients<Refused>>,
) {
    for ask in asks.read() {
        let Some(mut peer) = ask.client_id.entity().and_then(|e| peers.get_mut(e).ok()) else { continue };
        let object = SavedObject { age: 0.0, ..ask.object.clone() };
        let count = world.objects.as_ref().map_or(0, Vec::len);
        let problem = if peer.tokens < rules.spawn_cost {
            Some("too many spawns: wait a moment".to_string())
        } else if count >= MAX_SAVED_OBJECTS {
            Some(format!("this world holds {MAX_SAVED_OBJECTS} moving objects, the most the renderer draws"))
        } else {
            let size = world.grid.size().as_vec3();
            let inside =
                Vec3::from(object.anchor).cmpge(Vec3::ZERO).all() && Vec3::from(object.anchor).cmplt(size).all();
            object.check(size).err().or((!inside).then(|| "a spawn must be centred inside the world".to_string()))
        };
        if let Some(reason) = problem {
            refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused);
            continue;
        }
        peer.tokens -= rules.spawn_cost;
        let palette_before = world.palette.materials.len();
        if let Err(reason) = crate::dynamic::model_for_palette(&object.model, &mut world.palette) {
            world.palette.materials.truncate(palette_before);
            refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused);
            continue;
        }
        let materials = world.palette.materials[palette_before..].iter().map(NetMaterial::from).collect();
        world.objects.get_or_insert_with(Vec::new).push(object.clone());
        births.0.push(clock.0);
        stats.seq += 1;
        let message = EditDone {
            seq: stats.seq,
            by: player_id(ask.client_id),
            undoable: false,
            materials,
            change: Change::Spawn { object, born: clock.0 },
        };
        done.write(ToClients { targets: SendTargets::CLIENTS_ONLY, message });
    }
}

/// A copy of the world with the clock and the objects as they are now, for encoding off the tick (what a joining
/// client gets).
pub fn world_now(world: &VoxelWorld, clock: &WorldClock) -> VoxelWorld {
    let mut now = world.clone();
    now.time_of_day = Some(clock.0);
    now
}

/// Hands waiting clients the last encoded world when it is recent enough for them; otherwise encodes the world
/// as it is now on the async compute pool while the server ticks on.
fn start_sending_world(
    mut commands: Commands,
    waiting: Query<(Entity, &WantsWorld)>,
    world: Res<VoxelWorld>,
    (clock, objects_clock): (Res<WorldClock>, Res<ObjectClockSeconds>),
    stats: Res<ServerStats>,
    mut encoded: ResMut<EncodedWorld>,
    mut encoding: ResMut<Encoding>,
) {
    if let Some((seq, clock, task)) = &mut encoding.0
        && let Some(pieces) = bevy::tasks::futures::check_ready(task)
    {
        encoded.0 = Some(Encoded { seq: *seq, clock: *clock, pieces: Arc::new(pieces) });
        encoding.0 = None;
        crate::alloc_watch::return_freed_memory();
    }
    let mut stale = false;
    for (client, wants) in &waiting {
        match &encoded.0 {
            Some(world) if world.seq >= wants.since => {
                let sending = Sending { seq: world.seq, clock: world.clock, pieces: world.pieces.clone(), next: 0 };
                commands.entity(client).remove::<WantsWorld>().insert(sending);
            }
            _ => stale = true,
        }
    }
    if stale && encoding.0.is_none() {
        let now = world_now(&world, &clock);
        let task = AsyncComputeTaskPool::get().spawn(async move { snapshot::encode(&now) });
        encoding.0 = Some((stats.seq, objects_clock.0, task));
    }
}

fn send_world_pieces(
    mut commands: Commands,
    mut sending: Query<(Entity, &mut Sending)>,
    rules: Res<ServerRules>,
    mut stats: ResMut<ServerStats>,
    mut out: MessageWriter<ToClients<WorldPiece>>,
) {
    for (client, mut send) in &mut sending {
        let count = send.pieces.len() as u32;
        for _ in 0..rules.pieces_per_tick {
            let Some(bytes) = send.pieces.get(send.next).cloned() else { break };
            stats.world_bytes_sent += bytes.len() as u64;
            let message = WorldPiece {
                seq: send.seq,
                clock: send.clock,
                player: client.to_bits(),
                index: send.next as u32,
                count,
                bytes,
            };
            out.write(ToClients { targets: SendTargets::Single(client.into()), message });
            send.next += 1;
        }
        if send.next >= send.pieces.len() {
            commands.entity(client).remove::<Sending>();
        }
    }
}

/// Carries out a console command that acts on the players (`list`, `kick`, `ban`, `unban`, `say`) and says what
/// happened, for the console. `save` and `quit` are the caller's.
pub fn run_console_command(world: &mut World, command: &ConsoleCommand) -> String {
    let players: Vec<(Entity, String, Option<Pose>)> = world
        .query::<(Entity, &Peer)>()
        .iter(world)
        .map(|(entity, peer)| (entity, peer.name.clone(), peer.pose))
        .collect();
    let named = |name: &str| players.iter().filter(|p| same_name(&p.1, name)).map(|p| p.0).collect::<Vec<_>>();
    match command {
        ConsoleCommand::List => {
            let mut lines = vec![format!("{} playing", players.len())];
            for (entity, name, pose) in &players {
                let at = pose.map_or("not seen yet".to_string(), |p| {
                    format!("at {:.0}, {:.0}, {:.0}", p.position[0], p.position[1], p.position[2])
                });
                let from = client_address(world, *entity).map_or(String::new(), |a| format!(" from {a}"));
                lines.push(format!("  {name}: {at}{from}"));
            }
            lines.join(
                "
",
            )
        }
        ConsoleCommand::Kick(name) => {
            let found = named(name);
            for &client in &found {
                send_away(world, client, "the server's operator sent you away (you may join again)");
            }
            match found.len() {
                0 => format!("nobody called '{name}' is playing"),
                _ => format!("kicked {name}"),
            }
        }
        ConsoleCommand::Ban(name) => {
            let found = named(name);
            let addresses: Vec<Option<IpAddr>> = found.iter().map(|&c| client_address(world, c)).collect();
            let mut bans = world.resource_mut::<Bans>();
            if addresses.is_empty() {
                bans.list.add(name, None);
            }
            for address in addresses {
                bans.list.add(name, address);
            }
            let saved = match &bans.path {
                Some(path) => bans.list.save(path).map(|()| format!(" (kept in {})", path.display())),
                None => Ok(String::new()),
            };
            for &client in &found {
                send_away(world, client, "you are banned from this server");
            }
            match saved {
                Ok(kept) if found.is_empty() => format!("banned the name {name}, not playing now{kept}"),
                Ok(kept) => format!("banned {name} and sent them away{kept}"),
                Err(e) => format!("banned {name} until the server stops: {e}"),
            }
        }
        ConsoleCommand::Unban(name) => {
            let mut bans = world.resource_mut::<Bans>();
            if !bans.list.remove(name) {
                return format!("'{name}' is not banned");
            }
            match &bans.path {
                Some(path) => match bans.list.save(path) {
                    Ok(()) => format!("{name} may join again"),
                    Err(e) => format!("{name} may join again until the server stops: {e}"),
                },
                None => format!("{name} may join again"),
            }
        }
        ConsoleCommand::Say(text) => {
            let text = format!("[server] {}", text.chars().filter(|c| !c.is_control()).take(200).collect::<String>());
            world.write_message(ToClients {
                targets: SendTargets::CLIENTS_ONLY,
                message: Notice { text: text.clone(), farewell: false },
            });
            text
        }
        ConsoleCommand::Save | ConsoleCommand::Quit | ConsoleCommand::Help | ConsoleCommand::Nothing => String::new(),
    }
}

/// How often everyone hears where everyone is.
const PLAYERS_EVERY: f32 = 0.2;

fn send_players(
    time: Res<Time>,
    mut since: Local<f32>,
    peers: Query<(Entity, &Peer)>,
    mut out: MessageWriter<ToClients<Players>>,
) {
    *since += time.delta_secs();
    if *since < PLAYERS_EVERY {
        return;
    }
    *since = 0.0;
    let mut players: Vec<PlayerInfo> = peers
        .iter()
        .map(|(entity, peer)| PlayerInfo { id: entity.to_bits(), name: peer.name.clone(), pose: peer.pose })
        .collect();
    players.sort_by_key(|p| p.id);
    out.write(ToClients { targets: SendTargets::CLIENTS_ONLY, message: Players { players } });
}

/// The objects' phases move on with the server's clock, so a joining client sees them where the others do.
fn advance_objects(
    time: Res<Time>,
    mut clock: ResMut<ObjectClockSeconds>,
    births: Res<ObjectBirths>,
    mut world: ResMut<VoxelWorld>,
) {
    clock.0 += time.delta_secs_f64();
    if let Some(objects) = world.bypass_change_detection().objects.as_mut() {
        for (object, born) in objects.iter_mut().zip(&births.0) {
            object.age = (clock.0 - born) as f32;
        }
    }
}

/// How often clients hear the object clock.
const SERVER_TIME_EVERY: f32 = 0.25;

fn send_server_time(
    time: Res<Time>,
    mut since: Local<f32>,
    clock: Res<ObjectClockSeconds>,
    mut out: MessageWriter<ToClients<ServerTime>>,
) {
    *since += time.delta_secs();
    if *since >= SERVER_TIME_EVERY {
        *since = 0.0;
        out.write(ToClients { targets: SendTargets::CLIENTS_ONLY, message: ServerTime { seconds: clock.0 } });
    }
}

/// A save being written off the server's tick (the default world's 32 MB of RON took most of a second of the
/// tick, in which no one's edit was applied: docs/bench/net/soak.md), as of edit number `seq`.
#[derive(Resource, Default)]
pub struct Saving(Option<(u64, Task<std::io::Result<()>>)>);

#[allow(clippy::too_many_arguments)]
fn save_on_schedule(
    time: Res<Time>,
    mut since: Local<f32>,
    mut asks: MessageReader<SaveNow>,
    rules: Res<ServerRules>,
    world: Res<VoxelWorld>,
    clock: Res<WorldClock>,
    mut stats: ResMut<ServerStats>,
    mut saving: ResMut<Saving>,
) {
    *since += time.delta_secs();
    let Some(path) = &rules.save_path else { return };
    if let Some((seq, task)) = &mut saving.0
        && let Some(result) = bevy::tasks::futures::check_ready(task)
    {
        report_save(&mut stats, path, *seq, result);
        saving.0 = None;
        crate::alloc_watch::return_freed_memory();
    }
    if asks.read().count() > 0 {
        *since = f32::INFINITY;
    }
    // Due, and the last one written: the world as it is now, copied on the tick, written off it.
    if *since < rules.save_every.as_secs_f32() || saving.0.is_some() {
        return;
    }
    *since = 0.0;
    let now = world_now(&world, &clock);
    let to = path.clone();
    let task = AsyncComputeTaskPool::get().spawn(async move { save_with_backup(&now, &to) });
    saving.0 = Some((stats.seq, task));
}

fn report_save(stats: &mut ServerStats, path: &std::path::Path, seq: u64, result: std::io::Result<()>) {
    match result {
        Ok(()) => {
            stats.saves += 1;
            stats.last_save_error = None;
            println!("saved {} (after edit {seq})", path.display());
        }
        Err(e) => {
            eprintln!("could not save {}: {e}", path.display());
            stats.last_save_error = Some(e.to_string());
        }
    }
}

/// Waits for a save still being written (before the server writes its last one to the same file).
pub fn finish_saving(world: &mut World) {
    let Some((seq, task)) = world.resource_mut::<Saving>().0.take() else { return };
    let result = bevy::tasks::block_on(task);
    if let Some(path) = world.resource::<ServerRules>().save_path.clone() {
        report_save(&mut world.resource_mut::<ServerStats>(), &path, seq, result);
    }
}
