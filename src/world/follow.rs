//! An endless world's resident window following the player (issue 69): the regions around the player are made
//! in the background (`world::stream`), and once the player is a scroll step (two regions, 128 voxels) from the
//! window's centre and the regions that would enter are made, the window scrolls (`BrickGrid::scroll_window`):
//! only those regions are written, over the storage of the ones that left.

use super::VoxelWorld;
use super::format::LoadError;
use super::generate::endless::{EndlessGenerator, REGION_EDGE, Window};
use super::grid::{BRICK_SIZE, BrickGrid, WINDOW_STEP};
use super::stream::{RegionStreamer, StreamStep};
use bevy::math::{IVec2, IVec3, Vec3};
use std::sync::Arc;
use std::time::{Duration, Instant};

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
        BrickGrid::check_scroll(grid.size(), lo).map_err(|e| LoadError {
            location: "the endless world's window".into(),
            message: e.to_string(),
        })?;
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
        let mut streamer = RegionStreamer::new(generator.clone(), radius.max(regions / 2), workers);
        loop {
            streamer.update(centre);
            if let Some(window) = generator.window_of(centre, regions, |key| streamer.region(key)) {
                let min = window.min;
                return (WindowFollower { streamer, min, under_way: None }, window);
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        }
    }

    /// The world key of the region holding `at` (window coordinates).
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
                && world.grid.begin_scroll(plan.lo).is_ok()
            {
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
            followed.finished = self.under_way.take().map(|(plan, _)| plan);
        }
        followed
    }

    pub fn resident_count(&self) -> usize {
        self.streamer.resident_count()
    }
}
