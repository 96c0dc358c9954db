//! `glowbrick serve`: a dedicated server with no window and no GPU. It owns the world, applies the players' edits
//! in one order, and saves the world (RON, atomic, with a `.bak`) every `--save-every` seconds, on `save` typed
//! at its console and when it stops (`quit`, `--seconds` running out, or SIGTERM, SIGINT or SIGHUP: a service
//! manager's stop, Ctrl+C, a closed terminal). A second signal while it saves stops it at once; the atomic write
//! leaves the save or its `.bak` whole. Killed outright (SIGKILL), it loses at most the edits since its last save.
//! The console (`net::console`) reads standard input, a terminal's or a service's.

use super::args::GameWorldArgs;
use crate::net::console::{BanList, ConsoleCommand, HELP, parse_command};
use crate::net::endless_server::{EndlessStats, EndlessWorld};
use crate::net::server::{Bans, ServerRules, ServerStats, WorldClock, run_console_command};
use crate::net::{endless_server_app, server_app, transport};
use crate::world::VoxelWorld;
use crate::world::format::save_with_backup;
use crate::world::generate::endless::DEFAULT_HEIGHT;
use crate::world::region_save::EndlessSave;
use bevy::app::App;
use bevy_replicon_renet::RenetServer;
use clap::Args;
use std::net::{IpAddr, SocketAddr};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::time::{Duration, Instant};

#[derive(Args)]
pub struct ServeArgs {
    #[command(flatten)]
    world: GameWorldArgs,
    /// UDP port to listen on.
    #[arg(long, default_value_t = transport::DEFAULT_PORT)]
    port: u16,
    /// Address to listen on (default: every interface).
    #[arg(long, default_value = "0.0.0.0")]
    bind: IpAddr,
    /// Only clients that know this secret may join (they pass the same --secret); without it the server is open.
    #[arg(long)]
    secret: Option<String>,
    /// Where the world is saved (default: saves/<name of --world>.ron, or saves/server.ron).
    #[arg(long)]
    save: Option<PathBuf>,
    /// Seconds between saves.
    #[arg(long, default_value_t = 60, value_parser = clap::value_parser!(u64).range(1..=86_400))]
    save_every: u64,
    /// Most players at once.
    #[arg(long, default_value_t = 64, value_parser = clap::value_parser!(u64).range(1..=1024))]
    max_players: u64,
    /// Edits one player may make per second (on average; bursts of four seconds' worth pass).
    #[arg(long, default_value_t = 30.0)]
    edits_per_second: f32,
    /// The time of day to start at, in hours (default: the world's saved time, or noon).
    #[arg(long)]
    time: Option<f32>,
    /// Stop (and save) after this many seconds (scripts and tests; default: run until `quit`).
    #[arg(long)]
    seconds: Option<f64>,
    /// Serve the endless world of --seed: players stream their own surroundings wherever they go, and the server
    /// keeps the regions around them and the ones they changed (saved into the folder --save, by default
    /// saves/server-endless-<seed>).
    #[arg(long, conflicts_with_all = ["world", "scene", "new", "size"])]
    endless: bool,
}

/// Server ticks per second.
const TICK_HZ: f64 = 60.0;

impl ServeArgs {
    pub fn run(self) -> Result<(), String> {
        if !(self.edits_per_second.is_finite() && (0.1..=10_000.0).contains(&self.edits_per_second)) {
            return Err(format!("--edits-per-second {} must be within 0.1..10000", self.edits_per_second));
        }
        if let Some(s) = self.seconds
            && !(s.is_finite() && s > 0.0)
        {
            return Err(format!("--seconds {s} must be a positive number"));
        }
        if let Some(t) = self.time
            && !(t.is_finite() && (0.0..=24.0).contains(&t))
        {
            return Err(format!("--time {t} must be within 0..24 hours"));
        }
        let stop = stop_signals()?;
        let (mut app, summary, save, bans_path) = if self.endless { self.endless_app()? } else { self.bounded_app()? };
        let bans = BanList::load(&bans_path)?;
        app.insert_resource(Bans { list: bans, path: Some(bans_path.clone()) });
        let bind = SocketAddr::new(self.bind, self.port);
        let local = transport::listen(&mut app, bind, self.secret.as_deref(), self.max_players as usize)?;
        println!("serving {summary} on {local} (up to {} players)", self.max_players);
        match &self.secret {
            Some(_) => {
                println!("players need the secret to join: glowbrick play --connect HOST:{} --secret ...", local.port())
            }
            None => {
                println!("the server is open: anyone who reaches port {} can join (--secret to close it)", local.port())
            }
        }
        println!(
            "saving to {} every {} s and on stop (quit, SIGTERM, SIGINT, SIGHUP); bans kept in {}",
            save.display(),
            self.save_every,
            bans_path.display()
        );
        println!("{HELP}");
        let console = console_lines();
        let started = Instant::now();
        let tick = Duration::from_secs_f64(1.0 / TICK_HZ);
        let mut last_report = Instant::now();
        let mut ticks = TickTimes::default();
        loop {
            let frame = Instant::now();
            app.update();
            ticks.add(frame.elapsed());
            let mut quit = self.seconds.is_some_and(|s| started.elapsed().as_secs_f64() >= s);
            quit |= take_console_lines(&mut app, &console);
            if stop.load(Ordering::Relaxed) {
                println!("stopping on a signal: saving first (a second signal stops without saving)");
                quit = true;
            }
            if quit {
                break;
            }
            if last_report.elapsed() >= Duration::from_secs(60) {
                last_report = Instant::now();
                println!("{}; {}", report(&mut app), ticks.take());
            }
            std::thread::sleep(tick.saturating_sub(frame.elapsed()));
        }
        // Say goodbye to the clients, then save.
        app.world_mut().resource_mut::<RenetServer>().disconnect_all();
        app.update();
        println!("{}; {}", report(&mut app), ticks.take());
        if self.endless {
            return save_endless_before_stopping(&mut app);
        }
        println!("{}", state_line(&app));
        crate::net::server::finish_saving(app.world_mut());
        let hours = app.world().resource::<WorldClock>().0;
        let mut world = app.world_mut().resource_mut::<VoxelWorld>();
        world.time_of_day = Some(hours);
        println!("saving {} before stopping", save.display());
        save_with_backup(&world, &save).map_err(|e| format!("could not save {}: {e}", save.display()))?;
        println!("saved {}", save.display());
        Ok(())
    }

    fn rules(&self, save: &std::path::Path) -> ServerRules {
        ServerRules {
            edits_per_second: self.edits_per_second,
            edit_burst: self.edits_per_second * 4.0,
            save_path: Some(save.to_path_buf()),
            save_every: Duration::from_secs(self.save_every),
            ..Default::default()
        }
    }

    /// A bounded world's server: the app, what it serves, where it saves and where its bans are kept.
    fn bounded_app(&self) -> Result<(App, String, PathBuf, PathBuf), String> {
        let source = self.world.source();
        let save = self.save.clone().unwrap_or_else(|| self.world.default_save("server"));
        if let Some(folder) = save.parent().filter(|p| !p.as_os_str().is_empty()) {
            std::fs::create_dir_all(folder).map_err(|e| format!("cannot create {}: {e}", folder.display()))?;
        }
        let mut world = source.load().map_err(|e| e.to_string())?;
        if let Some(hours) = self.time {
            world.time_of_day = Some(hours % 24.0);
        }
        let summary =
            format!("a world of {}x{}x{} voxels", world.grid.size().x, world.grid.size().y, world.grid.size().z);
        let bans = BanList::path_beside(&save);
        Ok((server_app(world, self.rules(&save)), summary, save, bans))
    }

    /// The endless world's server (`net::endless_server`), its save a folder of changed regions.
    fn endless_app(&self) -> Result<(App, String, PathBuf, PathBuf), String> {
        let seed = self.world.seed;
        let folder = self.save.clone().unwrap_or_else(|| PathBuf::from(format!("saves/server-endless-{seed}")));
        let save = EndlessSave::open_or_create(&folder, seed, DEFAULT_HEIGHT)?;
        let hours = self.time.or(save.time_of_day).unwrap_or(12.0) % 24.0;
        let world = EndlessWorld::new(seed, DEFAULT_HEIGHT, Some(save))?;
        let summary = format!("the endless world of seed {seed} ({} changed regions saved)", world.counts().1);
        let bans = folder.join("bans.ron");
        Ok((endless_server_app(world, self.rules(&folder), hours), summary, folder, bans))
    }
}

/// The endless server's last save: the regions changed since its last one, and the time of day.
fn save_endless_before_stopping(app: &mut App) -> Result<(), String> {
    crate::net::endless_server::finish_endless_saving(app.world_mut());
    let hours = app.world().resource::<WorldClock>().0;
    let mut world = app.world_mut().resource_mut::<EndlessWorld>();
    let folder = world.folder().map(|f| f.display().to_string()).unwrap_or_default();
    let written = world.save_now(hours).map_err(|e| format!("could not save {folder}: {e}"))?;
    println!("saved {folder} ({written} changed regions)");
    Ok(())
}

/// The server's ticks (one `update` each) since the last report.
#[derive(Default)]
struct TickTimes(Vec<f64>);

impl TickTimes {
    fn add(&mut self, took: Duration) {
        self.0.push(took.as_secs_f64() * 1e3);
    }

    /// "ticks: N, p50 .. ms, p99 .. ms, max .. ms; resident memory .. MB", and a fresh start.
    fn take(&mut self) -> String {
        let mut ms = std::mem::take(&mut self.0);
        ms.sort_by(f64::total_cmp);
        let at = |q: f64| ms.get(((ms.len() as f64 - 1.0) * q).round() as usize).copied().unwrap_or(0.0);
        let rss =
            crate::stress::memory::resident_bytes().map_or("unknown".into(), |b| format!("{:.1} MB", b as f64 / 1e6));
        format!(
            "ticks: {}, p50 {:.2} ms, p99 {:.2} ms, max {:.2} ms; resident memory {rss}",
            ms.len(),
            at(0.5),
            at(0.99),
            at(1.0)
        )
    }
}

/// The world's state hash, as every client that followed the server must have it (`glowbrick bot` prints its own).
fn state_line(app: &App) -> String {
    let world = app.world().resource::<VoxelWorld>();
    let seq = app.world().resource::<ServerStats>().seq;
    let objects = world.objects.as_deref().unwrap_or_default();
    crate::net::state_hash::state_line(seq, world, app.world().resource::<crate::lights::LightPool>(), objects)
}

fn report(app: &mut App) -> String {
    let players = app.world_mut().query::<&crate::net::server::Peer>().iter(app.world()).count();
    let stats = app.world().resource::<ServerStats>();
    let sent = match (app.world().get_resource::<EndlessWorld>(), app.world().get_resource::<EndlessStats>()) {
        (Some(world), Some(endless)) => {
            let (in_memory, changed) = world.counts();
            format!(
                "{:.1} MB of changed regions sent; {in_memory} regions in memory, {changed} changed",
                endless.region_bytes_sent as f64 / 1e6
            )
        }
        _ => format!("{:.1} MB of world sent", stats.world_bytes_sent as f64 / 1e6),
    };
    format!(
        "{players} players; {} edits applied, {} refused; {} joins ({sent}); {} saves",
        stats.seq, stats.refused, stats.joins, stats.saves
    )
}

/// Carries out the lines typed at the console since the last tick; whether one asked to stop.
fn take_console_lines(app: &mut App, console: &mpsc::Receiver<String>) -> bool {
    let mut quit = false;
    while let Ok(line) = console.try_recv() {
        match parse_command(&line) {
            Ok(ConsoleCommand::Save) => {
                app.world_mut().write_message(crate::net::server::SaveNow);
            }
            Ok(ConsoleCommand::Quit) => quit = true,
            Ok(ConsoleCommand::Help) => println!("{HELP}"),
            Ok(command) => {
                let said = run_console_command(app.world_mut(), &command);
                if !said.is_empty() {
                    println!("{said}");
                }
            }
            Err(problem) => println!("{problem}"),
        }
    }
    quit
}

/// A flag SIGTERM, SIGINT and SIGHUP raise (the loop then saves and stops); a second one while it is raised exits
/// at once with 130, the atomic save keeping the last complete save and its `.bak`.
fn stop_signals() -> Result<Arc<AtomicBool>, String> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let stop = Arc::new(AtomicBool::new(false));
    for signal in [SIGTERM, SIGINT, SIGHUP] {
        // Registered first, so it sees the flag before the flag handler raises it.
        signal_hook::flag::register_conditional_shutdown(signal, 130, stop.clone())
            .and_then(|_| signal_hook::flag::register(signal, stop.clone()))
            .map_err(|e| format!("cannot catch signal {signal}: {e}"))?;
    }
    Ok(stop)
}

/// Lines typed at the server's console (none when stdin is closed: the server then runs until `--seconds`).
fn console_lines() -> mpsc::Receiver<String> {
    let (send, receive) = mpsc::channel();
    std::thread::spawn(move || {
        for line in std::io::stdin().lines() {
            let Ok(line) = line else { break };
            if send.send(line).is_err() {
                break;
            }
        }
    });
    receive
}
