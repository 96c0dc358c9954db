//! `glowbrick bench --net`'s endless part: what a player flying through the endless world costs on the wire. A
//! server of the endless world and two headless clients on loopback: a builder stays at the first village and
//! builds steadily; a flyer starts `distance` voxels east of it and flies to it at the game's top speed, its
//! window streaming around it. Reports each client's bytes per second both ways, what the server answered (plain
//! regions, changed regions and their bytes, edits sent), the server's ticks and regions in memory, the ticks where
//! the flyer's view ran outside its window, and whether the flyer, arrived, holds the builder's regions as the
//! builder does.

use crate::net::endless_client::{EndlessClient, EndlessWindowConfig};
use crate::net::endless_server::{EndlessStats, EndlessWorld};
use crate::net::server::{ServerRules, ServerStats};
use crate::net::{endless_server_app, headless_client_app, transport};
use crate::world::events::EditRequest;
use crate::world::generate::endless::{EndlessGenerator, REGION_EDGE};
use crate::world::{Edit, VoxelWorld};
use bevy::app::App;
use bevy::math::{IVec2, IVec3, Vec3};
use bevy_replicon_renet::RenetClient;
use std::fmt::Write as _;
use std::time::{Duration, Instant};

#[derive(Clone, Debug)]
pub struct EndlessNetConfig {
    pub seed: u32,
    pub height: u32,
    pub window: EndlessWindowConfig,
    /// How far east of the builder the flyer starts (voxels), and its speed (voxels a second).
    pub distance: f32,
    pub speed: f32,
    /// The builder's edits a second.
    pub edits_per_second: f32,
}

impl EndlessNetConfig {
    /// The game's window and height, two players 5 km apart, the flyer at the game's top flying speed.
    pub fn full() -> Self {
        EndlessNetConfig {
            seed: 1,
            height: crate::world::generate::endless::DEFAULT_HEIGHT,
            window: EndlessWindowConfig { workers: 1, ..Default::default() },
            distance: 5000.0,
            speed: crate::game::player::TOP_FLYING_SPEED,
            edits_per_second: 5.0,
        }
    }

    pub fn quick() -> Self {
        EndlessNetConfig {
            seed: 1,
            height: 64,
            window: EndlessWindowConfig { regions: 4, radius: 3, workers: 1, start: None },
            distance: 384.0,
            speed: 128.0,
            edits_per_second: 5.0,
        }
    }
}

/// What the flight measured.
#[derive(Clone, Debug, Default)]
pub struct EndlessNetRun {
    pub join_seconds: f64,
    pub flight_seconds: f64,
    /// Mean bytes a second each client received and sent over the flight (renet's count, with its headers).
    pub flyer_down: f64,
    pub flyer_up: f64,
    pub builder_down: f64,
    pub builder_up: f64,
    pub plain_regions: u64,
    pub changed_regions: u64,
    pub changed_region_bytes: u64,
    pub edits_applied: u64,
    pub edits_sent: u64,
    pub tick_ms_p50: f64,
    pub tick_ms_p99: f64,
    pub tick_ms_max: f64,
    pub server_regions_max: usize,
    pub ticks: usize,
    pub ticks_outside_window: usize,
    /// The builder's changed regions as the flyer holds them, and how many equal the builder's.
    pub compared_regions: usize,
    pub identical_regions: usize,
}

fn client(
    addr: std::net::SocketAddr,
    name: &str,
    id: u64,
    start: Vec3,
    config: &EndlessNetConfig,
) -> Result<App, String> {
    let mut app = headless_client_app(name, ());
    app.insert_resource(EndlessWindowConfig { start: Some(start), ..config.window.clone() });
    transport::dial(&mut app, addr, None, id)?;
    Ok(app)
}

fn endless(app: &App) -> &EndlessClient {
    app.world().resource::<EndlessClient>()
}

fn started(app: &App) -> bool {
    app.world().get_resource::<EndlessClient>().is_some_and(EndlessClient::started)
}

/// Region `key` as `app`'s window holds it, where it holds it whole.
fn region_held(app: &App, key: IVec2, height: u32) -> Option<Vec<u16>> {
    let offset = endless(app).offset()?;
    let grid = &app.world().resource::<VoxelWorld>().grid;
    let lo = IVec3::new(key.x * REGION_EDGE, 0, key.y * REGION_EDGE) - offset;
    let hi = lo + IVec3::new(REGION_EDGE, height as i32, REGION_EDGE);
    let (a, b) = grid.window();
    (lo.cmpge(a).all() && hi.cmple(b).all()).then(|| grid.read_box(lo, hi))
}

pub fn run_endless_net(config: &EndlessNetConfig) -> Result<EndlessNetRun, String> {
    let world = EndlessWorld::new(config.seed, config.height, None)?;
    let rules = ServerRules { edits_per_second: config.edits_per_second * 4.0, ..Default::default() };
    let mut server = endless_server_app(world, rules, 12.0);
    let addr = transport::listen(&mut server, "127.0.0.1:0".parse().unwrap(), None, 4)?;
    let generator = EndlessGenerator::new(config.seed, config.height)?;
    let home = Vec3::from(generator.start_view().origin);
    let away = home + Vec3::X * config.distance;
    let mut builder = client(addr, "builder", 1, home, config)?;
    let mut flyer = client(addr, "flyer", 2, away, config)?;
    let join_seconds = join_both(&mut server, &mut builder, &mut flyer)?;
    let mut run = EndlessNetRun { join_seconds, ..Default::default() };

    // The builder toggles voxels of a column high above its window's middle: every edit changes one.
    let builder_offset = endless(&builder).offset().unwrap();
    let column = (home.as_ivec3() - builder_offset) * IVec3::new(1, 0, 1) + IVec3::Y * (config.height as i32 - 3);
    let flyer_from = endless(&flyer).at;
    let flyer_to = flyer_from - Vec3::X * config.distance;
    let (mut owed, mut sent) = (0.0f32, 0u64);
    let (mut ticks, mut down, mut up, mut builder_down, mut builder_up) = (vec![], vec![], vec![], vec![], vec![]);
    let seq_before = server.world().resource::<ServerStats>().seq;
    let stats_before = *server.world().resource::<EndlessStats>();
    let flight = Instant::now();
    let mut last = Instant::now();
    let tick = Duration::from_secs_f64(1.0 / 60.0);
    loop {
        let frame = Instant::now();
        let dt = last.elapsed().as_secs_f32();
        last = Instant::now();
        let flown = (flight.elapsed().as_secs_f32() * config.speed).min(config.distance);
        let at = flyer_from + (flyer_to - flyer_from) * (flown / config.distance);
        flyer.world_mut().resource_mut::<EndlessClient>().at = at;
        owed += dt * config.edits_per_second;
        while owed >= 1.0 {
            owed -= 1.0;
            let at = column + IVec3::Y * (sent / 2 % 2) as i32;
            let edit = if sent.is_multiple_of(2) { Edit::Place { at, material: 1 } } else { Edit::Break { at } };
            builder.world_mut().write_message(EditRequest::player(edit));
            sent += 1;
        }
        let t = Instant::now();
        server.update();
        ticks.push(t.elapsed().as_secs_f64() * 1e3);
        builder.update();
        flyer.update();
        run.server_regions_max = run.server_regions_max.max(server.world().resource::<EndlessWorld>().counts().0);
        let (lo, hi) = flyer.world().resource::<VoxelWorld>().grid.window();
        run.ticks += 1;
        if at.x < lo.x as f32 || at.x >= hi.x as f32 || at.z < lo.z as f32 || at.z >= hi.z as f32 {
            run.ticks_outside_window += 1;
        }
        if flight.elapsed().as_secs_f32() > 1.0 {
            let info = |app: &App| app.world().resource::<RenetClient>().network_info();
            down.push(info(&flyer).bytes_received_per_second);
            up.push(info(&flyer).bytes_sent_per_second);
            builder_down.push(info(&builder).bytes_received_per_second);
            builder_up.push(info(&builder).bytes_sent_per_second);
        }
        if flown >= config.distance && flight.elapsed().as_secs_f32() > config.distance / config.speed + 2.0 {
            break;
        }
        std::thread::sleep(tick.saturating_sub(frame.elapsed()));
    }
    run.flight_seconds = flight.elapsed().as_secs_f64();
    let mean = |v: &[f64]| if v.is_empty() { 0.0 } else { v.iter().sum::<f64>() / v.len() as f64 };
    (run.flyer_down, run.flyer_up) = (mean(&down), mean(&up));
    (run.builder_down, run.builder_up) = (mean(&builder_down), mean(&builder_up));
    ticks.sort_by(f64::total_cmp);
    let pct = |p: f64| ticks.get(((ticks.len() as f64 - 1.0) * p).round() as usize).copied().unwrap_or(0.0);
    (run.tick_ms_p50, run.tick_ms_p99, run.tick_ms_max) = (pct(0.5), pct(0.99), pct(1.0));
    let stats = *server.world().resource::<EndlessStats>();
    run.plain_regions = stats.plain_regions_answered - stats_before.plain_regions_answered;
    run.changed_regions = stats.changed_regions_sent - stats_before.changed_regions_sent;
    run.changed_region_bytes = stats.region_bytes_sent - stats_before.region_bytes_sent;
    run.edits_sent = stats.edits_sent - stats_before.edits_sent;
    run.edits_applied = server.world().resource::<ServerStats>().seq - seq_before;
    let key = EndlessGenerator::region_of(column.x + builder_offset.x, column.z + builder_offset.z);
    (run.compared_regions, run.identical_regions) =
        compare_on_arrival(&mut server, &mut builder, &mut flyer, key, config.height);
    Ok(run)
}

/// Runs the server and both clients until both windows are made; the seconds it took.
fn join_both(server: &mut App, builder: &mut App, flyer: &mut App) -> Result<f64, String> {
    let start = Instant::now();
    while !(started(builder) && started(flyer)) {
        if start.elapsed() > Duration::from_secs(600) {
            return Err("the two clients' windows were not made in 600 s".into());
        }
        server.update();
        builder.update();
        flyer.update();
        std::thread::sleep(Duration::from_millis(1));
    }
    Ok(start.elapsed().as_secs_f64())
}

/// Once the last edits have arrived, the regions around `key` that both clients hold: how many, and how many of
/// them are the same in both windows.
fn compare_on_arrival(server: &mut App, builder: &mut App, flyer: &mut App, key: IVec2, height: u32) -> (usize, usize) {
    for _ in 0..120 {
        server.update();
        builder.update();
        flyer.update();
    }
    let (mut compared, mut identical) = (0, 0);
    for dz in -1..=1 {
        for dx in -1..=1 {
            let key = key + IVec2::new(dx, dz);
            if let (Some(a), Some(b)) = (region_held(builder, key, height), region_held(flyer, key, height)) {
                compared += 1;
                identical += (a == b) as usize;
            }
        }
    }
    (compared, identical)
}

/// The run as a section of net.md.
pub fn endless_report(run: &EndlessNetRun, config: &EndlessNetConfig) -> String {
    let mut md = String::new();
    let _ = writeln!(
        md,
        "\n## Flying through the endless world\n\nA server of the endless world (seed {}, {} voxels high) and two \
         headless clients on loopback, each streaming a window of {} x {} regions ({} regions around it, {} worker): \
         a builder at the first village toggling a voxel {} times a second, and a flyer starting {:.0} voxels east \
         of it, flying to it at {:.0} voxels a second. Both made their windows in {:.1} s; the flight took {:.1} s.\n",
        config.seed,
        config.height,
        config.window.regions,
        config.window.regions,
        config.window.radius,
        config.window.workers,
        config.edits_per_second,
        config.distance,
        config.speed,
        run.join_seconds,
        run.flight_seconds,
    );
    let _ = writeln!(md, "| client | bytes received a second | bytes sent a second |\n|---|---:|---:|");
    let _ = writeln!(md, "| flyer | {:.0} | {:.0} |", run.flyer_down, run.flyer_up);
    let _ = writeln!(md, "| builder | {:.0} | {:.0} |", run.builder_down, run.builder_up);
    let _ = writeln!(
        md,
        "\nDuring the flight the server answered {} asks for regions nobody changed (the flyer made them from the seed) \
         and sent {} changed regions ({:.1} KB deflated); it applied {} edits and sent {} (an edit goes only to the \
         clients holding its region). Server ticks: p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms; at most {} regions in \
         its memory. The flyer's view was outside its window in {} of {} ticks. Arrived, the flyer held {} of the \
         builder's regions, {} of them identical to the builder's.",
        run.plain_regions,
        run.changed_regions,
        run.changed_region_bytes as f64 / 1e3,
        run.edits_applied,
        run.edits_sent,
        run.tick_ms_p50,
        run.tick_ms_p99,
        run.tick_ms_max,
        run.server_regions_max,
        run.ticks_outside_window,
        run.ticks,
        run.compared_regions,
        run.identical_regions,
    );
    md
}
