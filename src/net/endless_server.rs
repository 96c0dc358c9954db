//! The server of an endless world (`glowbrick serve --endless`). Clients make the regions nobody changed
//! themselves, from the seed; the server holds what only it can: the regions around every player (so their edits
//! apply at once) and every region a player changed, which it hands to a client that asks for it. Each client
//! tells the server which regions it holds (`RegionAsk`, `RegionLetGo`) and hears only the edits that touch them,
//! so two players kilometres apart cost each other nothing. Edits travel in world coordinates, numbered in one
//! order as in a bounded world, and undo stays the server's. Changed regions are saved into the world's folder
//! (`world::region_save`) on a schedule, off the tick.

use super::protocol::*;
use super::server::{
    Histories, Peer, SaveNow, ServerRules, ServerStats, WantsWorld, WorldClock, edit_problem, player_id, refuse,
};
use super::snapshot;
use crate::world::generate::endless::{EndlessGenerator, REGION_EDGE};
use crate::world::region_save::EndlessSave;
use crate::world::{Edit, Voxel, VoxelWorld};
use bevy::prelude::*;
use bevy::tasks::{AsyncComputeTaskPool, Task};
use bevy_replicon::prelude::*;
use std::collections::{HashMap, HashSet, VecDeque};
use std::sync::Arc;

/// Regions each side of a player's that the server keeps made, so edits within reach apply at once.
pub const PLAYER_REGIONS: i32 = 1;
/// Most regions one client may hold at once (a window of 16 x 16 regions streams about 23 x 23).
pub const MAX_HELD_REGIONS: usize = 2048;
/// Region keys a client may name: a region's voxels stay within i32.
const MAX_KEY: i32 = i32::MAX / REGION_EDGE / 2;

/// A region's deflated world file, in pieces.
type Pieces = Arc<Vec<Vec<u8>>>;

/// The endless world as its server holds it.
#[derive(Resource)]
pub struct EndlessWorld {
    generator: Arc<EndlessGenerator>,
    /// Where changed regions are saved; `None` keeps them in memory.
    save: Option<EndlessSave>,
    /// Regions in memory, each with the number of the last edit that changed it (0: as made).
    regions: HashMap<IVec2, (VoxelWorld, u64)>,
    making: HashMap<IVec2, Task<VoxelWorld>>,
    /// Every region a player ever changed (in memory or in the save folder).
    changed: HashSet<IVec2>,
    /// Changed since the last save.
    unsaved: HashSet<IVec2>,
    /// The last reply made of a changed region, and the number of its last edit then.
    encoded: HashMap<IVec2, (u64, Pieces)>,
}

impl EndlessWorld {
    /// The endless world of `seed`, `height` voxels high; regions saved into `save`'s folder, when there is one.
    pub fn new(seed: u32, height: u32, save: Option<EndlessSave>) -> Result<Self, String> {
        let generator = Arc::new(EndlessGenerator::new(seed, height)?);
        let changed = save.as_ref().map_or_else(HashSet::new, |s| s.saved_regions().into_iter().collect());
        Ok(EndlessWorld {
            generator,
            save,
            regions: HashMap::new(),
            making: HashMap::new(),
            changed,
            unsaved: HashSet::new(),
            encoded: HashMap::new(),
        })
    }

    pub fn seed(&self) -> u32 {
        self.generator.seed()
    }

    pub fn height(&self) -> u32 {
        self.generator.height()
    }

    /// Regions in memory, and regions a player changed.
    pub fn counts(&self) -> (usize, usize) {
        (self.regions.len(), self.changed.len())
    }

    /// Region `key` as the server holds it, where it is in memory.
    pub fn region(&self, key: IVec2) -> Option<&VoxelWorld> {
        self.regions.get(&key).map(|(region, _)| region)
    }

    /// Region `key` from the save folder where it holds one (a file that cannot be read is reported and the
    /// generator's region used), else from the generator.
    fn make(generator: &EndlessGenerator, save: Option<&EndlessSave>, key: IVec2) -> VoxelWorld {
        match save.map(|s| s.load_region(key, generator.palette())) {
            Some(Ok(Some(region))) => region,
            Some(Err(e)) => {
                eprintln!("{e}; the generator's region {key} is served instead");
                generator.region(key)
            }
            _ => generator.region(key),
        }
    }

    /// Starts making region `key` off the tick, unless it is in memory or on its way.
    fn want(&mut self, key: IVec2) {
        if self.regions.contains_key(&key) || self.making.contains_key(&key) {
            return;
        }
        let (generator, save) = (self.generator.clone(), self.save.clone());
        let task = AsyncComputeTaskPool::get().spawn(async move { Self::make(&generator, save.as_ref(), key) });
        self.making.insert(key, task);
    }

    /// Takes the regions made since the last call.
    fn take_made(&mut self) {
        let done: Vec<IVec2> = (self.making.iter_mut())
            .filter_map(|(key, task)| bevy::tasks::futures::check_ready(task).map(|region| (*key, region)))
            .map(|(key, region)| {
                self.regions.insert(key, (region, 0));
                key
            })
            .collect();
        for key in done {
            self.making.remove(&key);
        }
    }

    /// Region `key` now: made on the tick where it is not in memory (a changed region a client asks for).
    fn region_now(&mut self, key: IVec2) -> &VoxelWorld {
        if !self.regions.contains_key(&key) {
            let region = Self::make(&self.generator, self.save.as_ref(), key);
            self.making.remove(&key);
            self.regions.insert(key, (region, 0));
        }
        &self.regions[&key].0
    }

    /// The deflated pieces of changed region `key` as it is now.
    fn encoded(&mut self, key: IVec2) -> Pieces {
        let version = self.regions.get(&key).map(|(_, v)| *v);
        if let (Some(version), Some((at, pieces))) = (version, self.encoded.get(&key))
            && *at == version
        {
            return pieces.clone();
        }
        let pieces = Arc::new(snapshot::encode(self.region_now(key)));
        let version = self.regions[&key].1;
        self.encoded.insert(key, (version, pieces.clone()));
        pieces
    }

    /// Keeps the regions within `PLAYER_REGIONS` of every player made, and lets go of those no player is near
    /// that hold nothing unsaved (without a save folder, a changed region stays in memory: it is the only copy).
    fn follow_players(&mut self, players: &[IVec2]) {
        self.take_made();
        for &centre in players {
            for z in -PLAYER_REGIONS..=PLAYER_REGIONS {
                for x in -PLAYER_REGIONS..=PLAYER_REGIONS {
                    self.want(centre + IVec2::new(x, z));
                }
            }
        }
        let near = |key: IVec2| players.iter().any(|p| (key - *p).abs().max_element() <= PLAYER_REGIONS + 1);
        let (unsaved, changed, saving) = (&self.unsaved, &self.changed, self.save.is_some());
        self.regions.retain(|key, _| near(*key) || unsaved.contains(key) || (!saving && changed.contains(key)));
        self.encoded.retain(|key, _| self.regions.contains_key(key));
    }

    /// The region keys the box `min..=max` spans.
    fn keys_of(min: IVec3, max: IVec3) -> Vec<IVec2> {
        let a = EndlessGenerator::region_of(min.x, min.z);
        let b = EndlessGenerator::region_of(max.x, max.z);
        (a.y..=b.y).flat_map(|z| (a.x..=b.x).map(move |x| IVec2::new(x, z))).collect()
    }

    /// Why `edit` (world coordinates) cannot be applied now: out of the world's height, a material this world
    /// lacks, or a region still being made (asked for, so a moment later it can).
    fn problem(&mut self, edit: &Edit) -> Option<String> {
        let (min, max) = edit.bounds();
        let height = self.generator.height() as i32;
        if min.y < 0 || max.y >= height {
            return Some(format!("edit refused: y {}..{} is outside the world's 0..{height}", min.y, max.y));
        }
        let reach = MAX_KEY * REGION_EDGE;
        if min.x.min(min.z) < -reach || max.x.max(max.z) >= reach {
            return Some("edit refused: past the world's end".into());
        }
        let ids = self.generator.palette().id_count();
        let bad = match edit {
            Edit::Place { material, .. } | Edit::FillBox { material, .. } => {
                (*material as usize >= ids).then_some(*material)
            }
            Edit::Restore { voxels, .. } => voxels.iter().copied().find(|&v| v as usize >= ids),
            Edit::Break { .. } => None,
        };
        if let Some(id) = bad {
            return Some(format!("edit refused: material id {id} is not in the endless world's palette"));
        }
        if let Edit::Restore { voxels, .. } = edit {
            let extent = (max - min + IVec3::ONE).as_uvec3();
            if voxels.len() as u64 != extent.x as u64 * extent.y as u64 * extent.z as u64 {
                return Some("edit refused: a restore's voxels do not fill its box".into());
            }
        }
        let missing: Vec<IVec2> =
            Self::keys_of(min, max).into_iter().filter(|k| !self.regions.contains_key(k)).collect();
        if missing.is_empty() {
            return None;
        }
        missing.into_iter().for_each(|key| self.want(key));
        Some("that place is still being made on the server: try again in a moment".into())
    }

    /// The voxels of the box `min..=max` (x fastest, then y, then z), every region of it in memory.
    fn read_box(&self, min: IVec3, max: IVec3) -> Arc<[Voxel]> {
        let mut voxels = Vec::new();
        for z in min.z..=max.z {
            for y in min.y..=max.y {
                for x in min.x..=max.x {
                    let key = EndlessGenerator::region_of(x, z);
                    let local = IVec3::new(x - key.x * REGION_EDGE, y, z - key.y * REGION_EDGE);
                    voxels.push(self.regions.get(&key).map_or(0, |(region, _)| region.grid.get(local)));
                }
            }
        }
        Arc::from(voxels)
    }

    /// Applies `edit` (world coordinates) to every region it spans, as edit number `seq`; how many voxels changed
    /// and the regions it changed. `problem` found nothing wrong with it first, so no part is refused.
    fn apply(&mut self, edit: &Edit, seq: u64) -> (u64, Vec<IVec2>) {
        let (min, max) = edit.bounds();
        let mut changed = 0;
        let mut touched = Vec::new();
        for key in Self::keys_of(min, max) {
            let corner = IVec3::new(key.x * REGION_EDGE, 0, key.y * REGION_EDGE);
            let size = IVec3::new(REGION_EDGE, self.generator.height() as i32, REGION_EDGE);
            let Some(part) = edit.clipped(corner, corner + size - IVec3::ONE) else { continue };
            let Some((region, version)) = self.regions.get_mut(&key) else { continue };
            let n = region.apply(part.moved(-corner)).unwrap_or_else(|e| {
                eprintln!("an edit checked beforehand was refused in region {key}: {e}");
                0
            });
            if n > 0 {
                changed += n;
                *version = seq;
                touched.push(key);
                self.changed.insert(key);
                self.unsaved.insert(key);
            }
        }
        (changed, touched)
    }

    /// Copies of the regions changed since the last save, with their versions.
    fn unsaved_copies(&self) -> Vec<(IVec2, u64, VoxelWorld)> {
        let mut keys: Vec<IVec2> = self.unsaved.iter().copied().collect();
        keys.sort_by_key(|k| (k.y, k.x));
        keys.into_iter()
            .filter_map(|key| self.regions.get(&key).map(|(region, version)| (key, *version, region.clone())))
            .collect()
    }

    /// Marks saved the regions written, unless they changed again since they were copied.
    fn saved(&mut self, written: &[(IVec2, u64)]) {
        for (key, version) in written {
            if self.regions.get(key).is_none_or(|(_, now)| now == version) {
                self.unsaved.remove(key);
            }
        }
    }

    /// Writes every changed region and `world.ron` (with the time of day) now, on this thread: the server's
    /// last save as it stops.
    pub fn save_now(&mut self, hours: f32) -> Result<usize, String> {
        let Some(save) = self.save.clone() else { return Ok(0) };
        let copies = self.unsaved_copies();
        let written = write_regions(save, &copies, hours)?;
        self.saved(&written);
        Ok(written.len())
    }

    pub fn folder(&self) -> Option<&std::path::Path> {
        self.save.as_ref().map(|s| s.folder.as_path())
    }
}

/// Writes `regions` into `save`'s folder and `world.ron` with the time `hours`; the regions written.
fn write_regions(
    mut save: EndlessSave,
    regions: &[(IVec2, u64, VoxelWorld)],
    hours: f32,
) -> Result<Vec<(IVec2, u64)>, String> {
    for (key, _, region) in regions {
        save.save_region(*key, region)?;
    }
    save.time_of_day = Some(hours);
    save.write_world_file()?;
    Ok(regions.iter().map(|(key, version, _)| (*key, *version)).collect())
}

/// The regions a client holds (it hears the edits that touch them), and the changed ones on their way to it.
#[derive(Component, Default)]
pub struct Held {
    /// Each region held, with the ticket of the ask that made it held.
    pub keys: HashMap<IVec2, u32>,
    sending: VecDeque<RegionSend>,
}

/// A changed region on its way to a client, piece by piece.
struct RegionSend {
    key: IVec2,
    ticket: u32,
    seq: u64,
    pieces: Pieces,
    next: usize,
}

/// Bytes of region pieces sent, for the bench.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct EndlessStats {
    pub region_bytes_sent: u64,
    pub changed_regions_sent: u64,
    pub plain_regions_answered: u64,
    pub edits_sent: u64,
}

/// A save being written off the tick, and the regions (with versions) it writes.
#[derive(Resource, Default)]
struct EndlessSaving(Option<Task<Result<Written, String>>>);

/// The regions a save wrote, each with the number of its last edit then.
type Written = Vec<(IVec2, u64)>;

pub struct EndlessServerPlugin;

impl Plugin for EndlessServerPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<EndlessStats>().init_resource::<EndlessSaving>().add_systems(
            Update,
            (
                welcome_to_the_endless_world,
                keep_regions_around_players,
                take_region_asks,
                (apply_endless_edits, apply_endless_history, refuse_spawns)
                    .chain()
                    .in_set(crate::world::events::ApplyEdits),
                send_region_pieces,
                save_endless_on_schedule,
            )
                .chain()
                .after(super::server::NetServerSystems),
        );
    }
}

/// A greeted client is told which endless world this is instead of being sent a world file.
fn welcome_to_the_endless_world(
    mut commands: Commands,
    waiting: Query<Entity, With<WantsWorld>>,
    world: Res<EndlessWorld>,
    (stats, clock): (Res<ServerStats>, Res<WorldClock>),
    mut out: MessageWriter<ToClients<EndlessWelcome>>,
) {
    for client in &waiting {
        commands.entity(client).remove::<WantsWorld>().insert(Held::default());
        let message = EndlessWelcome {
            seed: world.seed(),
            height: world.height(),
            seq: stats.seq,
            player: client.to_bits(),
            hours: clock.0,
        };
        out.write(ToClients { targets: SendTargets::Single(client.into()), message });
    }
}

/// The region a pose stands in.
fn region_of_pose(pose: &Pose) -> IVec2 {
    let [x, _, z] = pose.position;
    EndlessGenerator::region_of(x.floor() as i32, z.floor() as i32)
}

fn keep_regions_around_players(mut world: ResMut<EndlessWorld>, peers: Query<&Peer>) {
    let players: Vec<IVec2> = peers.iter().filter_map(|p| p.pose.as_ref()).map(region_of_pose).collect();
    world.follow_players(&players);
}

/// Adds the regions clients ask for to what they hold and answers: a region nobody changed in a few bytes (the
/// client makes it), a changed one in pieces (`send_region_pieces`). Lets go of the ones they let go.
#[allow(clippy::too_many_arguments)]
fn take_region_asks(
    mut asks: MessageReader<FromClient<RegionAsk>>,
    mut let_go: MessageReader<FromClient<RegionLetGo>>,
    mut world: ResMut<EndlessWorld>,
    mut held: Query<(&mut Held, &mut Peer)>,
    (mut stats, mut counts): (ResMut<ServerStats>, ResMut<EndlessStats>),
    mut out: MessageWriter<ToClients<RegionPiece>>,
    mut refused: MessageWriter<ToClients<Refused>>,
) {
    for gone in let_go.read() {
        if let Some(Ok((mut held, _))) = gone.client_id.entity().map(|e| held.get_mut(e)) {
            let key = IVec2::from_array(gone.message.key);
            if held.keys.get(&key) == Some(&gone.message.ticket) {
                held.keys.remove(&key);
            }
        }
    }
    for ask in asks.read() {
        let Some(Ok((mut held, mut peer))) = ask.client_id.entity().map(|e| held.get_mut(e)) else { continue };
        let key = IVec2::from_array(ask.message.key);
        if key.abs().max_element() > MAX_KEY {
            refuse(&mut stats, &mut peer, ask.client_id, format!("region {key} is past the world's end"), &mut refused);
            continue;
        }
        if !held.keys.contains_key(&key) && held.keys.len() >= MAX_HELD_REGIONS {
            let reason = format!("a client holds at most {MAX_HELD_REGIONS} regions: let some go first");
            refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused);
            continue;
        }
        held.keys.insert(key, ask.message.ticket);
        held.sending.retain(|send| send.key != key);
        let (ticket, seq) = (ask.message.ticket, stats.seq);
        if world.changed.contains(&key) {
            let pieces = world.encoded(key);
            counts.changed_regions_sent += 1;
            held.sending.push_back(RegionSend { key, ticket, seq, pieces, next: 0 });
        } else {
            counts.plain_regions_answered += 1;
            let message = RegionPiece { key: key.to_array(), ticket, seq, index: 0, count: 0, bytes: Vec::new() };
            out.write(ToClients { targets: SendTargets::Single(ask.client_id), message });
        }
    }
}

fn send_region_pieces(
    mut held: Query<(Entity, &mut Held)>,
    rules: Res<ServerRules>,
    mut counts: ResMut<EndlessStats>,
    mut out: MessageWriter<ToClients<RegionPiece>>,
) {
    for (client, mut held) in &mut held {
        for _ in 0..rules.pieces_per_tick {
            let Some(send) = held.sending.front_mut() else { break };
            let bytes = send.pieces[send.next].clone();
            counts.region_bytes_sent += bytes.len() as u64;
            let message = RegionPiece {
                key: send.key.to_array(),
                ticket: send.ticket,
                seq: send.seq,
                index: send.next as u32,
                count: send.pieces.len() as u32,
                bytes,
            };
            out.write(ToClients { targets: SendTargets::Single(client.into()), message });
            send.next += 1;
            if send.next >= send.pieces.len() {
                held.sending.pop_front();
            }
        }
    }
}

/// Sends a change to every client holding a region it changed.
fn send_to_holders(
    done: EditDone,
    keys: &[IVec2],
    held: &Query<(Entity, &Held)>,
    counts: &mut EndlessStats,
    out: &mut MessageWriter<ToClients<EditDone>>,
) {
    for (client, held) in held {
        if keys.iter().any(|key| held.keys.contains_key(key)) {
            counts.edits_sent += 1;
            out.write(ToClients { targets: SendTargets::Single(client.into()), message: done.clone() });
        }
    }
}

/// Applies the edits clients ask for (world coordinates) in one numbered order, as a bounded world's server
/// does; the endless world's palette is the generator's, so an edit that brings materials is refused.
#[allow(clippy::too_many_arguments)]
fn apply_endless_edits(
    mut asks: MessageReader<FromClient<EditAsk>>,
    mut world: ResMut<EndlessWorld>,
    rules: Res<ServerRules>,
    (mut stats, mut counts): (ResMut<ServerStats>, ResMut<EndlessStats>),
    mut peers: Query<&mut Peer>,
    held: Query<(Entity, &Held)>,
    mut histories: ResMut<Histories>,
    mut done: MessageWriter<ToClients<EditDone>>,
    mut refused: MessageWriter<ToClients<Refused>>,
) {
    for ask in asks.read() {
        let Some(mut peer) = ask.client_id.entity().and_then(|e| peers.get_mut(e).ok()) else { continue };
        let edit = Edit::from(&ask.edit);
        let problem = if peer.tokens < 1.0 {
            Some(format!("too many edits: the server takes {} a second", rules.edits_per_second))
        } else if !ask.materials.is_empty() {
            Some("a model's own colours cannot be placed in the endless world yet".to_string())
        } else {
            peer.tokens -= 1.0;
            edit_problem(&edit, &rules).or_else(|| world.problem(&edit))
        };
        if let Some(reason) = problem {
            refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused);
            continue;
        }
        let (min, max) = edit.bounds();
        let before = ask.undoable.then(|| world.read_box(min, max));
        let (changed, keys) = world.apply(&edit, stats.seq + 1);
        if changed == 0 {
            continue;
        }
        stats.seq += 1;
        if let Some(before) = before {
            histories.record(&peer.name, edit.clone(), before);
        }
        let message = EditDone {
            seq: stats.seq,
            by: player_id(ask.client_id),
            undoable: ask.undoable,
            materials: Vec::new(),
            change: Change::Edit(NetEdit::from(&edit)),
        };
        send_to_holders(message, &keys, &held, &mut counts, &mut done);
    }
}

/// Undoes or redoes the asking player's latest batch, in world coordinates.
#[allow(clippy::too_many_arguments)]
fn apply_endless_history(
    mut asks: MessageReader<FromClient<HistoryAsk>>,
    mut world: ResMut<EndlessWorld>,
    (mut stats, mut counts): (ResMut<ServerStats>, ResMut<EndlessStats>),
    mut peers: Query<&mut Peer>,
    held: Query<(Entity, &Held)>,
    mut histories: ResMut<Histories>,
    mut done: MessageWriter<ToClients<EditDone>>,
    mut refused: MessageWriter<ToClients<Refused>>,
) {
    for ask in asks.read() {
        let Some(mut peer) = ask.client_id.entity().and_then(|e| peers.get_mut(e).ok()) else { continue };
        if peer.tokens < 1.0 {
            refuse(&mut stats, &mut peer, ask.client_id, "too many edits: wait a moment".into(), &mut refused);
            continue;
        }
        peer.tokens -= 1.0;
        let Some(edit) = histories.step(&peer.name, ask.redo) else {
            let reason = format!("nothing to {}", if ask.redo { "redo" } else { "undo" });
            refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused);
            continue;
        };
        if let Some(reason) = world.problem(&edit) {
            refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused);
            continue;
        }
        let (changed, keys) = world.apply(&edit, stats.seq + 1);
        if changed == 0 {
            continue;
        }
        stats.seq += 1;
        let message = EditDone {
            seq: stats.seq,
            by: player_id(ask.client_id),
            undoable: false,
            materials: Vec::new(),
            change: Change::Edit(NetEdit::from(&edit)),
        };
        send_to_holders(message, &keys, &held, &mut counts, &mut done);
    }
}

/// Moving objects are not shared in the endless world yet: a spawn is refused with that reason.
fn refuse_spawns(
    mut asks: MessageReader<FromClient<SpawnAsk>>,
    mut stats: ResMut<ServerStats>,
    mut peers: Query<&mut Peer>,
    mut refused: MessageWriter<ToClients<Refused>>,
) {
    for ask in asks.read() {
        let Some(mut peer) = ask.client_id.entity().and_then(|e| peers.get_mut(e).ok()) else { continue };
        let reason = "moving objects are not shared in the endless world yet".to_string();
        refuse(&mut stats, &mut peer, ask.client_id, reason, &mut refused);
    }
}

/// Every `save_every` (and on `SaveNow`), the regions changed since the last save and `world.ron` are written
/// off the tick.
#[allow(clippy::too_many_arguments)]
fn save_endless_on_schedule(
    time: Res<Time>,
    mut since: Local<f32>,
    mut asks: MessageReader<SaveNow>,
    rules: Res<ServerRules>,
    mut world: ResMut<EndlessWorld>,
    clock: Res<WorldClock>,
    mut stats: ResMut<ServerStats>,
    mut saving: ResMut<EndlessSaving>,
) {
    *since += time.delta_secs();
    let Some(save) = world.save.clone() else { return };
    if let Some(task) = &mut saving.0
        && let Some(result) = bevy::tasks::futures::check_ready(task)
    {
        saving.0 = None;
        match result {
            Ok(written) => {
                world.saved(&written);
                stats.saves += 1;
                stats.last_save_error = None;
                println!("saved {} ({} changed regions)", save.folder.display(), written.len());
            }
            Err(e) => {
                eprintln!("could not save {}: {e}", save.folder.display());
                stats.last_save_error = Some(e);
            }
        }
    }
    if asks.read().count() > 0 {
        *since = f32::INFINITY;
    }
    if *since < rules.save_every.as_secs_f32() || saving.0.is_some() {
        return;
    }
    *since = 0.0;
    let copies = world.unsaved_copies();
    let hours = clock.0;
    saving.0 = Some(AsyncComputeTaskPool::get().spawn(async move { write_regions(save, &copies, hours) }));
}

/// Waits for a save still being written (before the server's last one).
pub fn finish_endless_saving(app_world: &mut World) {
    let Some(task) = app_world.resource_mut::<EndlessSaving>().0.take() else { return };
    if let Ok(written) = bevy::tasks::block_on(task) {
        app_world.resource_mut::<EndlessWorld>().saved(&written);
    }
}
