//! `glowbrick bench --net`: what one server holds. A server and N headless clients on loopback in this process
//! (real UDP sockets through renet and netcode); every client edits at a steady rate for a while. Reports the
//! time for all N to receive the world, the server's tick time, the edits per second it applies, the bytes on
//! the wire per edit and per client, and the time from an edit sent by one client to its arrival at another.
//! Clients and server share this machine's cores, so the numbers are a floor for a real server.

use super::net_endless::{EndlessNetConfig, endless_report, run_endless_net};
use crate::net::client::NetClient;
use crate::net::protocol::{Change, EditDone, NetEdit};
use crate::net::server::{ServerRules, ServerStats};
use crate::net::{headless_client_app, server_app, transport};
use crate::world::events::EditRequest;
use crate::world::recipe::generated_world;
use crate::world::{Edit, VoxelWorld};
use bevy::app::App;
use bevy::math::{IVec3, UVec3};
use bevy_replicon_renet::{RenetClient, RenetServer};
use std::fmt::Write as _;
use std::path::Path;
use std::time::{Duration, Instant};

#[derive(Clone, Debug)]
pub struct NetBenchConfig {
    pub client_counts: Vec<usize>,
    /// Edits each client asks for per second.
    pub edits_per_client: f32,
    /// Seconds of steady editing per client count.
    pub seconds: f32,
    pub world_size: UVec3,
    /// The flight through the endless world.
    pub endless: EndlessNetConfig,
}

impl NetBenchConfig {
    pub fn full() -> Self {
        NetBenchConfig {
            client_counts: vec![16, 64],
            edits_per_client: 5.0,
            seconds: 10.0,
            world_size: UVec3::new(256, 96, 256),
            endless: EndlessNetConfig::full(),
        }
    }

    pub fn quick() -> Self {
        NetBenchConfig {
            client_counts: vec![4],
            edits_per_client: 5.0,
            seconds: 2.0,
            world_size: UVec3::new(64, 48, 64),
            endless: EndlessNetConfig::quick(),
        }
    }
}

#[derive(Clone, Debug)]
pub struct NetRow {
    pub clients: usize,
    pub join_seconds: f64,
    pub world_bytes: u64,
    pub edits_applied_per_second: f64,
    pub tick_ms_mean: f64,
    pub tick_ms_p95: f64,
    pub wire_bytes_per_edit_per_client: f64,
    pub upload_bytes_per_edit: f64,
    pub latency_ms_median: f64,
    pub latency_ms_max: f64,
    pub identical: bool,
}

/// The size of one applied edit as it travels (its message's payload, before the transport's headers).
pub fn payload_bytes(edit: &Edit) -> usize {
    let change = Change::Edit(NetEdit::from(edit));
    let done = EditDone { seq: 123_456, by: u64::MAX / 3, undoable: true, materials: Vec::new(), change };
    let mut buffer = vec![0u8; 1 << 20];
    bevy_replicon::postcard::to_slice(&done, &mut buffer).map_or(0, |b| b.len())
}

/// Runs every client count; writes `net.md` and `net.csv` under `out`, returns the markdown.
pub fn run_net_bench(config: &NetBenchConfig, out: &Path) -> Result<String, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let world = generated_world(1, config.world_size).map_err(|e| e.to_string())?;
    let mut rows = Vec::new();
    for &n in &config.client_counts {
        println!("{n} clients...");
        rows.push(run_one(&world, n, config)?);
    }
    let place = payload_bytes(&Edit::Place { at: IVec3::new(500, 90, 500), material: 7 });
    let fill = payload_bytes(&Edit::FillBox { min: IVec3::ZERO, max: IVec3::splat(63), material: 7 });
    let mut md = report(&rows, config, place, fill);
    println!("flying through the endless world...");
    let flight = run_endless_net(&config.endless)?;
    md += &endless_report(&flight, &config.endless);
    if flight.identical_regions != flight.compared_regions || flight.compared_regions == 0 {
        return Err(format!(
            "the flyer holds {} of the builder's regions, {} identical: the endless world's clients disagree",
            flight.compared_regions, flight.identical_regions
        ));
    }
    std::fs::write(out.join("net.md"), &md).map_err(|e| e.to_string())?;
    std::fs::write(out.join("net.csv"), csv(&rows)).map_err(|e| e.to_string())?;
    Ok(md)
}

fn run_one(world: &VoxelWorld, n: usize, config: &NetBenchConfig) -> Result<NetRow, String> {
    let (mut server, mut clients, join_seconds) = join(world, n, config)?;
    let world_bytes = server.world().resource::<ServerStats>().world_bytes_sent / n as u64;
    let seq_before = server.world().resource::<ServerStats>().seq;
    let mut run = edit_steadily(world, &mut server, &mut clients, config);
    let applied = (server.world().resource::<ServerStats>().seq - seq_before) as f64 / run.seconds;
    let identical = settle_and_compare(&mut server, &mut clients);
    run.ticks.sort_by(f64::total_cmp);
    run.latencies.sort_by(f64::total_cmp);
    let mean = |v: &[f64]| if v.is_empty() { 0.0 } else { v.iter().sum::<f64>() / v.len() as f64 };
    let pct = |v: &[f64], p: f64| v.get(((v.len() as f64 - 1.0) * p).round() as usize).copied().unwrap_or(0.0);
    let edit_rate = config.edits_per_client as f64;
    Ok(NetRow {
        clients: n,
        join_seconds,
        world_bytes,
        edits_applied_per_second: applied,
        tick_ms_mean: mean(&run.ticks),
        tick_ms_p95: pct(&run.ticks, 0.95),
        // Everything the server sends each client (edits, player lists, acks) per edit it applied.
        wire_bytes_per_edit_per_client: mean(&run.wire_rates) / n as f64 / applied.max(1e-9),
        upload_bytes_per_edit: mean(&run.upload_rates) / edit_rate,
        latency_ms_median: pct(&run.latencies, 0.5),
        latency_ms_max: run.latencies.last().copied().unwrap_or(0.0),
        identical,
    })
}

/// A server on `world` and `n` clients that have all received it, and the seconds that took.
fn join(world: &VoxelWorld, n: usize, config: &NetBenchConfig) -> Result<(App, Vec<App>, f64), String> {
    let rules = ServerRules { edits_per_second: config.edits_per_client * 4.0, ..Default::default() };
    let mut server = server_app(world.clone(), rules);
    let addr = transport::listen(&mut server, "127.0.0.1:0".parse().unwrap(), None, n)?;
    let mut clients: Vec<App> = (0..n)
        .map(|i| {
            let mut app = headless_client_app(&format!("bot {i}"), ());
            transport::dial(&mut app, addr, None, 1000 + i as u64).map(|_| app)
        })
        .collect::<Result<_, _>>()?;
    let start = Instant::now();
    while !clients.iter().all(|c| c.world().resource::<NetClient>().loaded) {
        if start.elapsed() > Duration::from_secs(600) {
            return Err(format!("{n} clients did not all receive the world in 600 s"));
        }
        server.update();
        clients.iter_mut().for_each(App::update);
    }
    Ok((server, clients, start.elapsed().as_secs_f64()))
}

/// What the steady editing measured: server ticks and probe latencies (ms), the bytes per second the server
/// sent all clients and client 0 uploaded (second half of the run), and the run's length.
struct SteadyRun {
    ticks: Vec<f64>,
    latencies: Vec<f64>,
    wire_rates: Vec<f64>,
    upload_rates: Vec<f64>,
    seconds: f64,
}

/// Steady editing: each client toggles voxels of its own column high above the ground (every edit changes a
/// voxel); client 0's every fifth edit is a probe whose arrival at client 1 is timed.
fn edit_steadily(world: &VoxelWorld, server: &mut App, clients: &mut [App], config: &NetBenchConfig) -> SteadyRun {
    let n = clients.len();
    let size = world.grid.size().as_ivec3();
    let per_row = (size.x - 4) / 2;
    let column = |i: usize, k: u64| {
        let i = i as i32;
        IVec3::new(2 + (i % per_row) * 2, size.y - 2 - (k % 4) as i32, 2 + (i / per_row) * 2)
    };
    let mut owed = vec![0.0f32; n];
    let mut sent = vec![0u64; n];
    let mut probes: Vec<(IVec3, u16, Instant)> = Vec::new();
    let mut run = SteadyRun {
        ticks: Vec::new(),
        latencies: Vec::new(),
        wire_rates: Vec::new(),
        upload_rates: Vec::new(),
        seconds: 0.0,
    };
    let tick = Duration::from_secs_f64(1.0 / 60.0);
    let run_start = Instant::now();
    let mut last = Instant::now();
    while run_start.elapsed().as_secs_f32() < config.seconds {
        let frame = Instant::now();
        let dt = last.elapsed().as_secs_f32();
        last = Instant::now();
        for (i, client) in clients.iter_mut().enumerate() {
            owed[i] += dt * config.edits_per_client;
            while owed[i] >= 1.0 {
                owed[i] -= 1.0;
                let at = column(i, sent[i] / 2);
                let material = if sent[i].is_multiple_of(2) { 1 } else { 0 };
                let edit = if material == 0 { Edit::Break { at } } else { Edit::Place { at, material } };
                if i == 0 && material != 0 {
                    probes.push((at, material, Instant::now()));
                }
                client.world_mut().write_message(EditRequest::player(edit));
                sent[i] += 1;
            }
        }
        let t = Instant::now();
        server.update();
        run.ticks.push(t.elapsed().as_secs_f64() * 1e3);
        clients.iter_mut().for_each(App::update);
        if n > 1 {
            let grid = &clients[1].world().resource::<VoxelWorld>().grid;
            probes.retain(|(at, material, when)| {
                let arrived = grid.get(*at) == *material;
                if arrived {
                    run.latencies.push(when.elapsed().as_secs_f64() * 1e3);
                }
                !arrived && when.elapsed() < Duration::from_secs(5)
            });
        }
        if run_start.elapsed().as_secs_f32() > config.seconds * 0.5 {
            let renet = server.world().resource::<RenetServer>();
            let ids = renet.clients_id_iter();
            run.wire_rates
                .push(ids.filter_map(|id| renet.network_info(id).ok()).map(|i| i.bytes_sent_per_second).sum());
            run.upload_rates.push(clients[0].world().resource::<RenetClient>().network_info().bytes_sent_per_second);
        }
        std::thread::sleep(tick.saturating_sub(frame.elapsed()));
    }
    run.seconds = run_start.elapsed().as_secs_f64();
    run
}

/// Lets the last edits arrive, then whether every client's world is the server's.
fn settle_and_compare(server: &mut App, clients: &mut [App]) -> bool {
    for _ in 0..120 {
        server.update();
        clients.iter_mut().for_each(App::update);
    }
    let target = crate::net::state_hash::voxels_hash(server.world().resource::<VoxelWorld>());
    clients.iter().all(|c| crate::net::state_hash::voxels_hash(c.world().resource::<VoxelWorld>()) == target)
}

fn report(rows: &[NetRow], config: &NetBenchConfig, place: usize, fill: usize) -> String {
    let mut md = String::new();
    let s = config.world_size;
    let _ = writeln!(md, "# One server, many clients (loopback, one process)\n");
    let _ = writeln!(
        md,
        "World: generated, seed 1, {}x{}x{}. Each client asks for {} edits a second for {} s (a voxel placed, then \
         broken, in a column of its own); server and clients share this machine's {} cores, each client a whole \
         Bevy app.\n",
        s.x,
        s.y,
        s.z,
        config.edits_per_client,
        config.seconds,
        std::thread::available_parallelism().map_or(1, |n| n.get())
    );
    let _ = writeln!(
        md,
        "An edit's payload: {place} bytes for a block, {fill} for a box (postcard, before renet's headers).\n"
    );
    let _ = writeln!(
        md,
        "| clients | all joined (s) | world sent per client (KB) | edits applied / s | server tick mean / p95 (ms) | \
         bytes sent per edit per client | bytes uploaded per edit | edit to another client, median / max (ms) | \
         worlds identical |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|---|");
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {:.2} | {:.0} | {:.0} | {:.2} / {:.2} | {:.0} | {:.0} | {:.0} / {:.0} | {} |",
            r.clients,
            r.join_seconds,
            r.world_bytes as f64 / 1e3,
            r.edits_applied_per_second,
            r.tick_ms_mean,
            r.tick_ms_p95,
            r.wire_bytes_per_edit_per_client,
            r.upload_bytes_per_edit,
            r.latency_ms_median,
            r.latency_ms_max,
            if r.identical { "yes" } else { "NO" }
        );
    }
    md
}

fn csv(rows: &[NetRow]) -> String {
    let mut out = String::from(
        "clients,join_s,world_bytes,edits_applied_per_s,tick_ms_mean,tick_ms_p95,wire_bytes_per_edit_per_client,upload_bytes_per_edit,latency_ms_median,latency_ms_max,identical\n",
    );
    for r in rows {
        let _ = writeln!(
            out,
            "{},{:.3},{},{:.1},{:.3},{:.3},{:.1},{:.1},{:.2},{:.2},{}",
            r.clients,
            r.join_seconds,
            r.world_bytes,
            r.edits_applied_per_second,
            r.tick_ms_mean,
            r.tick_ms_p95,
            r.wire_bytes_per_edit_per_client,
            r.upload_bytes_per_edit,
            r.latency_ms_median,
            r.latency_ms_max,
            r.identical
        );
    }
    out
}
