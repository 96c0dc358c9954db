//! The light pool following an endless world's scrolling window (`world::follow`): the lamps of the regions that
//! leave are let go as a scroll begins (their slots' generations move on), and the regions that entered are lit
//! a few at a time once it is done, so no tick pays for a whole strip of the world. The window's sides, where a
//! lamp that was inside now borders air, are looked at again the same way, in pieces.

use super::{LightPool, window_sides};
use crate::world::VoxelWorld;
use crate::world::follow::Followed;
use crate::world::generate::endless::REGION_EDGE;
use bevy::math::IVec3;
use std::collections::VecDeque;
use std::time::{Duration, Instant};

/// The height of the boxes a finished scroll's regions are lit in: a whole region with crystals is too long a
/// step for one tick's budget (docs/world.md).
const SLAB: i32 = 16;
/// The length of the pieces a window's side is looked at again in.
const SIDE_PIECE: i32 = 128;

/// A tick's time for lighting the regions a scroll brought in.
pub const LIGHT_BUDGET: Duration = Duration::from_millis(2);

/// The boxes of a finished scroll still to be lit: each region in slabs of `SLAB` voxels' height.
#[derive(Default)]
pub struct WindowLights {
    queue: VecDeque<(IVec3, IVec3)>,
}

impl WindowLights {
    /// Takes in what one `WindowFollower::follow` did.
    pub fn followed(&mut self, pool: &mut LightPool, world: &VoxelWorld, followed: &Followed) {
        if followed.began.is_some() {
            pool.drop_outside_window(world);
            self.queue_sides(world);
        }
        if let Some(plan) = &followed.finished {
            pool.drop_outside_window(world);
            self.queue_sides(world);
            for &(lo, hi) in &plan.entered {
                for z in (lo.z..hi.z).step_by(REGION_EDGE as usize) {
                    for x in (lo.x..hi.x).step_by(REGION_EDGE as usize) {
                        for y in (lo.y..hi.y).step_by(SLAB as usize) {
                            let a = IVec3::new(x, y, z);
                            self.queue.push_back((a, (a + IVec3::new(REGION_EDGE, SLAB, REGION_EDGE)).min(hi)));
                        }
                    }
                }
            }
        }
    }

    /// Queues the window's four sides, in pieces.
    fn queue_sides(&mut self, world: &VoxelWorld) {
        for (lo, hi) in window_sides(world) {
            let long = if hi.x > lo.x { IVec3::X } else { IVec3::Z };
            let (from, to) = (lo.dot(long), hi.dot(long));
            for start in (from..=to).step_by(SIDE_PIECE as usize) {
                let end = (start + SIDE_PIECE - 1).min(to);
                let a = lo + long * (start - lo.dot(long));
                let b = hi + long * (end - hi.dot(long));
                self.queue.push_back((a, b + IVec3::ONE));
            }
        }
    }

    /// Lights queued regions until `budget` is spent (one at least, when any waits); returns how many.
    pub fn update(&mut self, pool: &mut LightPool, world: &VoxelWorld, budget: Duration) -> usize {
        let begin = Instant::now();
        let mut done = 0;
        while let Some((lo, hi)) = self.queue.pop_front() {
            pool.update_region(world, lo, hi - IVec3::ONE);
            done += 1;
            if begin.elapsed() >= budget {
                break;
            }
        }
        done
    }

    /// Regions still to be lit.
    pub fn waiting(&self) -> usize {
        self.queue.len()
    }
}
