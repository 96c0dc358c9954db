//! The brick grid (seed 000 §2.3, §4.1): a top grid of 8^3 bricks, each empty, homogeneous or pooled.
//!
//! Top cell encoding (shared with `shaders/lib/world.wgsl` through shader defs, see `render::gpu_types`):
//! - `0`: empty brick (all air),
//! - `1..=0xFFFF`: homogeneous brick of that material id,
//! - `POOLED_FLAG | slot`: the brick's 512 voxels live in pool slot `slot`.

use super::occupancy::{self, Occupancy, SOLID_BRICK, VOXEL_MASK_WORDS};
use bevy::math::{IVec3, UVec3};
use std::collections::BTreeSet;

/// Voxels per brick edge.
pub const BRICK_SIZE: i32 = 8;
/// Voxels per brick.
pub const BRICK_VOXELS: usize = 512;
/// Top-cell flag marking a pooled brick; the low bits are its pool slot.
pub const POOLED_FLAG: u32 = 0x8000_0000;
/// The largest world edge, in voxels, on every axis (the thesis scenes are 1027 wide; the top grid stays small).
pub const MAX_WORLD_EDGE: u32 = 2048;

/// A material id; 0 is air.
pub type Voxel = u16;
/// The air voxel.
pub const AIR: Voxel = 0;

/// What one top-grid cell holds, decoded.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum BrickCell {
    Empty,
    Homogeneous(Voxel),
    Pooled(u32),
}

impl BrickCell {
    pub fn decode(raw: u32) -> Self {
        if raw == 0 {
            BrickCell::Empty
        } else if raw & POOLED_FLAG != 0 {
            BrickCell::Pooled(raw & !POOLED_FLAG)
        } else {
            BrickCell::Homogeneous(raw as Voxel)
        }
    }

    pub fn encode(self) -> u32 {
        match self {
            BrickCell::Empty => 0,
            BrickCell::Homogeneous(m) => m as u32,
            BrickCell::Pooled(slot) => POOLED_FLAG | slot,
        }
    }
}

/// A world of voxels stored as a two-level grid with a pool of dense bricks.
#[derive(Clone, Debug)]
pub struct BrickGrid {
    /// World size in voxels (edits outside it are rejected; voxels outside it are air).
    size: UVec3,
    /// World size in bricks (size rounded up to whole bricks).
    bricks: UVec3,
    /// One encoded `BrickCell` per brick, x fastest, then y, then z.
    top: Vec<u32>,
    /// Dense bricks, `BRICK_VOXELS` voxels per slot, local index `x + 8 * (y + 8 * z)`.
    pool: Vec<Voxel>,
    /// Per pool slot, which of its voxels are solid (`occupancy::voxel_word_bit`), `VOXEL_MASK_WORDS` words a
    /// slot: a ray tests a voxel here and reads its material only when it is solid.
    voxel_masks: Vec<u64>,
    /// Pool slots no brick uses.
    free_slots: Vec<u32>,
    /// Brick indices whose top cell or pooled voxels changed since the last `take_dirty`.
    dirty: BTreeSet<u32>,
    /// Which cells of every level hold a solid voxel, kept current on every change (`world::occupancy`).
    occupancy: Occupancy,
}

/// An edit or lookup outside the world.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OutOfWorld {
    pub position: IVec3,
    pub size: UVec3,
}

impl std::fmt::Display for OutOfWorld {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "voxel ({}, {}, {}) is outside the world of {}x{}x{}",
            self.position.x, self.position.y, self.position.z, self.size.x, self.size.y, self.size.z
        )
    }
}

impl std::error::Error for OutOfWorld {}

/// Local index of a voxel inside its brick.
#[inline]
pub fn local_index(local: IVec3) -> usize {
    (local.x + BRICK_SIZE * (local.y + BRICK_SIZE * local.z)) as usize
}

impl BrickGrid {
    /// An all-air world. `size` must be within `1..=MAX_WORLD_EDGE` on every axis (checked by callers that take
    /// user input, see `world::format`); out-of-range sizes are clamped so this never panics.
    pub fn new(size: UVec3) -> Self {
        let size = size.clamp(UVec3::ONE, UVec3::splat(MAX_WORLD_EDGE));
        let bricks = (size + UVec3::splat(BRICK_SIZE as u32 - 1)) / BRICK_SIZE as u32;
        let cells = (bricks.x * bricks.y * bricks.z) as usize;
        BrickGrid {
            size,
            bricks,
            top: vec![0; cells],
            pool: Vec::new(),
            voxel_masks: Vec::new(),
            free_slots: Vec::new(),
            dirty: BTreeSet::new(),
            occupancy: Occupancy::new(bricks),
        }
    }

    pub fn size(&self) -> UVec3 {
        self.size
    }

    /// World size in bricks.
    pub fn brick_dims(&self) -> UVec3 {
        self.bricks
    }

    pub fn contains(&self, p: IVec3) -> bool {
        p.cmpge(IVec3::ZERO).all() && p.cmplt(self.size.as_ivec3()).all()
    }

    /// Index of the brick cell holding brick coordinate `b` (must be in range).
    #[inline]
    pub fn brick_index(&self, b: IVec3) -> usize {
        (b.x as u32 + self.bricks.x * (b.y as u32 + self.bricks.y * b.z as u32)) as usize
    }

    /// Brick coordinate of a brick index.
    pub fn brick_coord(&self, index: u32) -> IVec3 {
        let x = index % self.bricks.x;
        let y = (index / self.bricks.x) % self.bricks.y;
        let z = index / (self.bricks.x * self.bricks.y);
        IVec3::new(x as i32, y as i32, z as i32)
    }

    /// The decoded top cell of brick coordinate `b`, or `Empty` outside the grid.
    #[inline]
    pub fn cell(&self, b: IVec3) -> BrickCell {
        if b.cmplt(IVec3::ZERO).any() || b.cmpge(self.bricks.as_ivec3()).any() {
            return BrickCell::Empty;
        }
        BrickCell::decode(self.top[self.brick_index(b)])
    }

    /// The occupancy masks rays skip empty space with.
    #[inline]
    pub fn occupancy(&self) -> &Occupancy {
        &self.occupancy
    }

    /// The voxels `[lo, hi)` of the bricks that may hold a solid voxel (`Occupancy::occupied_bricks`), within the
    /// world; an empty box (`lo == hi`) when none does.
    pub fn occupied_box(&self) -> (IVec3, IVec3) {
        match self.occupancy.occupied_bricks() {
            Some((lo, hi)) => (lo * BRICK_SIZE, ((hi + 1) * BRICK_SIZE).min(self.size().as_ivec3())),
            None => (IVec3::ZERO, IVec3::ZERO),
        }
    }

    /// The raw top cell of brick index `i`.
    #[inline]
    pub fn top_cell(&self, i: usize) -> u32 {
        self.top[i]
    }

    /// Raw top grid, for GPU upload.
    pub fn top_cells(&self) -> &[u32] {
        &self.top
    }

    /// Raw brick pool (all slots, including free ones), for GPU upload.
    pub fn pool(&self) -> &[Voxel] {
        &self.pool
    }

    /// Voxels of one pool slot.
    pub fn pool_brick(&self, slot: u32) -> &[Voxel] {
        let start = slot as usize * BRICK_VOXELS;
        &self.pool[start..start + BRICK_VOXELS]
    }

    /// The voxel mask of pool slot `slot` (`occupancy::voxel_word_bit`).
    pub fn voxel_mask(&self, slot: u32) -> &[u64] {
        let start = slot as usize * VOXEL_MASK_WORDS;
        &self.voxel_masks[start..start + VOXEL_MASK_WORDS]
    }

    /// Every slot's voxel mask (free ones too), for GPU upload.
    pub fn voxel_masks(&self) -> &[u64] {
        &self.voxel_masks
    }

    /// Number of pool slots allocated (used or free).
    pub fn pool_capacity(&self) -> u32 {
        (self.pool.len() / BRICK_VOXELS) as u32
    }

    /// Number of pool slots in use.
    pub fn pooled_bricks(&self) -> u32 {
        self.pool_capacity() - self.free_slots.len() as u32
    }

    /// The voxel at `p`; air outside the world.
    #[inline]
    pub fn get(&self, p: IVec3) -> Voxel {
        if !self.contains(p) {
            return AIR;
        }
        match BrickCell::decode(self.top[self.brick_index(p >> 3_i32)]) {
            BrickCell::Empty => AIR,
            BrickCell::Homogeneous(m) => m,
            BrickCell::Pooled(slot) => self.pool[slot as usize * BRICK_VOXELS + local_index(p & 7_i32)],
        }
    }

    /// Sets one voxel; returns whether it changed. Marks its brick dirty when it does.
    pub fn set(&mut self, p: IVec3, voxel: Voxel) -> Result<bool, OutOfWorld> {
        if !self.contains(p) {
            return Err(OutOfWorld { position: p, size: self.size });
        }
        let index = self.brick_index(p >> 3_i32);
        let local = local_index(p & 7_i32);
        let slot = match BrickCell::decode(self.top[index]) {
            BrickCell::Empty if voxel == AIR => return Ok(false),
            BrickCell::Homogeneous(m) if m == voxel => return Ok(false),
            BrickCell::Empty => self.expand(index, AIR),
            BrickCell::Homogeneous(m) => self.expand(index, m),
            BrickCell::Pooled(slot) => {
                if self.pool[slot as usize * BRICK_VOXELS + local] == voxel {
                    return Ok(false);
                }
                slot
            }
        };
        self.pool[slot as usize * BRICK_VOXELS + local] = voxel;
        self.collapse_if_uniform(index, slot);
        self.update_cell_occupancy(index, p & 7_i32);
        self.dirty.insert(index as u32);
        Ok(true)
    }

    /// Whether the box `[min, max)` holds any voxel (`Ok(false)` when empty), or the corner outside the world.
    fn box_in_world(&self, min: IVec3, max: IVec3) -> Result<bool, OutOfWorld> {
        if max.cmple(min).any() {
            return Ok(false);
        }
        for corner in [min, max - IVec3::ONE] {
            if !self.contains(corner) {
                return Err(OutOfWorld { position: corner, size: self.size });
            }
        }
        Ok(true)
    }

    /// Fills the box `[min, max)`: `max` is exclusive and the whole box must lie inside the world (no clipping).
    /// Whole bricks covered by the box become homogeneous without touching the pool. Returns the number of voxels
    /// that changed.
    pub fn fill_box(&mut self, min: IVec3, max: IVec3, voxel: Voxel) -> Result<u64, OutOfWorld> {
        if !self.box_in_world(min, max)? {
            return Ok(0);
        }
        let mut changed = 0u64;
        let bmin = min >> 3_i32;
        let bmax = (max - IVec3::ONE) >> 3_i32;
        for bz in bmin.z..=bmax.z {
            for by in bmin.y..=bmax.y {
                for bx in bmin.x..=bmax.x {
                    let b = IVec3::new(bx, by, bz);
                    let lo = (b * BRICK_SIZE).max(min);
                    let hi = ((b + IVec3::ONE) * BRICK_SIZE).min(max);
                    changed += self.fill_in_brick(b, lo, hi, voxel);
                }
            }
        }
        Ok(changed)
    }

    /// The voxels of the box `[min, max)` (x fastest, then y, then z); air outside the world.
    pub fn read_box(&self, min: IVec3, max: IVec3) -> Vec<Voxel> {
        let e = (max - min).max(IVec3::ZERO);
        let mut out = Vec::with_capacity(e.x as usize * e.y as usize * e.z as usize);
        for z in min.z..max.z {
            for y in min.y..max.y {
                for x in min.x..max.x {
                    out.push(self.get(IVec3::new(x, y, z)));
                }
            }
        }
        out
    }

    /// Writes `voxels` (x fastest, then y, then z) into the box `[min, max)`, which must lie inside the world.
    /// Checks each touched brick for collapse once, not per voxel. Returns the number of voxels that changed.
    pub fn write_box(&mut self, min: IVec3, max: IVec3, voxels: &[Voxel]) -> Result<u64, OutOfWorld> {
        if !self.box_in_world(min, max)? {
            return Ok(0);
        }
        let e = max - min;
        let mut changed = 0u64;
        let mut touched = BTreeSet::new();
        for z in min.z..max.z {
            for y in min.y..max.y {
                for x in min.x..max.x {
                    let p = IVec3::new(x, y, z);
                    let q = p - min;
                    let v = voxels[(q.x + e.x * (q.y + e.y * q.z)) as usize];
                    if self.get(p) == v {
                        continue;
                    }
                    let index = self.brick_index(p >> 3_i32);
                    let slot = match BrickCell::decode(self.top[index]) {
                        BrickCell::Pooled(slot) => slot,
                        BrickCell::Empty => self.expand(index, AIR),
                        BrickCell::Homogeneous(m) => self.expand(index, m),
                    };
                    self.pool[slot as usize * BRICK_VOXELS + local_index(p & 7_i32)] = v;
                    touched.insert(index);
                    changed += 1;
                }
            }
        }
        for index in touched {
            if let BrickCell::Pooled(slot) = BrickCell::decode(self.top[index]) {
                self.collapse_if_uniform(index, slot);
            }
            self.update_occupancy(index);
            self.dirty.insert(index as u32);
        }
        Ok(changed)
    }

    /// Fills `[lo, hi)`, which lies inside brick `b`.
    fn fill_in_brick(&mut self, b: IVec3, lo: IVec3, hi: IVec3, voxel: Voxel) -> u64 {
        let index = self.brick_index(b);
        let whole = lo == b * BRICK_SIZE && hi == (b + IVec3::ONE) * BRICK_SIZE;
        let target = if voxel == AIR { BrickCell::Empty } else { BrickCell::Homogeneous(voxel) };
        let current = BrickCell::decode(self.top[index]);
        if current == target {
            return 0;
        }
        let count = |grid: &Self| -> u64 {
            let mut n = 0;
            for z in lo.z..hi.z {
                for y in lo.y..hi.y {
                    for x in lo.x..hi.x {
                        n += (grid.get(IVec3::new(x, y, z)) != voxel) as u64;
                    }
                }
            }
            n
        };
        let changed = count(self);
        if changed == 0 {
            return 0;
        }
        if whole {
            if let BrickCell::Pooled(slot) = current {
                self.free_slots.push(slot);
            }
            self.top[index] = target.encode();
        } else {
            let slot = match current {
                BrickCell::Empty => self.expand(index, AIR),
                BrickCell::Homogeneous(m) => self.expand(index, m),
                BrickCell::Pooled(slot) => slot,
            };
            let base = slot as usize * BRICK_VOXELS;
            for z in lo.z..hi.z {
                for y in lo.y..hi.y {
                    for x in lo.x..hi.x {
                        self.pool[base + local_index(IVec3::new(x, y, z) & 7_i32)] = voxel;
                    }
                }
            }
            self.collapse_if_uniform(index, slot);
        }
        self.update_occupancy(index);
        self.dirty.insert(index as u32);
        changed
    }

    /// Recomputes brick `index`'s occupancy mask from its cell (a pooled brick: its 512 voxels).
    fn update_occupancy(&mut self, index: usize) {
        let mask = match BrickCell::decode(self.top[index]) {
            BrickCell::Empty => 0,
            BrickCell::Homogeneous(_) => SOLID_BRICK,
            BrickCell::Pooled(slot) => {
                let words = occupancy::brick_voxel_mask(self.pool_brick(slot));
                let start = slot as usize * VOXEL_MASK_WORDS;
                self.voxel_masks[start..start + VOXEL_MASK_WORDS].copy_from_slice(&words);
                occupancy::cells_of_voxel_mask(&words)
            }
        };
        let b = self.brick_coord(index as u32);
        self.occupancy.set_brick(index, b, mask);
    }

    /// Updates brick `index`'s occupancy after one voxel (`local` inside it) changed: one bit of its voxel mask,
    /// then its cells from that mask, so a voxel edit stays a few words whatever the brick holds.
    fn update_cell_occupancy(&mut self, index: usize, local: IVec3) {
        let BrickCell::Pooled(slot) = BrickCell::decode(self.top[index]) else {
            return self.update_occupancy(index);
        };
        let (word, voxel_bit) = occupancy::voxel_word_bit(local);
        let word = &mut self.voxel_masks[slot as usize * VOXEL_MASK_WORDS + word];
        if self.pool[slot as usize * BRICK_VOXELS + local_index(local)] == AIR {
            *word &= !(1 << voxel_bit);
        } else {
            *word |= 1 << voxel_bit;
        }
        let mask = occupancy::cells_of_voxel_mask(self.voxel_mask(slot));
        let b = self.brick_coord(index as u32);
        self.occupancy.set_brick(index, b, mask);
    }

    /// Moves brick `index` from a uniform state into a pool slot filled with `voxel`; returns the slot.
    fn expand(&mut self, index: usize, voxel: Voxel) -> u32 {
        let slot = match self.free_slots.pop() {
            Some(slot) => slot,
            None => {
                self.pool.resize(self.pool.len() + BRICK_VOXELS, AIR);
                self.voxel_masks.resize(self.voxel_masks.len() + VOXEL_MASK_WORDS, 0);
                self.pool_capacity() - 1
            }
        };
        let base = slot as usize * BRICK_VOXELS;
        self.pool[base..base + BRICK_VOXELS].fill(voxel);
        let words = slot as usize * VOXEL_MASK_WORDS;
        self.voxel_masks[words..words + VOXEL_MASK_WORDS].fill(if voxel == AIR { 0 } else { u64::MAX });
        self.top[index] = BrickCell::Pooled(slot).encode();
        slot
    }

    /// Collapses a pooled brick whose voxels are all equal back into an empty or homogeneous cell.
    fn collapse_if_uniform(&mut self, index: usize, slot: u32) {
        let base = slot as usize * BRICK_VOXELS;
        let voxels = &self.pool[base..base + BRICK_VOXELS];
        let first = voxels[0];
        if voxels.iter().all(|&v| v == first) {
            self.top[index] = if first == AIR { 0 } else { first as u32 };
            self.free_slots.push(slot);
        }
    }

    /// Replaces a whole brick with the given 512 voxels (used by loaders); collapses uniform bricks.
    pub fn set_brick(&mut self, b: IVec3, voxels: &[Voxel; BRICK_VOXELS]) {
        let index = self.brick_index(b);
        let slot = match BrickCell::decode(self.top[index]) {
            BrickCell::Pooled(slot) => slot,
            _ => self.expand(index, AIR),
        };
        let base = slot as usize * BRICK_VOXELS;
        self.pool[base..base + BRICK_VOXELS].copy_from_slice(voxels);
        self.collapse_if_uniform(index, slot);
        self.update_occupancy(index);
        self.dirty.insert(index as u32);
    }

    /// The 512 voxels of brick `b`, expanded.
    pub fn brick_voxels(&self, b: IVec3) -> [Voxel; BRICK_VOXELS] {
        match self.cell(b) {
            BrickCell::Empty => [AIR; BRICK_VOXELS],
            BrickCell::Homogeneous(m) => [m; BRICK_VOXELS],
            BrickCell::Pooled(slot) => {
                let mut out = [AIR; BRICK_VOXELS];
                out.copy_from_slice(self.pool_brick(slot));
                out
            }
        }
    }

    /// Brick indices changed since the last call, in ascending order; clears the set.
    pub fn take_dirty(&mut self) -> Vec<u32> {
        std::mem::take(&mut self.dirty).into_iter().collect()
    }

    /// Brick indices changed since the last `take_dirty`, without clearing.
    pub fn dirty(&self) -> &BTreeSet<u32> {
        &self.dirty
    }

    /// Iterates over every solid voxel as (position, material); cost follows occupied bricks.
    pub fn for_each_solid(&self, mut f: impl FnMut(IVec3, Voxel)) {
        for (index, &raw) in self.top.iter().enumerate() {
            let cell = BrickCell::decode(raw);
            if cell == BrickCell::Empty {
                continue;
            }
            let origin = self.brick_coord(index as u32) * BRICK_SIZE;
            for z in 0..BRICK_SIZE {
                for y in 0..BRICK_SIZE {
                    for x in 0..BRICK_SIZE {
                        let local = IVec3::new(x, y, z);
                        let p = origin + local;
                        if !self.contains(p) {
                            continue;
                        }
                        let v = match cell {
                            BrickCell::Homogeneous(m) => m,
                            BrickCell::Pooled(slot) => self.pool[slot as usize * BRICK_VOXELS + local_index(local)],
                            BrickCell::Empty => AIR,
                        };
                        if v != AIR {
                            f(p, v);
                        }
                    }
                }
            }
        }
    }
}
