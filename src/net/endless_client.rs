//! The client's side of an endless world (`net::endless_server`). Told the seed, it streams and scrolls its own
//! window around its player (`world::follow`), as a game alone does, except that each region's worker first asks
//! the server about it: a region nobody changed is made here from the seed, a changed one comes from the server
//! as of an edit number. From its first ask until it lets a region go, the client hears every edit that touches
//! it (world coordinates) and keeps them by region: those in the window apply at once, and a region entering the
//! window gets every edit made after the copy it was made from. Its own edits leave in world coordinates.

use super::client::NetClient;
use super::protocol::*;
use super::snapshot::PIECE_BYTES;
use crate::lights::LightPool;
use crate::lights::window::{LIGHT_BUDGET, WindowLights};
use crate::world::events::EditApplied;
use crate::world::follow::{STREAM_RADIUS, WINDOW_REGIONS, WRITE_BUDGET, WindowFollower, WindowStart};
use crate::world::generate::endless::{EndlessGenerator, REGION_EDGE};
use crate::world::stream::MakeRegion;
use crate::world::{CameraView, Edit, VoxelWorld};
use bevy::prelude::*;
use std::collections::HashMap;
use std::sync::{Arc, Condvar, Mutex};
use std::time::Duration;

/// Most pieces one changed region may come in (a region file deflates to far fewer).
const MAX_REGION_PIECES: u32 = 256;
/// How long a worker waits for the server's answer before making the region from the seed (and saying so).
const ANSWER_WAIT: Duration = Duration::from_secs(30);

/// The window a client of an endless server keeps: its size, its streaming reach and workers, and where it starts
/// (world coordinates; by default where the server says the player was, else above the first village).
#[derive(Resource, Clone, Debug)]
pub struct EndlessWindowConfig {
    pub regions: i32,
    pub radius: i32,
    pub workers: usize,
    pub start: Option<Vec3>,
}

impl Default for EndlessWindowConfig {
    fn default() -> Self {
        EndlessWindowConfig {
            regions: WINDOW_REGIONS,
            radius: STREAM_RADIUS,
            workers: crate::world::follow::stream_workers(),
            start: None,
        }
    }
}

/// The server's answer about a region: the edit number it is as of, and the deflated region where it changed.
type Answer = (u32, u64, Option<Vec<u8>>);

/// What the region workers and the client's tick share.
#[derive(Default)]
struct Asks {
    /// Asks the workers made, for the tick to send.
    outbox: Vec<(IVec2, u32)>,
    next_ticket: u32,
    answers: HashMap<IVec2, Answer>,
    /// The edit number each region the streamer holds was made as of.
    made_as_of: HashMap<IVec2, u64>,
    closed: bool,
}

type SharedAsks = Arc<(Mutex<Asks>, Condvar)>;

/// The region maker of a client: asks the server, waits for its answer, then makes the region from the seed or
/// from the server's copy.
fn region_maker(generator: Arc<EndlessGenerator>, asks: SharedAsks) -> MakeRegion {
    Arc::new(move |key| {
        let (lock, wake) = &*asks;
        let mut shared = lock.lock().unwrap_or_else(|e| e.into_inner());
        let ticket = shared.next_ticket;
        shared.next_ticket = shared.next_ticket.wrapping_add(1);
        shared.outbox.push((key, ticket));
        let asked = std::time::Instant::now();
        let answer = loop {
            // A stale answer (to an earlier ask for the region) is dropped.
            if let Some((t, seq, bytes)) = shared.answers.remove(&key)
                && t == ticket
            {
                break Some((seq, bytes));
            }
            if shared.closed || asked.elapsed() > ANSWER_WAIT {
                break None;
            }
            shared = wake.wait_timeout(shared, Duration::from_millis(100)).unwrap_or_else(|e| e.into_inner()).0;
        };
        drop(shared);
        let (seq, region) = match answer {
            Some((seq, None)) => (seq, generator.region(key)),
            Some((seq, Some(bytes))) => match server_region(&generator, &bytes) {
                Ok(region) => (seq, region),
                Err(e) => {
                    warn!("the server's region {key}: {e}; the seed's is shown instead");
                    (seq, generator.region(key))
                }
            },
            None => {
                warn!("the server did not answer about region {key}: the seed's is shown");
                (0, generator.region(key))
            }
        };
        lock.lock().unwrap_or_else(|e| e.into_inner()).made_as_of.insert(key, seq);
        region
    })
}

/// A changed region as the server sent it: a world file of one region of this world.
fn server_region(generator: &EndlessGenerator, bytes: &[u8]) -> Result<VoxelWorld, String> {
    let region = super::snapshot::decode(bytes)?;
    let size = UVec3::new(REGION_EDGE as u32, generator.height(), REGION_EDGE as u32);
    if region.grid.size() != size {
        return Err(format!("it is {}, not {size}", region.grid.size()));
    }
    if region.palette != *generator.palette() {
        return Err("its palette is not the endless world's".into());
    }
    Ok(region)
}

/// The window being made, then followed.
enum Window {
    Starting(WindowStart),
    Following(WindowFollower),
}

/// The endless world this client joined: its window, what it holds and the edits that touched it.
#[derive(Resource)]
pub struct EndlessClient {
    /// In a mutex only because the streamer's channel may not be shared between threads; one system uses it.
    window: Mutex<Option<Window>>,
    asks: SharedAsks,
    lights: WindowLights,
    generator: Arc<EndlessGenerator>,
    /// Where the player is (window coordinates) and which way it looks: the window follows it.
    pub at: Vec3,
    pub yaw: f32,
    /// Which way the player looks at the start, and the server's time of day then.
    look: Vec3,
    hours: Option<f32>,
    /// The world column of the window's column (0, 0), once the window is made.
    min: Option<IVec2>,
    /// Regions asked for and not let go, with their asks' tickets.
    held: HashMap<IVec2, u32>,
    /// Every edit (world coordinates, cut to the region) that touched a held region since it was asked for.
    edits: HashMap<IVec2, Vec<(u64, Edit)>>,
    /// Changed regions arriving: ticket, edit number, pieces so far, their bytes.
    arriving: HashMap<IVec2, (u32, u64, u32, Vec<u8>)>,
    /// Bytes of changed regions received, for the bench.
    pub region_bytes: u64,
}

impl Drop for EndlessClient {
    fn drop(&mut self) {
        // Workers waiting for an answer give up at once, so the streamer's threads can be joined.
        let (lock, wake) = &*self.asks;
        lock.lock().unwrap_or_else(|e| e.into_inner()).closed = true;
        wake.notify_all();
    }
}

impl EndlessClient {
    /// Starts the window of the endless world of `seed` and `height` around `start` (world coordinates).
    pub fn start(seed: u32, height: u32, start: Vec3, config: &EndlessWindowConfig) -> Result<Self, String> {
        let generator = Arc::new(EndlessGenerator::new(seed, height)?);
        let asks = SharedAsks::default();
        let make = region_maker(generator.clone(), asks.clone());
        let centre = EndlessGenerator::region_of(start.x.floor() as i32, start.z.floor() as i32);
        let window = WindowStart::new(generator.clone(), make, centre, config.regions, config.radius, config.workers);
        Ok(EndlessClient {
            window: Mutex::new(Some(Window::Starting(window))),
            asks,
            lights: WindowLights::default(),
            generator,
            at: start,
            yaw: 0.0,
            look: look_along(0.0),
            hours: None,
            min: None,
            held: HashMap::new(),
            edits: HashMap::new(),
            arriving: HashMap::new(),
            region_bytes: 0,
        })
    }

    /// What a window coordinate adds to make a world coordinate, once the window is made.
    pub fn offset(&self) -> Option<IVec3> {
        self.min.map(|min| IVec3::new(min.x, 0, min.y))
    }

    /// Whether the window is made and in play.
    pub fn started(&self) -> bool {
        self.min.is_some()
    }

    /// Regions this client holds (asked for and not let go).
    pub fn held_count(&self) -> usize {
        self.held.len()
    }

    pub fn seed(&self) -> u32 {
        self.generator.seed()
    }

    /// Applies the edits that touched region `key` after the copy it was made from (it just entered the window).
    fn catch_up(&self, world: &mut VoxelWorld, key: IVec2, offset: IVec3) {
        let Some(edits) = self.edits.get(&key) else { return };
        let made_as_of = self.asks.0.lock().unwrap_or_else(|e| e.into_inner()).made_as_of.get(&key).copied();
        for (seq, edit) in edits {
            if made_as_of.is_some_and(|made| *seq > made)
                && let Err(e) = world.apply(edit.moved(-offset))
            {
                warn!("edit {seq} from the server does not apply here: {e}");
            }
        }
    }

    /// Forgets region `key` (the streamer let it go); the ticket it was held by.
    fn let_go(&mut self, key: IVec2) -> Option<u32> {
        let ticket = self.held.remove(&key);
        self.edits.remove(&key);
        self.arriving.remove(&key);
        self.asks.0.lock().unwrap_or_else(|e| e.into_inner()).made_as_of.remove(&key);
        ticket
    }
}

pub struct EndlessClientPlugin;

impl Plugin for EndlessClientPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<EndlessWindowConfig>().add_systems(
            Update,
            (
                take_endless_welcome,
                (send_region_asks, take_region_pieces, take_endless_edits, follow_endless_window, send_endless_pose)
                    .chain()
                    .in_set(crate::world::events::ApplyEdits)
                    .run_if(resource_exists::<EndlessClient>),
            )
                .chain(),
        );
    }
}

/// A view's direction facing `yaw`, a little down.
fn look_along(yaw: f32) -> Vec3 {
    Vec3::new(yaw.sin(), -0.3, yaw.cos())
}

/// An endless welcome starts the window around where the player starts.
fn take_endless_welcome(
    mut commands: Commands,
    mut welcomes: MessageReader<EndlessWelcome>,
    mut back: MessageReader<WelcomeBack>,
    mut client: ResMut<NetClient>,
    config: Res<EndlessWindowConfig>,
    mut returned: Local<Option<Pose>>,
    renet: Option<ResMut<bevy_replicon_renet::RenetClient>>,
) {
    if let Some(back) = back.read().last() {
        *returned = Some(back.pose).filter(|p| Vec3::from(p.position).is_finite() && p.yaw.is_finite());
    }
    let Some(welcome) = welcomes.read().last() else { return };
    client.me = Some(welcome.player);
    client.seq = welcome.seq;
    let generator = EndlessGenerator::new(welcome.seed, welcome.height);
    let village = generator.ok().map(|g| g.start_view());
    let (start, look) = match (config.start, returned.take(), village) {
        (Some(start), _, _) => (start, look_along(0.0)),
        (None, Some(back), _) => (back.position.into(), look_along(back.yaw)),
        (None, None, Some(view)) => (Vec3::from(view.origin), Vec3::from(view.direction)),
        (None, None, None) => (Vec3::ZERO, Vec3::Z),
    };
    match EndlessClient::start(welcome.seed, welcome.height, start, &config) {
        Ok(mut endless) => {
            endless.look = look;
            endless.hours = Some(welcome.hours);
            info!("joined the endless world of seed {}: making the window around {start}", welcome.seed);
            commands.insert_resource(endless);
        }
        Err(e) => {
            error!("the server's endless world: {e}");
            client.error = Some(e);
            if let Some(mut renet) = renet {
                renet.disconnect();
            }
        }
    }
}

/// Sends the asks the workers made since the last tick.
fn send_region_asks(mut endless: ResMut<EndlessClient>, mut out: MessageWriter<RegionAsk>) {
    let asked = std::mem::take(&mut endless.asks.0.lock().unwrap_or_else(|e| e.into_inner()).outbox);
    for (key, ticket) in asked {
        endless.held.insert(key, ticket);
        out.write(RegionAsk { key: key.to_array(), ticket });
    }
}

/// Hands the server's answers to the workers waiting for them.
fn take_region_pieces(mut endless: ResMut<EndlessClient>, mut pieces: MessageReader<RegionPiece>) {
    let endless = &mut *endless;
    let mut answers = Vec::new();
    for piece in pieces.read() {
        let key = IVec2::from_array(piece.key);
        if endless.held.get(&key) != Some(&piece.ticket) {
            continue;
        }
        if piece.count == 0 {
            answers.push((key, (piece.ticket, piece.seq, None)));
            continue;
        }
        if piece.count > MAX_REGION_PIECES || piece.bytes.len() > PIECE_BYTES || piece.index >= piece.count {
            warn!("region {key}'s piece {} of {} is out of bounds: ignored", piece.index, piece.count);
            continue;
        }
        if piece.index == 0 {
            endless.arriving.insert(key, (piece.ticket, piece.seq, 0, Vec::new()));
        }
        let Some((ticket, seq, received, bytes)) = endless.arriving.get_mut(&key) else { continue };
        if (*ticket, *seq, *received) != (piece.ticket, piece.seq, piece.index) {
            warn!("region {key}'s pieces arrived out of order: ignored");
            endless.arriving.remove(&key);
            continue;
        }
        bytes.extend_from_slice(&piece.bytes);
        *received += 1;
        endless.region_bytes += piece.bytes.len() as u64;
        if *received == piece.count
            && let Some((ticket, seq, _, bytes)) = endless.arriving.remove(&key)
        {
            answers.push((key, (ticket, seq, Some(bytes))));
        }
    }
    if answers.is_empty() {
        return;
    }
    let (lock, wake) = &*endless.asks;
    lock.lock().unwrap_or_else(|e| e.into_inner()).answers.extend(answers);
    wake.notify_all();
}

/// The region keys the box `min..=max` (world coordinates) spans.
fn keys_of(min: IVec3, max: IVec3) -> impl Iterator<Item = IVec2> {
    let a = EndlessGenerator::region_of(min.x, min.z);
    let b = EndlessGenerator::region_of(max.x, max.z);
    (a.y..=b.y).flat_map(move |z| (a.x..=b.x).map(move |x| IVec2::new(x, z)))
}

/// Keeps every edit by the regions it touched, and applies the parts in the window now.
fn take_endless_edits(
    mut endless: ResMut<EndlessClient>,
    mut client: ResMut<NetClient>,
    mut done: MessageReader<EditDone>,
    world: Option<ResMut<VoxelWorld>>,
    mut applied: MessageWriter<EditApplied>,
) {
    let endless = &mut *endless;
    let mut world = world.filter(|_| endless.started());
    let window = endless.window.get_mut().unwrap_or_else(|e| e.into_inner());
    for done in done.read() {
        let Change::Edit(edit) = &done.change else { continue };
        if done.seq <= client.seq {
            continue;
        }
        client.seq = client.seq.max(done.seq);
        let edit = Edit::from(edit);
        let (min, max) = edit.bounds();
        for key in keys_of(min, max) {
            if !endless.held.contains_key(&key) {
                continue;
            }
            let corner = IVec3::new(key.x * REGION_EDGE, 0, key.y * REGION_EDGE);
            let size = IVec3::new(REGION_EDGE, endless.generator.height() as i32, REGION_EDGE);
            let Some(part) = edit.clipped(corner, corner + size - IVec3::ONE) else { continue };
            endless.edits.entry(key).or_default().push((done.seq, part.clone()));
            if let (Some(world), Some(Window::Following(follower)), Some(min)) = (world.as_mut(), &*window, endless.min)
                && follower.holds(world, key)
            {
                let local = part.moved(-IVec3::new(min.x, 0, min.y));
                let (lo, hi) = local.bounds();
                match world.apply(local.clone()) {
                    Ok(0) => {}
                    Ok(changed) => {
                        applied.write(EditApplied { edit: local, min: lo, max: hi, changed, before: None });
                    }
                    Err(e) => warn!("edit {} from the server does not apply here: {e}", done.seq),
                }
            }
        }
    }
}

/// Makes the window, then streams and scrolls it after the player, lighting what a scroll brought in; regions
/// entering it catch up on the edits made since their copy; regions let go are let go at the server too.
#[allow(clippy::too_many_arguments)]
fn follow_endless_window(
    mut commands: Commands,
    mut endless: ResMut<EndlessClient>,
    mut client: ResMut<NetClient>,
    world: Option<ResMut<VoxelWorld>>,
    pool: Option<ResMut<LightPool>>,
    mut let_go: MessageWriter<RegionLetGo>,
) {
    let endless = &mut *endless;
    let taken = endless.window.get_mut().unwrap_or_else(|e| e.into_inner()).take();
    let next = match taken {
        Some(Window::Starting(start)) => match start.poll() {
            Err(waiting) => Some(Window::Starting(waiting)),
            Ok((follower, window)) => {
                let mut world = window.world;
                let offset = IVec3::new(window.min.x, 0, window.min.y);
                let (lo, hi) = world.grid.window();
                for key in keys_of(lo + offset, hi - IVec3::ONE + offset) {
                    endless.catch_up(&mut world, key, offset);
                }
                world.grid.take_dirty();
                let origin = endless.at - offset.as_vec3();
                world.views = vec![CameraView {
                    name: "joined".into(),
                    origin: origin.into(),
                    direction: endless.look.into(),
                    fov_deg: 60.0,
                }];
                world.time_of_day = endless.hours;
                endless.at = origin;
                endless.min = Some(window.min);
                client.loaded = true;
                commands.insert_resource(world);
                Some(Window::Following(follower))
            }
        },
        Some(Window::Following(mut follower)) => {
            if let (Some(mut world), Some(min)) = (world, endless.min) {
                let offset = IVec3::new(min.x, 0, min.y);
                let followed = follower.follow(world.bypass_change_detection(), endless.at, WRITE_BUDGET);
                if let Some(plan) = &followed.finished {
                    for &key in &plan.keys {
                        endless.catch_up(world.bypass_change_detection(), key, offset);
                    }
                }
                if let Some(mut pool) = pool {
                    endless.lights.followed(&mut pool, &world, &followed);
                    if endless.lights.waiting() > 0 {
                        endless.lights.update(&mut pool, &world, LIGHT_BUDGET);
                    }
                }
                for &key in &followed.stream.let_go {
                    if let Some(ticket) = endless.let_go(key) {
                        let_go.write(RegionLetGo { key: key.to_array(), ticket });
                    }
                }
                if followed.began.is_some() || followed.regions_written > 0 || followed.finished.is_some() {
                    world.set_changed();
                }
            }
            Some(Window::Following(follower))
        }
        None => None,
    };
    *endless.window.get_mut().unwrap_or_else(|e| e.into_inner()) = next;
}

/// Tells the server where the player is, in world coordinates, ten times a second.
fn send_endless_pose(
    endless: Res<EndlessClient>,
    time: Res<Time>,
    mut since: Local<f32>,
    mut poses: MessageWriter<Pose>,
) {
    *since += time.delta_secs();
    let Some(offset) = endless.offset().filter(|_| *since >= 0.1) else { return };
    *since = 0.0;
    poses.write(Pose { position: (endless.at + offset.as_vec3()).into(), yaw: endless.yaw });
}
