//! CPU ray traversal, two ways to the same hits (Amanatides & Woo DDAs): `trace`, over bricks then the voxels of
//! pooled bricks, one load per step; and `trace_occupancy`, over the occupancy hierarchy of the brick grid
//! (`world::occupancy`), leaving in one step the coarsest empty cell of 128 down to 2 voxels its masks prove empty,
//! testing voxels only inside occupied 2^3 cells, mostly through bits of a voxel mask.
//! `shaders/lib/traversal.wgsl` mirrors both step for step (the `traversal` setting picks), so the GPU and CPU
//! agree per pixel; keep them in sync.
//!
//! Conventions shared by both: `t` is distance along the unit direction; every boundary crossing is computed as
//! `(plane - origin) / dir` from the ray's own origin (never accumulated), so both sides round the same way; the
//! hit face is the face the ray entered through; a ray starting inside a solid voxel hits it at `t = 0`.

use super::grid::{AIR, BRICK_SIZE, BrickCell, BrickGrid, Voxel, local_index};
use super::occupancy::{
    BRICK_SHIFT, CELL_BOX_LEVEL, CELL_SHIFT, SECTOR_SHIFT, TOP_WALK_LEVEL, WALK_LEVELS, box_bits, box3_bits, has_child,
    voxel_word_bit,
};
use bevy::math::{IVec3, Vec3};

/// Secondary rays start this far off the surface they leave (the GPU passes use the same, as
/// `1.0 / RAY_OFFSET_INVERSE`: a quotient of two exact values, so both sides get the same f32).
pub const RAY_OFFSET_INVERSE: u32 = 1000;
pub const RAY_OFFSET: f32 = 1.0 / RAY_OFFSET_INVERSE as f32;

/// A voxel face, by outward normal: +X, -X, +Y, -Y, +Z, -Z (index 0..6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Face(pub u8);

impl Face {
    /// The face of `axis` whose normal points against a ray going in direction sign `dir_sign`.
    pub fn entered(axis: usize, dir_positive: bool) -> Face {
        Face(axis as u8 * 2 + dir_positive as u8)
    }

    pub fn axis(self) -> usize {
        (self.0 / 2) as usize
    }

    pub fn normal(self) -> IVec3 {
        let mut n = IVec3::ZERO;
        n[self.axis()] = if self.0.is_multiple_of(2) { 1 } else { -1 };
        n
    }

    pub const ALL: [Face; 6] = [Face(0), Face(1), Face(2), Face(3), Face(4), Face(5)];
}

/// A ray with a unit direction.
#[derive(Clone, Copy, Debug)]
pub struct Ray {
    pub origin: Vec3,
    pub dir: Vec3,
}

impl Ray {
    /// A ray from `origin` towards `dir` (normalised here; a zero direction gives a ray that hits nothing).
    /// A ray along `dir` normalised. Components below 1e-20 become 0: their reciprocal would be infinite, and
    /// infinity times zero (an origin on a boundary plane) NaN; the GPU flushes such values to zero as well.
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        let dir = dir.normalize_or_zero();
        let dir = Vec3::select(dir.abs().cmplt(Vec3::splat(1e-20)), Vec3::ZERO, dir);
        Ray { origin, dir }
    }

    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.dir * t
    }
}

/// The first solid voxel along a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub voxel: IVec3,
    pub face: Face,
    pub distance: f32,
    pub material: Voxel,
}

/// Per-axis slab parameters of a ray: `1 / dir` (infinite on zero components).
fn inverse_dir(dir: Vec3) -> Vec3 {
    Vec3::new(
        if dir.x != 0.0 { 1.0 / dir.x } else { f32::INFINITY },
        if dir.y != 0.0 { 1.0 / dir.y } else { f32::INFINITY },
        if dir.z != 0.0 { 1.0 / dir.z } else { f32::INFINITY },
    )
}

/// Ray parameter where the ray crosses plane `plane` of `axis` (infinite when parallel).
#[inline]
fn cross_t(ray: &Ray, inv: Vec3, axis: usize, plane: f32) -> f32 {
    if ray.dir[axis] == 0.0 { f32::INFINITY } else { (plane - ray.origin[axis]) * inv[axis] }
}

/// Entry into the axis-aligned box `[lo, hi]`: `(t_enter, t_exit, axis of t_enter)`; `t_enter > t_exit` on a miss.
/// The axis is the first (x, y, z order) whose near plane gives the largest entry parameter.
pub fn box_entry(ray: &Ray, lo: Vec3, hi: Vec3) -> (f32, f32, usize) {
    let inv = inverse_dir(ray.dir);
    let mut t_enter = f32::NEG_INFINITY;
    let mut t_exit = f32::INFINITY;
    let mut axis = 0;
    for a in 0..3 {
        if ray.dir[a] == 0.0 {
            if ray.origin[a] < lo[a] || ray.origin[a] > hi[a] {
                return (f32::INFINITY, f32::NEG_INFINITY, 0);
            }
            continue;
        }
        let (near, far) = if ray.dir[a] > 0.0 { (lo[a], hi[a]) } else { (hi[a], lo[a]) };
        let t0 = (near - ray.origin[a]) * inv[a];
        let t1 = (far - ray.origin[a]) * inv[a];
        if t0 > t_enter {
            t_enter = t0;
            axis = a;
        }
        t_exit = t_exit.min(t1);
    }
    (t_enter, t_exit, axis)
}

/// What one trace did, for the benches: loop steps (a move to the next cell at some level, or a descent into an
/// occupied one) and memory loads (mask words, top cells and voxels; a bit test of a mask a ray already holds is
/// not a load).
pub trait Tally {
    /// A cell of `level` visited (`world::occupancy::WALK_LEVELS`: 0 voxel, 3 brick).
    fn step(&mut self, level: usize);
    fn load(&mut self);
}

/// Counts nothing: the game's and the reference's traces.
pub struct NoTally;

impl Tally for NoTally {
    #[inline(always)]
    fn step(&mut self, _level: usize) {}
    #[inline(always)]
    fn load(&mut self) {}
}

/// Counts steps and loads.
#[derive(Clone, Copy, Debug, Default)]
pub struct Counts {
    pub rays: u64,
    pub steps: u64,
    pub loads: u64,
    /// Steps by level.
    pub levels: [u64; WALK_LEVELS],
}

impl Tally for Counts {
    #[inline(always)]
    fn step(&mut self, level: usize) {
        self.steps += 1;
        self.levels[level] += 1;
    }
    #[inline(always)]
    fn load(&mut self) {
        self.loads += 1;
    }
}

/// Where a ray enters the grid's window: the clipped parameter range and the axis of the face it entered
/// through, or `None` when it misses the window (or is not finite).
fn enter_world(grid: &BrickGrid, ray: &Ray, max_distance: f32) -> Option<(f32, f32, usize)> {
    let (lo, hi) = grid.window();
    enter_box(lo.as_vec3(), hi.as_vec3(), ray, max_distance)
}

/// Where a ray enters the box `[lo, hi]` (voxel planes), as `enter_world`.
fn enter_box(lo: Vec3, hi: Vec3, ray: &Ray, max_distance: f32) -> Option<(f32, f32, usize)> {
    if ray.dir == Vec3::ZERO || !ray.origin.is_finite() || !ray.dir.is_finite() {
        return None;
    }
    let (t_enter, t_exit, enter_axis) = box_entry(ray, lo, hi);
    let t_end = t_exit.min(max_distance);
    let t = t_enter.max(0.0);
    if t > t_end {
        return None;
    }
    // The face through which the ray entered the current cell; a ray starting inside the box uses the axis of
    // its voxel's entry, as `box_entry` reports for a box around the origin.
    let mut axis = enter_axis;
    if t_enter < 0.0 {
        let v = ray.origin.floor();
        axis = box_entry(ray, v, v + Vec3::ONE).2;
    }
    Some((t, t_end, axis))
}

/// The first solid voxel along `ray` within `max_distance`, found through the occupancy hierarchy: the same hit
/// as `trace` save where the ray grazes an edge within rounding.
#[inline]
pub fn trace_occupancy(grid: &BrickGrid, ray: &Ray, max_distance: f32) -> Option<Hit> {
    trace_occupancy_counted(grid, ray, max_distance, &mut NoTally)
}

/// `trace_occupancy`, telling `tally` its steps and loads.
///
/// One move per loop step: the ray is in voxel `v` at `t`; the step finds the coarsest cell holding `v` that the
/// masks prove empty (`WALK_LEVELS`: a region, a box of sectors, a sector, a box of bricks, a brick, a box of
/// 2^3 cells, a 2^3 cell, a voxel; a box is the 3^3 or else the 2^3 children of a mask reaching ahead of the ray's
/// own child, else its aligned 2^3 group; below a region every test is a bit test of a mask the ray holds) and
/// leaves that cell through its nearest face. A mask is loaded only when the ray enters a new region, sector or
/// pooled brick (a ray that starts in an occupied brick reads its brick's mask first and the coarser ones only when
/// it leaves it); a brick's top cell only when a voxel of it must be tested; in each 4^3 quadrant of a brick, the
/// first voxel tested, then the quadrant's word of the voxel mask, then a material only at the hit. Rays start
/// and end in the box of occupied bricks (`BrickGrid::occupied_box`). Every face is a voxel boundary computed as
/// in the plain DDA, and ties go to the first axis, so the hits are the DDA's save where a ray grazes an edge
/// within rounding of `origin + dir * t`.
pub fn trace_occupancy_counted(grid: &BrickGrid, ray: &Ray, max_distance: f32, tally: &mut impl Tally) -> Option<Hit> {
    let size = grid.size().as_ivec3();
    let window_hi = grid.window().1;
    // Nothing solid lies outside the occupied box: a ray starts where it enters it and misses where it leaves.
    let (box_lo, box_hi) = grid.occupied_box();
    if box_hi.cmple(box_lo).any() {
        return None;
    }
    let (mut t, t_end, mut axis) = enter_box(box_lo.as_vec3(), box_hi.as_vec3(), ray, max_distance)?;
    let inv = inverse_dir(ray.dir);
    let positive = [ray.dir.x > 0.0, ray.dir.y > 0.0, ray.dir.z > 0.0];
    let occupancy = grid.occupancy();
    let mut v = voxel_at(ray.at(t)).clamp(box_lo, box_hi - IVec3::ONE);
    // The masks of the region and sector the ray is in, valid from the level at which they were last loaded down;
    // `entered`: the coarsest walk level whose cell the last move changed (its masks and those below are stale).
    let (mut region_mask, mut sector_mask) = (0u64, 0u64);
    // The pool slot of the brick the ray is in, once read; the word of its voxel mask the ray holds (its
    // quadrant, `NO_QUADRANT` before one is read) and the quadrant whose first voxel it read.
    let mut slot = None::<u32>;
    let (mut quadrant, mut quadrant_mask, mut probed) = (NO_QUADRANT, 0u64, NO_QUADRANT);
    // A ray that starts in an occupied brick (as one leaving a surface does) reads that brick's mask first: it
    // needs its sector's and region's masks only once it leaves the brick (`*_unread` until then).
    tally.load();
    let mut brick = grid.brick_index(v >> BRICK_SHIFT);
    let mut brick_mask = occupancy.brick(brick);
    let starts_in_brick = brick_mask != 0;
    let (mut region_unread, mut sector_unread) = (starts_in_brick, starts_in_brick);
    let mut entered = if starts_in_brick { CELL_BOX_LEVEL } else { TOP_WALK_LEVEL };
    // Every step crosses at least one voxel boundary.
    let max_steps = size.x + size.y + size.z + 8;
    let bounds = CellExit { ray, inv, positive, t_end, box_lo, box_hi, last: window_hi - IVec3::ONE };
    'walk: for _ in 0..max_steps {
        // The level of the coarsest empty cell holding v. A mask's tests are skipped while the ray stays in the
        // child it last proved occupied: a move that left a cell of a sector's size or more crossed a sector's
        // face (so `entered` < 5 means the last step found the sector occupied), and likewise for bricks.
        let (level, lo, edge) = 'empty: {
            if entered >= 5 {
                if entered >= 7 || region_unread {
                    tally.load();
                    region_mask = occupancy.region(v);
                    region_unread = false;
                }
                if region_mask == 0 {
                    break 'empty (7, v & !127, 128);
                }
                if let Some(cell) = empty_child_cell(region_mask, v, SECTOR_SHIFT, positive) {
                    break 'empty cell;
                }
                // A mask not loaded since the ray entered its cell: the steps since then left coarser empty cells.
                tally.load();
                sector_mask = occupancy.sector(v);
                sector_unread = false;
            }
            if entered >= 3 {
                if sector_unread {
                    tally.load();
                    sector_mask = occupancy.sector(v);
                    sector_unread = false;
                }
                if let Some(cell) = empty_child_cell(sector_mask, v, BRICK_SHIFT, positive) {
                    break 'empty cell;
                }
                // The brick's mask first: its top cell (homogeneous, or the pool slot) is read only where the mask
                // cannot tell (every cell solid) or a voxel must be read.
                tally.load();
                brick = grid.brick_index(v >> BRICK_SHIFT);
                brick_mask = occupancy.brick(brick);
                slot = None;
                (quadrant, probed) = (NO_QUADRANT, NO_QUADRANT);
            }
            if let Some(cell) = empty_child_cell(brick_mask, v, CELL_SHIFT, positive) {
                break 'empty cell;
            }
            let s = match slot {
                Some(s) => s,
                None => {
                    tally.load();
                    match BrickCell::decode(grid.top_cell(brick)) {
                        BrickCell::Homogeneous(material) => {
                            tally.step(0);
                            return Some(Hit {
                                voxel: v,
                                face: Face::entered(axis, positive[axis]),
                                distance: t,
                                material,
                            });
                        }
                        BrickCell::Pooled(s) => s,
                        // The mask said otherwise (never with masks kept current): leave it as the empty brick.
                        BrickCell::Empty => break 'empty (3, v & !7, 8),
                    }
                }
            };
            slot = Some(s);
            // Inside an occupied 2^3 cell: a plain voxel DDA until the ray leaves the cell (at most 4 voxels), the
            // moves the walk would make one loop step each. The first voxel tested in a 4^3 quadrant of the brick
            // is read (often the hit); past it the quadrant's word of the voxel mask is loaded, so the voxels
            // after it are bit tests and a material is read only at the hit.
            let (voxel_mask, voxels) = (grid.voxel_mask(s), grid.pool_brick(s));
            loop {
                let local = v & 7_i32;
                let (word, bit) = voxel_word_bit(local);
                tally.step(0);
                let material = if word == quadrant || word == probed {
                    if word != quadrant {
                        tally.load();
                        (quadrant, quadrant_mask) = (word, voxel_mask[word]);
                    }
                    if has_child(quadrant_mask, bit) {
                        tally.load();
                        voxels[local_index(local)]
                    } else {
                        AIR
                    }
                } else {
                    probed = word;
                    tally.load();
                    voxels[local_index(local)]
                };
                if material != AIR {
                    return Some(Hit { voxel: v, face: Face::entered(axis, positive[axis]), distance: t, material });
                }
                let voxel = v;
                (t, axis, entered) = bounds.leave(&mut v, voxel, 1)?;
                if entered > 0 {
                    continue 'walk;
                }
            }
        };
        tally.step(level);
        (t, axis, entered) = bounds.leave(&mut v, lo, edge)?;
    }
    None
}

/// No voxel mask word held yet (`occupancy::voxel_word_bit` gives 0..8).
const NO_QUADRANT: usize = usize::MAX;

/// What a ray needs to leave a cell: its parameters, where it ends, and the box it walks in.
struct CellExit<'a> {
    ray: &'a Ray,
    inv: Vec3,
    positive: [bool; 3],
    t_end: f32,
    box_lo: IVec3,
    box_hi: IVec3,
    /// The window's last voxel.
    last: IVec3,
}

impl CellExit<'_> {
    /// Moves voxel `v` out of the cell `[lo, lo + edge)` through the face the ray reaches first. Returns the
    /// parameter there, the axis crossed and the coarsest walk level whose cell `v` changed; `None` past `t_end`
    /// or out of the box.
    #[inline(always)]
    fn leave(&self, v: &mut IVec3, lo: IVec3, edge: i32) -> Option<(f32, usize, usize)> {
        let mut t_max = Vec3::ZERO;
        for a in 0..3 {
            t_max[a] = cross_t(self.ray, self.inv, a, (lo[a] + if self.positive[a] { edge } else { 0 }) as f32);
        }
        let a = min_axis(t_max);
        let t = t_max[a];
        if t > self.t_end {
            return None;
        }
        let before = v[a];
        let moved = if self.positive[a] { lo[a] + edge } else { lo[a] - 1 };
        if moved < self.box_lo[a] || moved >= self.box_hi[a] {
            return None;
        }
        if edge > 1 {
            // v's other axes are the ray's only to the cell's precision: the voxel the ray is in at t, within the
            // cell's extent on every axis but a.
            *v = voxel_at(self.ray.at(t)).clamp(lo, (lo + IVec3::splat(edge - 1)).min(self.last));
        }
        v[a] = moved;
        Some((t, a, (31 - ((before ^ moved) as u32).leading_zeros()) as usize))
    }
}

/// The coarsest empty cell below 4^3-child mask `m` that holds voxel `v` (children of edge `1 << child_shift`,
/// whose walk level is `child_shift`), as its level, low corner and edge: the 3^3 children reaching ahead of the
/// ray's child on every axis, else the 2^3 reaching ahead, else its aligned 2^3 group (each counted one level up),
/// else its child; `None` when the child is occupied. A box need not be aligned, or a power of two: the ray leaves
/// it as any cell, through voxel planes.
#[inline(always)]
fn empty_child_cell(m: u64, v: IVec3, child_shift: i32, positive: [bool; 3]) -> Option<(usize, IVec3, i32)> {
    let c = (v >> child_shift) & 3;
    let node = v & !((4 << child_shift) - 1);
    let (mut ahead3, mut ahead) = (c, c);
    for a in 0..3 {
        ahead3[a] = if positive[a] { c[a].min(1) } else { (c[a] - 2).max(0) };
        ahead[a] = if positive[a] { c[a].min(2) } else { (c[a] - 1).max(0) };
    }
    let up = child_shift as usize + 1;
    if m & box3_bits(ahead3) == 0 {
        return Some((up, node + (ahead3 << child_shift), 3 << child_shift));
    }
    if m & box_bits(ahead) == 0 {
        return Some((up, node + (ahead << child_shift), 2 << child_shift));
    }
    // The aligned group, unless it is the box just tested.
    let aligned = c & 2;
    if aligned != ahead && m & box_bits(aligned) == 0 {
        return Some((up, v & !((2 << child_shift) - 1), 2 << child_shift));
    }
    if !has_child(m, (c.x + 4 * (c.y + 4 * c.z)) as u32) {
        return Some((child_shift as usize, v & !((1 << child_shift) - 1), 1 << child_shift));
    }
    None
}

/// Finds the first solid voxel along `ray` within `max_distance`: the two-level DDA (bricks, skipping empty and
/// stopping at homogeneous ones, then the voxels of pooled bricks), one load per step.
#[inline]
pub fn trace(grid: &BrickGrid, ray: &Ray, max_distance: f32) -> Option<Hit> {
    trace_counted(grid, ray, max_distance, &mut NoTally)
}

/// `trace`, telling `tally` its steps (each one load).
pub fn trace_counted(grid: &BrickGrid, ray: &Ray, max_distance: f32, tally: &mut impl Tally) -> Option<Hit> {
    let (mut t, t_end, mut axis) = enter_world(grid, ray, max_distance)?;
    let inv = inverse_dir(ray.dir);
    let step = ray.dir.signum().as_ivec3();
    let positive = [ray.dir.x > 0.0, ray.dir.y > 0.0, ray.dir.z > 0.0];
    let brick_edge = BRICK_SIZE as f32;
    let (window_lo, window_hi) = grid.window();
    let first_brick = window_lo >> 3_i32;
    let last_brick = ((window_hi - IVec3::ONE) >> 3_i32).max(first_brick);
    let start = ray.at(t);
    let mut brick = voxel_at(start / brick_edge).clamp(first_brick, last_brick);
    let mut brick_t_max = Vec3::ZERO;
    for a in 0..3 {
        let plane = (brick[a] + positive[a] as i32) as f32 * brick_edge;
        brick_t_max[a] = cross_t(ray, inv, a, plane);
    }

    loop {
        tally.step(2);
        tally.load();
        match grid.cell(brick) {
            BrickCell::Empty => {}
            BrickCell::Homogeneous(material) => {
                let voxel = clamp_into_brick(voxel_at(ray.at(t)), brick).min(window_hi - 1);
                return Some(Hit { voxel, face: Face::entered(axis, positive[axis]), distance: t, material });
            }
            BrickCell::Pooled(slot) => {
                if let Some(hit) = trace_in_brick(grid, slot, ray, inv, brick, t, t_end, axis, tally) {
                    return Some(hit);
                }
            }
        }
        // Step to the next brick along the axis whose boundary comes first.
        let a = min_axis(brick_t_max);
        t = brick_t_max[a];
        if t > t_end {
            return None;
        }
        axis = a;
        brick[a] += step[a];
        if brick[a] < first_brick[a] || brick[a] > last_brick[a] {
            return None;
        }
        brick_t_max[a] = cross_t(ray, inv, a, (brick[a] + positive[a] as i32) as f32 * brick_edge);
    }
}

/// Voxel DDA inside one pooled brick (pool slot `slot`), starting at parameter `t` where the ray entered it
/// through `axis`. Its voxels are read from the slot directly: each step is one load, not a top-grid lookup.
#[allow(clippy::too_many_arguments)]
fn trace_in_brick(
    grid: &BrickGrid,
    slot: u32,
    ray: &Ray,
    inv: Vec3,
    brick: IVec3,
    mut t: f32,
    t_end: f32,
    mut axis: usize,
    tally: &mut impl Tally,
) -> Option<Hit> {
    let step = ray.dir.signum().as_ivec3();
    let positive = [ray.dir.x > 0.0, ray.dir.y > 0.0, ray.dir.z > 0.0];
    let lo = brick * BRICK_SIZE;
    let hi = (lo + IVec3::splat(BRICK_SIZE)).min(grid.window().1) - IVec3::ONE;
    let mut voxel = voxel_at(ray.at(t)).clamp(lo, hi);
    let voxels = grid.pool_brick(slot);
    let mut t_max = Vec3::ZERO;
    for a in 0..3 {
        t_max[a] = cross_t(ray, inv, a, (voxel[a] + positive[a] as i32) as f32);
    }
    loop {
        tally.step(0);
        tally.load();
        let material = voxels[local_index(voxel - lo)];
        if material != 0 {
            return Some(Hit { voxel, face: Face::entered(axis, positive[axis]), distance: t, material });
        }
        let a = min_axis(t_max);
        t = t_max[a];
        if t > t_end {
            return None;
        }
        axis = a;
        voxel[a] += step[a];
        if voxel[a] < lo[a] || voxel[a] > hi[a] {
            return None;
        }
        t_max[a] = cross_t(ray, inv, a, (voxel[a] + positive[a] as i32) as f32);
    }
}

/// The voxel holding point `p`: `p.floor().as_ivec3()` without a call per component (without SSE4.1 `f32::floor`
/// is a library call, and the occupancy walk takes three every step).
#[inline]
fn voxel_at(p: Vec3) -> IVec3 {
    let floor = |x: f32| {
        // Truncation saturates as `as_ivec3` does (NaN gives 0); below a negative non-integer it is one too high.
        let i = x as i32;
        i.saturating_sub((x < i as f32) as i32)
    };
    IVec3::new(floor(p.x), floor(p.y), floor(p.z))
}

/// The axis of the smallest component; ties go to the first in x, y, z order.
#[inline]
fn min_axis(v: Vec3) -> usize {
    if v.x <= v.y && v.x <= v.z {
        0
    } else if v.y <= v.z {
        1
    } else {
        2
    }
}

fn clamp_into_brick(voxel: IVec3, brick: IVec3) -> IVec3 {
    let lo = brick * BRICK_SIZE;
    voxel.clamp(lo, lo + IVec3::splat(BRICK_SIZE - 1))
}

/// Brute-force reference: tests every solid voxel's box and keeps the nearest entry. For tests only; cost grows
/// with the number of solid voxels.
pub fn trace_brute_force(grid: &BrickGrid, ray: &Ray, max_distance: f32) -> Option<Hit> {
    let mut best: Option<Hit> = None;
    grid.for_each_solid(|p, material| {
        let lo = p.as_vec3();
        let (t0, t1, axis) = box_entry(ray, lo, lo + Vec3::ONE);
        if t0 > t1 || t1 < 0.0 {
            return;
        }
        let t = t0.max(0.0);
        if t > max_distance {
            return;
        }
        if best.is_none_or(|b| t < b.distance) {
            let face = Face::entered(axis, ray.dir[axis] > 0.0);
            best = Some(Hit { voxel: p, face, distance: t, material });
        }
    });
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn voxel_at_is_the_floor() {
        let xs = [-1e10, -2147483904.0, -3.5, -1.0, -0.25, -0.0, 0.0, 0.5, 1.0, 7.999, 2147483648.0, 1e10];
        for x in xs.into_iter().chain([f32::NAN, f32::INFINITY, f32::NEG_INFINITY]) {
            let p = Vec3::new(x, x + 0.5, -x);
            assert_eq!(voxel_at(p), p.floor().as_ivec3(), "{p}");
        }
    }
}
