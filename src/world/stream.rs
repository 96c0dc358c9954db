//! Regions of the endless world kept resident around a moving point: the ones within `radius` regions of it are
//! made on worker threads, nearest first, and the ones that fall more than a region outside it are dropped. The
//! main thread only hands out the wanted list and takes finished regions (`update`), so what it waits on is a
//! lock and a few map operations, never the generator.
//!
//! Regions a player changed are kept (`keep`): they stay resident wherever the point goes and are never made
//! again, so a region edited, left behind and come back to holds the edits. Where regions come from is the
//! maker's business (`with_maker`): the generator, or a save folder over it.

use super::VoxelWorld;
use super::generate::endless::EndlessGenerator;
use bevy::math::IVec2;
use std::collections::{HashMap, HashSet, VecDeque};
use std::sync::mpsc::{Receiver, Sender, channel};
use std::sync::{Arc, Condvar, Mutex};
use std::thread::JoinHandle;

/// What the workers share with the main thread: the regions wanted, nearest first.
#[derive(Default)]
struct Queue {
    wanted: VecDeque<IVec2>,
    stop: bool,
}

type Shared = Arc<(Mutex<Queue>, Condvar)>;

/// Makes region `key` on a worker thread.
pub type MakeRegion = Arc<dyn Fn(IVec2) -> VoxelWorld + Send + Sync>;

/// The resident regions around a point, made in the background.
pub struct RegionStreamer {
    radius: i32,
    resident: HashMap<IVec2, VoxelWorld>,
    /// Regions changed in play, resident whatever the point's distance (`keep`).
    kept: HashMap<IVec2, VoxelWorld>,
    /// Handed to a worker or waiting in the queue.
    requested: HashSet<IVec2>,
    queue: Shared,
    finished: Receiver<(IVec2, VoxelWorld)>,
    workers: Vec<JoinHandle<()>>,
}

/// What one `update` did.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct StreamStep {
    pub arrived: usize,
    pub dropped: usize,
    /// The regions no longer wanted: dropped, or made after they stopped being wanted (a client tells its server
    /// it no longer holds them).
    pub let_go: Vec<IVec2>,
}

impl RegionStreamer {
    /// Keeps the regions within `radius` of the point resident, made by `threads` workers.
    pub fn new(generator: Arc<EndlessGenerator>, radius: i32, threads: usize) -> Self {
        Self::with_maker(Arc::new(move |key| generator.region(key)), radius, threads)
    }

    /// Keeps the regions within `radius` of the point resident, each made by `make` on one of `threads` workers.
    pub fn with_maker(make: MakeRegion, radius: i32, threads: usize) -> Self {
        let queue: Shared = Arc::new((Mutex::new(Queue::default()), Condvar::new()));
        let (done, finished) = channel();
        let workers = (0..threads.max(1))
            .map(|_| {
                let (queue, done, make) = (queue.clone(), done.clone(), make.clone());
                std::thread::spawn(move || {
                    yield_to_the_game();
                    work(&queue, &done, &*make)
                })
            })
            .collect();
        RegionStreamer {
            radius: radius.max(0),
            resident: HashMap::new(),
            kept: HashMap::new(),
            requested: HashSet::new(),
            queue,
            finished,
            workers,
        }
    }

    /// Takes the regions finished since the last call, drops those more than a region outside the window
    /// around `centre` (a region key), and asks for the missing ones, nearest first.
    pub fn update(&mut self, centre: IVec2) -> StreamStep {
        let mut step = StreamStep::default();
        let keep = self.radius + 1;
        let inside = |key: IVec2, reach: i32| (key - centre).abs().max_element() <= reach;
        while let Ok((key, region)) = self.finished.try_recv() {
            self.requested.remove(&key);
            if inside(key, keep) && !self.kept.contains_key(&key) {
                self.resident.insert(key, region);
                step.arrived += 1;
            } else if !self.kept.contains_key(&key) {
                step.let_go.push(key);
            }
        }
        let before = self.resident.len();
        self.resident.retain(|&key, _| {
            let stays = inside(key, keep);
            if !stays {
                step.let_go.push(key);
            }
            stays
        });
        step.dropped = before - self.resident.len();
        let r = self.radius;
        let mut missing: Vec<IVec2> = (-r..=r)
            .flat_map(|z| (-r..=r).map(move |x| centre + IVec2::new(x, z)))
            .filter(|key| !self.resident.contains_key(key) && !self.kept.contains_key(key))
            .collect();
        missing.sort_by_key(|key| (*key - centre).length_squared());
        let (lock, wake) = &*self.queue;
        let mut queue = lock.lock().unwrap_or_else(|e| e.into_inner());
        // The queue is this frame's wish list: what is no longer wanted leaves it, what a worker holds stays held.
        for key in queue.wanted.drain(..) {
            self.requested.remove(&key);
        }
        for key in missing {
            if self.requested.insert(key) {
                queue.wanted.push_back(key);
            }
        }
        drop(queue);
        wake.notify_all();
        step
    }

    /// Whether every region within `reach` regions of `centre` is resident.
    pub fn filled(&self, centre: IVec2, reach: i32) -> bool {
        (-reach..=reach).all(|z| (-reach..=reach).all(|x| self.region(centre + IVec2::new(x, z)).is_some()))
    }

    /// A resident region: the kept one where there is one.
    pub fn region(&self, key: IVec2) -> Option<&VoxelWorld> {
        self.kept.get(&key).or_else(|| self.resident.get(&key))
    }

    /// Keeps `region` as region `key` from now on, in place of what was made.
    pub fn keep(&mut self, key: IVec2, region: VoxelWorld) {
        self.resident.remove(&key);
        self.kept.insert(key, region);
    }

    /// The kept regions.
    pub fn kept(&self) -> impl Iterator<Item = (IVec2, &VoxelWorld)> {
        self.kept.iter().map(|(&key, region)| (key, region))
    }

    /// Forgets every kept region (a save was loaded over them).
    pub fn forget_kept(&mut self) {
        self.kept.clear();
    }

    pub fn resident_count(&self) -> usize {
        self.resident.len() + self.kept.len()
    }
}

impl Drop for RegionStreamer {
    fn drop(&mut self) {
        let (lock, wake) = &*self.queue;
        lock.lock().unwrap_or_else(|e| e.into_inner()).stop = true;
        wake.notify_all();
        for worker in self.workers.drain(..) {
            let _ = worker.join();
        }
    }
}

/// Lowers the calling thread's scheduling priority (Linux: nice 10), so that where the workers and the game share
/// too few cores, the game's frame is not the one kept waiting. Elsewhere it does nothing.
fn yield_to_the_game() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        unsafe extern "C" {
            fn gettid() -> i32;
            fn setpriority(which: i32, who: u32, prio: i32) -> i32;
        }
        const PRIO_PROCESS: i32 = 0;
        // SAFETY: both take and return plain integers; on Linux a thread id names one thread for setpriority.
        unsafe {
            setpriority(PRIO_PROCESS, gettid() as u32, 10);
        }
    }
}

/// A worker: takes the nearest wanted region, makes it, sends it back; sleeps while nothing is wanted.
fn work(queue: &Shared, done: &Sender<(IVec2, VoxelWorld)>, make: &(dyn Fn(IVec2) -> VoxelWorld + Send + Sync)) {
    let (lock, wake) = &**queue;
    loop {
        let key = {
            let mut queue = lock.lock().unwrap_or_else(|e| e.into_inner());
            loop {
                if queue.stop {
                    return;
                }
                if let Some(key) = queue.wanted.pop_front() {
                    break key;
                }
                queue = wake.wait(queue).unwrap_or_else(|e| e.into_inner());
            }
        };
        if done.send((key, make(key))).is_err() {
            return;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use bevy::math::IVec3;
    use std::time::{Duration, Instant};

    fn wait_until(streamer: &mut RegionStreamer, centre: IVec2, reach: i32) {
        let start = Instant::now();
        while !streamer.filled(centre, reach) {
            assert!(start.elapsed() < Duration::from_secs(60), "the window around {centre} never filled");
            streamer.update(centre);
            std::thread::sleep(Duration::from_millis(2));
        }
    }

    #[test]
    fn the_window_fills_follows_the_point_and_drops_what_it_left() {
        let generator = Arc::new(EndlessGenerator::new(2, 48).unwrap());
        let mut streamer = RegionStreamer::new(generator.clone(), 2, 2);
        wait_until(&mut streamer, IVec2::ZERO, 2);
        assert_eq!(streamer.resident_count(), 25);
        // A region made in the background is the region made in the foreground.
        let key = IVec2::new(1, -2);
        let made = generator.region(key);
        let resident = streamer.region(key).unwrap();
        let all = |world: &VoxelWorld| world.grid.read_box(IVec3::ZERO, world.grid.size().as_ivec3());
        assert_eq!(all(resident), all(&made));
        // Five regions east: the new column fills, and what is more than a region behind goes.
        let east = IVec2::new(5, 0);
        wait_until(&mut streamer, east, 2);
        let step = streamer.update(east);
        assert_eq!(step.arrived, 0);
        assert!(streamer.region(IVec2::new(-2, 0)).is_none() && streamer.region(IVec2::new(2, 0)).is_some());
        assert!(streamer.resident_count() <= 35, "{} resident", streamer.resident_count());
    }

    #[test]
    fn a_kept_region_stays_whatever_the_point_does_and_is_never_made_again() {
        let generator = Arc::new(EndlessGenerator::new(2, 48).unwrap());
        let mut streamer = RegionStreamer::new(generator.clone(), 1, 2);
        wait_until(&mut streamer, IVec2::ZERO, 1);
        let key = IVec2::new(1, 0);
        let mut edited = generator.region(key);
        edited.grid.set(IVec3::new(3, 40, 5), 7).unwrap();
        streamer.keep(key, edited);
        // Far away and back: the region is the edited one, not the generator's made again.
        wait_until(&mut streamer, IVec2::new(9, 0), 1);
        assert!(streamer.region(key).is_some(), "kept while the point is far");
        wait_until(&mut streamer, IVec2::ZERO, 1);
        std::thread::sleep(Duration::from_millis(50));
        streamer.update(IVec2::ZERO);
        assert_eq!(streamer.region(key).unwrap().grid.get(IVec3::new(3, 40, 5)), 7);
        assert_eq!(streamer.kept().count(), 1);
        streamer.forget_kept();
        assert!(streamer.region(key).is_none(), "forgotten, and made again on the next update");
    }
}
