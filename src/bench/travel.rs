//! `glowbrick bench --travel`: a straight flight across the endless world at the game's top flying speed, in
//! real time, through the game's window: 16 x 16 regions (1024 voxels) that scroll after the player
//! (`world::follow`), fed by regions streamed on worker threads `RADIUS` regions around it, with the light pool
//! following and each tick's GPU upload staged as the game stages it. Reports the time to make the first window,
//! regions made per second, scrolls, the longest time the main thread spent on the window in one 60 Hz tick
//! (streaming, scrolling, the light pool and the upload's staging), the upload bytes per tick, the ticks where
//! the window did not reach the view (4 regions, 256 voxels) ahead, and the process's resident memory over the
//! trip. No GPU: the bytes are what the renderer would write.

use crate::game::player::TOP_FLYING_SPEED;
use crate::lights::LightPool;
use crate::lights::window::LIGHT_BUDGET;
use crate::lights::window::WindowLights;
use crate::render::scene::world::{UploadState, stage_upload, world_gpu_bytes};
use crate::stress::memory::resident_bytes;
use crate::world::follow::{STREAM_RADIUS as RADIUS, WINDOW_REGIONS, WRITE_BUDGET, WindowFollower, stream_workers};
use crate::world::generate::endless::{DEFAULT_HEIGHT, EndlessGenerator, REGION_EDGE};
use bevy::math::{DVec2, IVec2, Vec3};
use std::path::Path;
use std::sync::Arc;
use std::time::{Duration, Instant};

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
            workers: stream_workers(),
        }
    }

    /// 320 voxels diagonally at top speed (7 s): the test suite's.
    pub fn quick() -> Self {
        TravelConfig { distance: 320.0, direction: DVec2::ONE.normalize(), ..Self::full() }
    }
}

#[derive(Clone, Debug, Default)]
pub struct TravelReport {
    pub first_window_s: f64,
    pub flight_s: f64,
    pub ticks: u64,
    /// Ticks where the window did not hold every region within VIEW_REACH of the player's.
    pub ticks_unfilled: u64,
    pub scrolls: u64,
    /// Regions the scrolls wrote into the window.
    pub regions_scrolled: usize,
    /// The most bytes one tick's upload would write to the GPU, and all of them over the flight.
    pub upload_max: u64,
    pub upload_total: u64,
    /// Regions that arrived during the flight (the first window's not counted).
    pub regions_made: usize,
    pub longest_update_ms: f64,
    /// Of the longest tick, the time the main thread ran (the rest it waited for a core).
    pub longest_update_on_cpu_ms: f64,
    /// The longest of each part of a tick: following (streaming, scrolling), lighting, staging the upload.
    pub longest_parts_ms: [f64; 3],
    pub resident_min: usize,
    pub resident_max: usize,
    /// Process resident bytes: the most in the flight's first minute (or all of it, if shorter), the most
    /// after it, and at the end.
    pub rss_first_minute: u64,
    pub rss_after: u64,
    pub rss_end: u64,
    /// The grid's GPU bytes (`world_gpu_bytes`) likewise.
    pub gpu_first_minute: u64,
    pub gpu_after: u64,
}

fn region_at(p: DVec2) -> IVec2 {
    EndlessGenerator::region_of(p.x.floor() as i32, p.y.floor() as i32)
}

pub fn run_travel(config: &TravelConfig) -> Result<TravelReport, String> {
    let generator = Arc::new(EndlessGenerator::new(config.seed, DEFAULT_HEIGHT)?);
    let start_point =
        generator.village_site(IVec2::ZERO).map_or(DVec2::ZERO, |s| DVec2::new(s.centre.0 as f64, s.centre.1 as f64));
    let mut report = TravelReport { resident_min: usize::MAX, ..Default::default() };
    let begin = Instant::now();
    let first = region_at(start_point);
    let (mut follower, window) = WindowFollower::start(generator, first, WINDOW_REGIONS, RADIUS, config.workers);
    let (mut world, min) = (window.world, window.min);
    let mut lights = LightPool::from_world(&world);
    let mut window_lights = WindowLights::default();
    let mut uploads = UploadState::default();
    stage_upload(&mut world, &mut uploads);
    report.first_window_s = begin.elapsed().as_secs_f64();
    let local = |p: DVec2| Vec3::new((p.x - min.x as f64) as f32, 0.0, (p.y - min.y as f64) as f32);
    let flight = Instant::now();
    let seconds = config.distance / config.speed;
    let mut next_tick = Instant::now();
    loop {
        let t = flight.elapsed().as_secs_f64();
        let at = start_point + config.direction * config.speed * t.min(seconds);
        let tick = Instant::now();
        let cpu_at_tick = thread_cpu_ms().unwrap_or(0.0);
        let followed = follower.follow(&mut world, local(at), WRITE_BUDGET);
        let followed_at = Instant::now();
        window_lights.followed(&mut lights, &world, &followed);
        window_lights.update(&mut lights, &world, LIGHT_BUDGET);
        let lit_at = Instant::now();
        report.scrolls += u64::from(followed.finished.is_some());
        report.regions_scrolled += followed.regions_written;
        let bytes = stage_upload(&mut world, &mut uploads).bytes();
        let ms = |a: Instant, b: Instant| (b - a).as_secs_f64() * 1e3;
        let parts = [ms(tick, followed_at), ms(followed_at, lit_at), ms(lit_at, Instant::now())];
        for (longest, part) in report.longest_parts_ms.iter_mut().zip(parts) {
            *longest = longest.max(part);
        }
        let tick_ms = tick.elapsed().as_secs_f64() * 1e3;
        if tick_ms > report.longest_update_ms {
            report.longest_update_ms = tick_ms;
            report.longest_update_on_cpu_ms = thread_cpu_ms().map_or(f64::NAN, |end| end - cpu_at_tick);
        }
        report.upload_max = report.upload_max.max(bytes);
        report.upload_total += bytes;
        report.regions_made += followed.stream.arrived;
        report.ticks += 1;
        report.ticks_unfilled += u64::from(!window_reaches(&follower, &world, region_at(at)));
        report.resident_min = report.resident_min.min(follower.resident_count());
        report.resident_max = report.resident_max.max(follower.resident_count());
        let rss = resident_bytes().unwrap_or(0);
        let gpu = world_gpu_bytes(&world);
        if t < 60.0 {
            report.rss_first_minute = report.rss_first_minute.max(rss);
            report.gpu_first_minute = report.gpu_first_minute.max(gpu);
        } else {
            report.rss_after = report.rss_after.max(rss);
            report.gpu_after = report.gpu_after.max(gpu);
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

/// Whether the window holds every region within VIEW_REACH of region `here`.
fn window_reaches(follower: &WindowFollower, world: &crate::world::VoxelWorld, here: IVec2) -> bool {
    let first = follower.centre(world) - WINDOW_REGIONS / 2;
    let last = first + WINDOW_REGIONS - 1;
    (here - VIEW_REACH).cmpge(first).all() && (here + VIEW_REACH).cmple(last).all()
}

/// The time the calling thread has run, in ms (`CLOCK_THREAD_CPUTIME_ID`; Linux only, else `None`).
fn thread_cpu_ms() -> Option<f64> {
    #[cfg(all(target_os = "linux", target_env = "gnu", target_pointer_width = "64"))]
    {
        #[repr(C)]
        struct Timespec {
            seconds: i64,
            nanoseconds: i64,
        }
        unsafe extern "C" {
            fn clock_gettime(clock: i32, time: *mut Timespec) -> i32;
        }
        const CLOCK_THREAD_CPUTIME_ID: i32 = 3;
        let mut time = Timespec { seconds: 0, nanoseconds: 0 };
        // SAFETY: `time` is a valid, writable timespec for the call's duration.
        let ok = unsafe { clock_gettime(CLOCK_THREAD_CPUTIME_ID, &mut time) } == 0;
        ok.then(|| time.seconds as f64 * 1e3 + time.nanoseconds as f64 / 1e6)
    }
    #[cfg(not(all(target_os = "linux", target_env = "gnu", target_pointer_width = "64")))]
    None
}

pub fn travel_markdown(config: &TravelConfig, r: &TravelReport) -> String {
    let mb = |b: u64| b as f64 / 1e6;
    let edge = WINDOW_REGIONS * REGION_EDGE;
    format!(
        "# Travel: the endless world streamed around a straight flight\n\n\
         Seed {}, from the first village, {:.0} voxels at {:.0} voxels/s in direction ({:.2}, {:.2}), real time \
         at 60 ticks a second; {} worker threads; regions of {REGION_EDGE} x {DEFAULT_HEIGHT} x {REGION_EDGE}; the \
         game's window of {WINDOW_REGIONS} x {WINDOW_REGIONS} regions ({edge} voxels across) scrolling after the \
         player, fed by regions made {RADIUS} regions each side of it; the view reach the window must hold: \
         {VIEW_REACH} regions each side. Main thread: streaming, scrolling, the light pool and staging the GPU \
         upload (no GPU: the bytes are what the renderer would write).\n\n\
         | measure | value |\n|---|---|\n\
         | first window ({} regions) made in | {:.2} s |\n\
         | flight | {:.1} s, {} ticks |\n\
         | regions made during the flight | {} ({:.1} a second) |\n\
         | scrolls / regions they wrote | {} / {} |\n\
         | ticks with the view reach outside the window | {} |\n\
         | longest main-thread time on the window in a tick (of it on a core) | {:.2} ms ({:.2} ms) |\n\
         | longest following / lighting / staging the upload | {:.2} / {:.2} / {:.2} ms |\n\
         | GPU upload: most in a tick / mean a tick | {:.2} MB / {:.1} KB |\n\
         | resident regions (the streamer's) | {} - {} |\n\
         | resident memory: first minute / after / end | {:.0} / {:.0} / {:.0} MB |\n\
         | the grid's GPU bytes: first minute / after | {:.1} / {:.1} MB |\n",
        config.seed,
        config.distance,
        config.speed,
        config.direction.x,
        config.direction.y,
        config.workers,
        WINDOW_REGIONS.pow(2),
        r.first_window_s,
        r.flight_s,
        r.ticks,
        r.regions_made,
        r.regions_made as f64 / r.flight_s.max(1e-9),
        r.scrolls,
        r.regions_scrolled,
        r.ticks_unfilled,
        r.longest_update_ms,
        r.longest_update_on_cpu_ms,
        r.longest_parts_ms[0],
        r.longest_parts_ms[1],
        r.longest_parts_ms[2],
        mb(r.upload_max),
        r.upload_total as f64 / r.ticks.max(1) as f64 / 1e3,
        r.resident_min,
        r.resident_max,
        mb(r.rss_first_minute),
        mb(r.rss_after),
        mb(r.rss_end),
        mb(r.gpu_first_minute),
        mb(r.gpu_after),
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
