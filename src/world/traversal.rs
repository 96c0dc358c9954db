//! CPU ray traversal, two ways to the same hits (Amanatides & Woo DDAs): `trace`, over bricks then the voxels of
//! pooled bricks, one load per step; and `trace_occupancy`, over the occupancy hierarchy of the brick grid
//! (`world::occupancy`), jumping empty cells of 128, 32, 8 and 2 voxels and reading voxels only inside occupied 2^3
//! cells. `shaders/lib/traversal.wgsl` mirrors both step for step (the `traversal` setting picks), so the GPU and
//! CPU agree per pixel; keep them in sync.
//!
//! Conventions shared by both: `t` is distance along the unit direction; every boundary crossing is computed as
//! `(plane - origin) / dir` from the ray's own origin (never accumulated), so both sides round the same way; the
//! hit face is the face the ray entered through; a ray starting inside a solid voxel hits it at `t = 0`.

use super::grid::{BRICK_SIZE, BRICK_VOXELS, BrickCell, BrickGrid, Voxel, local_index};
use super::occupancy::{TOP_LEVEL, child_bit, has_child};
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
    /// A cell of `level` visited (`world::occupancy`: 0 voxel, 2 brick).
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
    pub levels: [u64; TOP_LEVEL + 1],
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

/// Where a ray enters the world: the clipped parameter range and the axis of the face it entered through, or
/// `None` when it misses the world (or is not finite).
fn enter_world(size: Vec3, ray: &Ray, max_distance: f32) -> Option<(f32, f32, usize)> {
    if ray.dir == Vec3::ZERO || !ray.origin.is_finite() || !ray.dir.is_finite() {
        return None;
    }
    let (t_enter, t_exit, enter_axis) = box_entry(ray, Vec3::ZERO, size);
    let t_end = t_exit.min(max_distance);
    let t = t_enter.max(0.0);
    if t > t_end {
        return None;
    }
    // The face through which the ray entered the current cell; a ray starting inside the world uses the axis of
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
/// One flat loop over the occupancy hierarchy (`world::occupancy`): at level `level` the ray is in the cell holding
/// voxel `v`; an occupied cell is entered (the level below, `v` re-found from the ray at `t` and clamped into the
/// cell), an empty one left through its nearest face, going up as many levels as that face closes. Every face is
/// a voxel boundary computed as in the plain DDA, and ties go to the first axis, so the hits are the DDA's save
/// where a ray grazes an edge within rounding of `origin + dir * t`.
pub fn trace_occupancy_counted(grid: &BrickGrid, ray: &Ray, max_distance: f32, tally: &mut impl Tally) -> Option<Hit> {
    let size = grid.size().as_ivec3();
    let (mut t, t_end, mut axis) = enter_world(size.as_vec3(), ray, max_distance)?;
    let inv = inverse_dir(ray.dir);
    let positive = [ray.dir.x > 0.0, ray.dir.y > 0.0, ray.dir.z > 0.0];
    let occupancy = grid.occupancy();
    let last = size - IVec3::ONE;
    let mut v = ray.at(t).floor().as_ivec3().clamp(IVec3::ZERO, last);
    let mut level = TOP_LEVEL;
    // masks[l]: the child mask of the level-l cell the ray is in (valid while it stays there).
    let mut masks = [0u64; TOP_LEVEL + 1];
    let mut slot = 0u32;
    // Every move crosses at least one voxel boundary and is followed by at most TOP_LEVEL descents.
    let max_steps = (TOP_LEVEL as i32 + 1) * (size.x + size.y + size.z) + 8;
    for _ in 0..max_steps {
        tally.step(level);
        let shift = level_shift(level);
        let edge = 1 << shift;
        let lo = v & !(edge - 1);
        let occupied = match level {
            0 => {
                tally.load();
                let material = grid.pool()[slot as usize * BRICK_VOXELS + local_index(v & 7_i32)];
                if material != 0 {
                    return Some(Hit { voxel: v, face: Face::entered(axis, positive[axis]), distance: t, material });
                }
                false
            }
            TOP_LEVEL => {
                tally.load();
                masks[TOP_LEVEL] = occupancy.region(v);
                masks[TOP_LEVEL] != 0
            }
            _ => has_child(masks[level + 1], child_bit(v, level)),
        };
        if occupied {
            // Into the cell: the voxel the ray is in at t, within the cell.
            let hi = (lo + IVec3::splat(edge - 1)).min(last);
            v = ray.at(t).floor().as_ivec3().clamp(lo, hi);
            match level {
                3 => {
                    tally.load();
                    masks[3] = occupancy.sector(v);
                }
                2 => {
                    tally.load();
                    let index = grid.brick_index(v >> 3_i32);
                    match BrickCell::decode(grid.top_cell(index)) {
                        BrickCell::Homogeneous(material) => {
                            let face = Face::entered(axis, positive[axis]);
                            return Some(Hit { voxel: v, face, distance: t, material });
                        }
                        BrickCell::Pooled(s) => slot = s,
                        // The sector said otherwise; never with masks kept current.
                        BrickCell::Empty => {}
                    }
                    tally.load();
                    masks[2] = occupancy.brick(index);
                }
                _ => {}
            }
            level -= 1;
            continue;
        }
        // Out of the cell through the face the ray reaches first.
        let mut t_max = Vec3::ZERO;
        for a in 0..3 {
            t_max[a] = cross_t(ray, inv, a, (lo[a] + if positive[a] { edge } else { 0 }) as f32);
        }
        let a = min_axis(t_max);
        t = t_max[a];
        if t > t_end {
            return None;
        }
        axis = a;
        let before = v[a];
        v[a] = if positive[a] { lo[a] + edge } else { lo[a] - 1 };
        if v[a] < 0 || v[a] > last[a] {
            return None;
        }
        level = level_after_move(level, before, v[a]);
    }
    None
}

/// log2 of the cell edge of `level` (`LEVEL_SHIFTS`, as arithmetic: 0, 1, 3, 5, 7).
#[inline]
fn level_shift(level: usize) -> i32 {
    (2 * level as i32 - 1).max(0)
}

/// The level after a move along one axis from coordinate `before` to `after` (both in the world) at `level`: up
/// as many levels as the crossed face closes, i.e. to the first level whose cells hold the two coordinates'
/// highest differing bit (bit h lies inside level l's cells while h < `level_shift(l + 1)` = 2 l + 1).
#[inline]
fn level_after_move(level: usize, before: i32, after: i32) -> usize {
    let h = 31 - ((before ^ after) as u32).leading_zeros() as usize;
    level.max(h.div_ceil(2).min(TOP_LEVEL))
}

/// Finds the first solid voxel along `ray` within `max_distance`: the two-level DDA (bricks, skipping empty and
/// stopping at homogeneous ones, then the voxels of pooled bricks), one load per step.
#[inline]
pub fn trace(grid: &BrickGrid, ray: &Ray, max_distance: f32) -> Option<Hit> {
    trace_counted(grid, ray, max_distance, &mut NoTally)
}

/// `trace`, telling `tally` its steps (each one load).
pub fn trace_counted(grid: &BrickGrid, ray: &Ray, max_distance: f32, tally: &mut impl Tally) -> Option<Hit> {
    let (mut t, t_end, mut axis) = enter_world(grid.size().as_vec3(), ray, max_distance)?;
    let inv = inverse_dir(ray.dir);
    let step = ray.dir.signum().as_ivec3();
    let positive = [ray.dir.x > 0.0, ray.dir.y > 0.0, ray.dir.z > 0.0];
    let brick_edge = BRICK_SIZE as f32;
    let last_brick = ((grid.size().as_ivec3() - IVec3::ONE) >> 3_i32).max(IVec3::ZERO);
    let start = ray.at(t);
    let mut brick = (start / brick_edge).floor().as_ivec3().clamp(IVec3::ZERO, last_brick);
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
                let voxel = clamp_into_brick(ray.at(t).floor().as_ivec3(), brick).min(grid.size().as_ivec3() - 1);
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
        if brick[a] < 0 || brick[a] > last_brick[a] {
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
    let hi = (lo + IVec3::splat(BRICK_SIZE)).min(grid.size().as_ivec3()) - IVec3::ONE;
    let mut voxel = ray.at(t).floor().as_ivec3().clamp(lo, hi);
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
    use crate::world::occupancy::LEVEL_SHIFTS;

    /// The arithmetic forms the loop uses are the table's shifts and the level-by-level climb.
    #[test]
    fn level_arithmetic_matches_the_table() {
        for (level, &shift) in LEVEL_SHIFTS.iter().enumerate() {
            assert_eq!(level_shift(level), shift);
        }
        for level in 0..=TOP_LEVEL {
            for before in 0..600 {
                for after in [before - 1, before + 1, before + 2, before + 8, before - 32] {
                    if after < 0 || after == before {
                        continue;
                    }
                    let mut climbed = level;
                    while climbed < TOP_LEVEL
                        && (after >> LEVEL_SHIFTS[climbed + 1]) != (before >> LEVEL_SHIFTS[climbed + 1])
                    {
                        climbed += 1;
                    }
                    assert_eq!(level_after_move(level, before, after), climbed, "{level} {before} -> {after}");
                }
            }
        }
    }
}
