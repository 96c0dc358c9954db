//! `glowbrick bench --travel`: a straight flight across the endless world at the game's top flying speed, in
//! real time, with the regions around the player streamed by `world::stream` (a window of 17 x 17 regions, 1088
//! voxels). Reports the time to fill the first window, regions made per second, the longest time the main
//! thread spent on streaming in one 60 Hz tick, the ticks where a region within the view reach (4 regions,
//! 256 voxels) was not yet made, the resident regions and the process's resident memory over the trip. The CPU
//! side only: the GPU upload of the regions that arrive is the scrolling window's, still to come (issue 69).

use crate::game::player::TOP_FLYING_SPEED;
use crate::stress::memory::resident_bytes;
use crate::world::generate::endless::{DEFAULT_HEIGHT, EndlessGenerator, REGION_EDGE};
use crate::world::stream::RegionStreamer;
use bevy::math::{DVec2, IVec2};
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Regions each side of the player's that stay resident.
const RADIUS: i32 = 8;
/// Regions each side of the player's that must be there: the view the player sees.
const VIEW_REACH: i32 = 4;
const TICK: Duration = Duration::from_micros(16_667);

#[derive(Clone, Debug)]
pub struct TravelConfig {
    pub seed: u32,
    /// Voxels flown.
    pub distance: f64,
    /// Voxels a second.
    pub speed: f64,
    /// Unit direction in x and z.
    pub direction: DVec2,
    pub workers: usize,
}

impl TravelConfig {
    /// 10 km along x at top speed (208 s).
    pub fn full() -> Self {
        TravelConfig {
            seed: 1,
            distance: 10_000.0,
            speed: TOP_FLYING_SPEED as f64,
            direction: DVec2::X,
            workers: workers(),
        }
    }

    /// 320 voxels diagonally at top speed (7 s): the test suite's.
    pub fn quick() -> Self {
        TravelConfig { distance: 320.0, direction: DVec2::ONE.normalize(), ..Self::full() }
    }
}

/// One worker a core, leaving none idle: the main thread mostly sleeps between ticks.
fn workers() -> usize {
    std::thread::available_parallelism().map_or(2, |n| n.get())
}

#[derive(Clone, Debug, Default)]
pub struct TravelReport {
    pub first_window_s: f64,
    pub flight_s: f64,
    pub ticks: u64,
    /// Ticks where a region within VIEW_REACH of the player was missing.
    pub ticks_unfilled: u64,
    /// Regions that arrived during the flight (the first window's not counted).
    pub regions_made: usize,
    pub longest_update_ms: f64,
    pub resident_min: usize,
    pub resident_max: usize,
    /// Process resident bytes: the most in the flight's first minute (or all of it, if shorter), the most
    /// after it, and at the end.
    pub rss_first_minute: u64,
    pub rss_after: u64,
    pub rss_end: u64,
}

fn region_at(p: DVec2) -> IVec2 {
    EndlessGenerator::region_of(p.x.floor() as i32, p.y.floor() as i32)
}

pub fn run_travel(config: &TravelConfig) -> Result<TravelReport, String> {
    let generator = Arc::new(EndlessGenerator::new(config.seed, DEFAULT_HEIGHT)?);
    let start_point =
        generator.village_site(IVec2::ZERO).map_or(DVec2::ZERO, |s| DVec2::new(s.centre.0 as f64, s.centre.1 as f64));
    let mut streamer = RegionStreamer::new(generator, RADIUS, config.workers);
    let mut report = TravelReport { resident_min: usize::MAX, ..Default::default() };
    let begin = Instant::now();
    let first = region_at(start_point);
    while !streamer.filled(first, RADIUS) {
        streamer.update(first);
        std::thread::sleep(Duration::from_millis(5));
    }
    report.first_window_s = begin.elapsed().as_secs_f64();
    let flight = Instant::now();
    let seconds = config.distance / config.speed;
    let mut next_tick = Instant::now();
    loop {
        let t = flight.elapsed().as_secs_f64();
        let at = start_point + config.direction * config.speed * t.min(seconds);
        let update = Instant::now();
        let step = streamer.update(region_at(at));
        report.longest_update_ms = report.longest_update_ms.max(update.elapsed().as_secs_f64() * 1e3);
        report.regions_made += step.arrived;
        report.ticks += 1;
        report.ticks_unfilled += u64::from(!streamer.filled(region_at(at), VIEW_REACH));
        report.resident_min = report.resident_min.min(streamer.resident_count());
        report.resident_max = report.resident_max.max(streamer.resident_count());
        let rss = resident_bytes().unwrap_or(0);
        if t < 60.0 {
            report.rss_first_minute = report.rss_first_minute.max(rss);
        } else {
            report.rss_after = report.rss_after.max(rss);
        }
        report.rss_end = rss;
        if t >= seconds {
            break;
        }
        next_tick += TICK;
        std::thread::sleep(next_tick.saturating_duration_since(Instant::now()));
    }
    report.flight_s = flight.elapsed().as_secs_f64();
    Ok(report)
}

pub fn travel_markdown(config: &TravelConfig, r: &TravelReport) -> String {
    let mb = |b: u64| b as f64 / 1e6;
    let edge = (2 * RADIUS + 1) * REGION_EDGE;
    format!(
        "# Travel: the endless world streamed around a straight flight\n\n\
         Seed {}, from the first village, {:.0} voxels at {:.0} voxels/s in direction ({:.2}, {:.2}), real time \
         at 60 ticks a second; {} worker threads; regions of {REGION_EDGE} x {DEFAULT_HEIGHT} x {REGION_EDGE} kept \
         resident {RADIUS} regions each side ({edge} voxels across); the view reach that must be made: {VIEW_REACH} \
         regions each side. The CPU side only (generation and the resident set): the GPU upload is the scrolling \
         window's, not built yet.\n\n\
         | measure | value |\n|---|---|\n\
         | first window ({} regions) made in | {:.2} s |\n\
         | flight | {:.1} s, {} ticks |\n\
         | regions made during the flight | {} ({:.1} a second) |\n\
         | ticks with a region in view reach missing | {} |\n\
         | longest main-thread streaming update in a tick | {:.2} ms |\n\
         | resident regions | {} - {} |\n\
         | resident memory: first minute / after / end | {:.0} / {:.0} / {:.0} MB |\n",
        config.seed,
        config.distance,
        config.speed,
        config.direction.x,
        config.direction.y,
        config.workers,
        (2 * RADIUS + 1).pow(2),
        r.first_window_s,
        r.flight_s,
        r.ticks,
        r.regions_made,
        r.regions_made as f64 / r.flight_s.max(1e-9),
        r.ticks_unfilled,
        r.longest_update_ms,
        r.resident_min,
        r.resident_max,
        mb(r.rss_first_minute),
        mb(r.rss_after),
        mb(r.rss_end),
    )
}

pub fn run_travel_bench(config: &TravelConfig, out: &Path) -> Result<String, String> {
    let report = run_travel(config)?;
    let text = travel_markdown(config, &report);
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let path = out.join("travel.md");
    std::fs::write(&path, &text).map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(text)
}
