//! An endless world's resident window following the player (issue 69): the regions around the player are made
//! in the background (`world::stream`), and once the player is a scroll step (two regions, 128 voxels) from the
//! window's centre and the regions that would enter are made, the window scrolls (`BrickGrid::scroll_window`):
//! only those regions are written, over the storage of the ones that left.
//!
//! The player's edits follow too: a region edited in the window is copied out as it leaves and kept by the
//! streamer (never made again), and `changed_regions` hands a save every region changed since the last one.

use super::VoxelWorld;
use super::format::LoadError;
use super::generate::endless::{EndlessGenerator, REGION_EDGE, Window};
use super::grid::{BRICK_SIZE, BrickGrid, WINDOW_STEP};
use super::stream::{MakeRegion, RegionStreamer, StreamStep};
use bevy::math::{IVec2, IVec3, UVec3, Vec3};
use std::collections::HashSet;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// The game's window's edge in regions: 1024 voxels.
pub const WINDOW_REGIONS: i32 = 16;
/// Regions each side of the player's that stay resident: a scroll step past the window's half, so the regions a
/// scroll takes in are made before it.
pub const STREAM_RADIUS: i32 = WINDOW_REGIONS / 2 + SCROLL_REGIONS;
/// A tick's time for writing the regions of a scroll under way.
pub const WRITE_BUDGET: Duration = Duration::from_millis(3);

/// The region workers the game and the travel bench run: one a core. They run below the game's priority
/// (`world::stream`), so they take what the frame leaves; at top speed on 2 cores the flight needs both.
pub fn stream_workers() -> usize {
    std::thread::available_parallelism().map_or(2, |n| n.get())
}

/// Regions a scroll moves the window by, on an axis: the occupancy hierarchy's coarsest cell.
pub const SCROLL_REGIONS: i32 = WINDOW_STEP / REGION_EDGE;

/// A window's move to the regions around region `centre`: where it will start and the regions that enter it.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct ScrollPlan {
    /// The window's new lowest voxel, in its coordinates.
    pub lo: IVec3,
    /// The world keys of the regions that enter, in the order `apply` writes them.
    pub keys: Vec<IVec2>,
    /// The boxes of voxels (window coordinates) they fill.
    pub entered: Vec<(IVec3, IVec3)>,
}

impl ScrollPlan {
    /// The move of `world`'s window (its coordinates' column (0, 0) at world column `detail_origin`, a multiple
    /// of the region edge) to the regions around region `centre`; refused where it is not a whole step.
    pub fn new(world: &VoxelWorld, centre: IVec2) -> Result<Self, LoadError> {
        let grid = &world.grid;
        let min = IVec2::new(world.detail_origin.x, world.detail_origin.z);
        let regions = grid.size().x as i32 / REGION_EDGE;
        let lo = (centre - regions / 2) * REGION_EDGE - min;
        let lo = IVec3::new(lo.x, 0, lo.y);
        BrickGrid::check_scroll(grid.size(), lo)
            .map_err(|e| LoadError { location: "the endless world's window".into(), message: e.to_string() })?;
        let entered = BrickGrid::entered_boxes(grid.size(), grid.window().0, lo);
        let edge = IVec3::splat(REGION_EDGE);
        let keys = entered
            .iter()
            .flat_map(|&(a, b)| {
                let (a, b) = (a.div_euclid(edge), b.div_euclid(edge));
                (a.z..b.z).flat_map(move |z| (a.x..b.x).map(move |x| IVec2::new(x, z)))
            })
            .map(|key| key + min.div_euclid(IVec2::splat(REGION_EDGE)))
            .collect();
        Ok(ScrollPlan { lo, keys, entered })
    }

    /// Scrolls `world`'s window at once and writes each region that entered from `region(key)`, which must give
    /// every key of the plan (else nothing changes and the missing key is the error).
    pub fn apply<'a>(
        &self,
        world: &mut VoxelWorld,
        region: impl Fn(IVec2) -> Option<&'a BrickGrid>,
    ) -> Result<(), LoadError> {
        let sources: Vec<&BrickGrid> = self
            .keys
            .iter()
            .map(|&key| region(key).ok_or_else(|| window_error(format!("region {key} is not made yet"))))
            .collect::<Result<_, _>>()?;
        world.grid.begin_scroll(self.lo).map_err(|e| window_error(e.to_string()))?;
        for (&key, source) in self.keys.iter().zip(sources) {
            write_region(world, key, source);
        }
        world.grid.finish_scroll();
        Ok(())
    }
}

fn window_error(message: String) -> LoadError {
    LoadError { location: "the endless world's window".into(), message }
}

/// Writes region `key` (world key) from `source` into `world`'s storage, brick by brick.
fn write_region(world: &mut VoxelWorld, key: IVec2, source: &BrickGrid) {
    let min = world.detail_origin;
    let at = IVec3::new(key.x * REGION_EDGE - min.x, 0, key.y * REGION_EDGE - min.z) / BRICK_SIZE;
    let dims = source.brick_dims().as_ivec3();
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let b = IVec3::new(x, y, z);
                world.grid.put_brick(at + b, source, b);
            }
        }
    }
}

/// An endless world's window that follows a moving point.
pub struct WindowFollower {
    streamer: RegionStreamer,
    /// The world column of the window's coordinates' column (0, 0).
    min: IVec2,
    /// A scroll under way (`BrickGrid::begin_scroll`): its plan and how many of its regions are written.
    under_way: Option<(ScrollPlan, usize)>,
    /// Regions edited since they last entered the window: copied out (kept) as they leave.
    edited_in_window: HashSet<IVec2>,
    /// Regions changed since the last save.
    unsaved: HashSet<IVec2>,
    /// The generator's palette's length: the window's palette starts with it.
    generator_materials: usize,
}

/// A window being started: its first regions are being made. `poll` hands over the window and its follower
/// once they are, without waiting (a client whose regions come from its server keeps its tick going meanwhile).
pub struct WindowStart {
    generator: Arc<EndlessGenerator>,
    streamer: RegionStreamer,
    centre: IVec2,
    regions: i32,
}

impl WindowStart {
    /// Starts making a window of `regions` x `regions` regions around region `centre`, its follower keeping
    /// regions `radius` regions around the point, made by `make` on `workers` threads.
    pub fn new(
        generator: Arc<EndlessGenerator>,
        make: MakeRegion,
        centre: IVec2,
        regions: i32,
        radius: i32,
        workers: usize,
    ) -> Self {
        let streamer = RegionStreamer::with_maker(make, radius.max(regions / 2), workers);
        WindowStart { generator, streamer, centre, regions }
    }

    /// The window and its follower once every region of the window is made (the window is made of the
    /// streamer's regions, so none is made twice); else itself, to poll again.
    pub fn poll(mut self) -> Result<(WindowFollower, Window), Self> {
        self.streamer.update(self.centre);
        let Some(window) = self.generator.window_of(self.centre, self.regions, |key| self.streamer.region(key)) else {
            return Err(self);
        };
        let follower = WindowFollower {
            streamer: self.streamer,
            min: window.min,
            under_way: None,
            edited_in_window: HashSet::new(),
            unsaved: HashSet::new(),
            generator_materials: window.world.palette.materials.len(),
        };
        Ok((follower, window))
    }

    /// Regions of the window made so far, of `regions` squared.
    pub fn made(&self) -> usize {
        self.streamer.resident_count()
    }
}

/// What `follow` did in one call.
#[derive(Clone, Debug, Default)]
pub struct Followed {
    pub stream: StreamStep,
    /// A scroll it began: the window shrank to what the old and new windows share.
    pub began: Option<ScrollPlan>,
    /// Regions of the scroll under way it wrote (outside the window, unseen until the scroll is done).
    pub regions_written: usize,
    /// The scroll it finished: the window is the new one, its entered boxes to be lit (`LightPool`).
    pub finished: Option<ScrollPlan>,
}

impl WindowFollower {
    /// A window of `regions` x `regions` regions around region `centre` and its follower, which keeps regions
    /// `radius` regions around the point made by `workers` threads. The window is made of the streamer's first
    /// regions (so none is made twice); this waits until they are there.
    pub fn start(
        generator: Arc<EndlessGenerator>,
        centre: IVec2,
        regions: i32,
        radius: i32,
        workers: usize,
    ) -> (Self, Window) {
        let make: MakeRegion = {
            let generator = generator.clone();
            Arc::new(move |key| generator.region(key))
        };
        Self::start_with(generator, make, centre, regions, radius, workers)
    }

    /// `start`, the regions made by `make` (a save folder over the generator, say).
    pub fn start_with(
        generator: Arc<EndlessGenerator>,
        make: MakeRegion,
        centre: IVec2,
        regions: i32,
        radius: i32,
        workers: usize,
    ) -> (Self, Window) {
        let mut start = WindowStart::new(generator, make, centre, regions, radius, workers);
        loop {
            match start.poll() {
                Ok(ready) => return ready,
                Err(waiting) => start = waiting,
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }

    /// The world key of the region holding `at`    /// The world key of the region holding `at` (window coordinates).
    pub fn region_at(&self, at: Vec3) -> IVec2 {
        let p = at.floor().as_ivec3();
        EndlessGenerator::region_of(p.x + self.min.x, p.z + self.min.y)
    }

    /// The world key of the centre region of the window (of the one a scroll under way goes to).
    pub fn centre(&self, world: &VoxelWorld) -> IVec2 {
        let lo = world.grid.storage_box().0;
        let first = (self.min + IVec2::new(lo.x, lo.z)).div_euclid(IVec2::splat(REGION_EDGE));
        first + world.grid.size().x as i32 / REGION_EDGE / 2
    }

    /// One tick: streams the regions around `at` (window coordinates); where the point is a scroll step or more
    /// from the window's centre and every region that would enter is made, begins a scroll toward it; writes
    /// regions of the scroll under way until `budget` is spent (one at least), and finishes it once all are.
    /// A scroll so spread over ticks never shows a half-written region: they are outside the window until done.
    pub fn follow(&mut self, world: &mut VoxelWorld, at: Vec3, budget: Duration) -> Followed {
        let begin = Instant::now();
        let here = self.region_at(at);
        let mut followed = Followed { stream: self.streamer.update(here), ..Default::default() };
        if self.under_way.is_none() {
            let shift = (here - self.centre(world)) / SCROLL_REGIONS * SCROLL_REGIONS;
            if shift != IVec2::ZERO
                && let Ok(plan) = ScrollPlan::new(world, self.centre(world) + shift)
                && plan.keys.iter().all(|&key| self.streamer.region(key).is_some())
            {
                self.keep_leaving_edits(world, plan.lo);
                world.grid.begin_scroll(plan.lo).expect("ScrollPlan::new checked the step");
                followed.began = Some(plan.clone());
                self.under_way = Some((plan, 0));
            }
        }
        let Some((plan, written)) = &mut self.under_way else { return followed };
        while *written < plan.keys.len() {
            let key = plan.keys[*written];
            // A region dropped since the scroll began (the point turned back) is made again; the scroll waits.
            let Some(source) = self.streamer.region(key) else { break };
            write_region(world, key, &source.grid);
            *written += 1;
            followed.regions_written += 1;
            if begin.elapsed() >= budget {
                break;
            }
        }
        if *written == plan.keys.len() {
            world.grid.finish_scroll();
            // The regions the streamer dropped were freed on its workers' arenas, which glibc keeps otherwise;
            // trimming them takes milliseconds, so not on this thread.
            std::thread::spawn(crate::alloc_watch::return_freed_memory);
            followed.finished = self.under_way.take().map(|(plan, _)| plan);
        }
        followed
    }

    pub fn resident_count(&self) -> usize {
        self.streamer.resident_count()
    }

    /// The world column of the window's coordinates' column (0, 0).
    pub fn min(&self) -> IVec2 {
        self.min
    }

    /// Takes note of an edit of the window's voxels `lo..=hi` (window coordinates; clipped to the window, which
    /// is all an edit changes).
    pub fn note_edit(&mut self, world: &VoxelWorld, lo: IVec3, hi: IVec3) {
        let (window_lo, window_hi) = world.grid.window();
        let (lo, hi) = (lo.max(window_lo), hi.min(window_hi - IVec3::ONE));
        if lo.cmpgt(hi).any() {
            return;
        }
        let edge = IVec2::splat(REGION_EDGE);
        let a = (IVec2::new(lo.x, lo.z) + self.min).div_euclid(edge);
        let b = (IVec2::new(hi.x, hi.z) + self.min).div_euclid(edge);
        for z in a.y..=b.y {
            for x in a.x..=b.x {
                self.edited_in_window.insert(IVec2::new(x, z));
                self.unsaved.insert(IVec2::new(x, z));
            }
        }
    }

    /// Whether the window (as it shows now) holds region `key` whole.
    pub fn holds(&self, world: &VoxelWorld, key: IVec2) -> bool {
        let (lo, hi) = world.grid.window();
        let a = key * REGION_EDGE - self.min;
        let b = a + REGION_EDGE;
        a.x >= lo.x && a.y >= lo.z && b.x <= hi.x && b.y <= hi.z
    }

    /// Region `key` as the window holds it now, with the generator's palette: what the game adds to the palette
    /// later (moving objects' materials) is never in the grid, and a region file must hold the palette the
    /// generator's regions have to load.
    fn copy_out(&self, world: &VoxelWorld, key: IVec2) -> VoxelWorld {
        let size = UVec3::new(REGION_EDGE as u32, world.grid.size().y, REGION_EDGE as u32);
        let mut palette = world.palette.clone();
        palette.materials.truncate(self.generator_materials);
        let mut region = VoxelWorld::new(size, palette);
        let at = IVec3::new(key.x * REGION_EDGE - self.min.x, 0, key.y * REGION_EDGE - self.min.y) / BRICK_SIZE;
        let dims = region.grid.brick_dims().as_ivec3();
        for z in 0..dims.z {
            for y in 0..dims.y {
                for x in 0..dims.x {
                    let b = IVec3::new(x, y, z);
                    region.grid.put_brick(b, &world.grid, at + b);
                }
            }
        }
        region.grid.take_dirty();
        region
    }

    /// Copies the edited regions a scroll to `lo` takes out of the window to the streamer, which keeps them.
    fn keep_leaving_edits(&mut self, world: &VoxelWorld, lo: IVec3) {
        let size = world.grid.size().as_ivec3();
        let stays = |key: IVec2| {
            let a = key * REGION_EDGE - self.min;
            a.x >= lo.x && a.y >= lo.z && a.x + REGION_EDGE <= lo.x + size.x && a.y + REGION_EDGE <= lo.z + size.z
        };
        let leaving: Vec<IVec2> = self.edited_in_window.iter().copied().filter(|&key| !stays(key)).collect();
        for key in leaving {
            self.edited_in_window.remove(&key);
            if self.holds(world, key) {
                let region = self.copy_out(world, key);
                self.streamer.keep(key, region);
            }
        }
    }

    /// Every region changed since the last `saved`, as it is now (from the window where it holds it, else as
    /// kept), in key order.
    pub fn changed_regions(&self, world: &VoxelWorld) -> Vec<(IVec2, VoxelWorld)> {
        let mut keys: Vec<IVec2> = self.unsaved.iter().copied().collect();
        keys.sort_by_key(|k| (k.y, k.x));
        keys.into_iter()
            .filter_map(|key| {
                if self.holds(world, key) {
                    Some((key, self.copy_out(world, key)))
                } else {
                    self.streamer.region(key).map(|r| (key, r.clone()))
                }
            })
            .collect()
    }

    /// Marks `keys` saved.
    pub fn saved(&mut self, keys: &[IVec2]) {
        for key in keys {
            self.unsaved.remove(key);
        }
    }

    /// Regions changed since the last save.
    pub fn unsaved_count(&self) -> usize {
        self.unsaved.len()
    }
}
