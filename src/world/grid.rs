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
    /// The voxels `[lo, hi)` of the window the grid holds, the ones it reads and traces: `[0, size)` for a bounded
    /// world. An endless world's window moves as the player travels (`scroll_window`); voxels are stored at their
    /// coordinates modulo the size, so a scroll leaves every brick that stays where it is and writes only the
    /// bricks that enter.
    window: (IVec3, IVec3),
    /// The lowest voxel of the box of `size` the storage holds now: the window itself, or while a scroll is
    /// under way (`begin_scroll`) the window it goes to, whose entering bricks are written outside the window.
    ring_lo: IVec3,
    /// `ring_lo` rounded down to a multiple of the size: a coordinate's storage is its offset from here, less
    /// the size where that reaches past it.
    wrap_base: IVec3,
}

/// A wrapping window's edge (x and z) and every scroll's step are multiples of this many voxels: the coarsest
/// occupancy cell (a region of 128^3), so each level of the hierarchy wraps whole cells.
pub const WINDOW_STEP: i32 = 1 << super::occupancy::REGION_SHIFT;

/// A window the grid cannot scroll to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct BadScroll {
    pub to: IVec3,
    pub size: UVec3,
}

impl std::fmt::Display for BadScroll {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "a {}x{}x{} grid cannot scroll its window to ({}, {}, {}): x and z must be multiples of {WINDOW_STEP} \
             (the size too) and y must stay 0",
            self.size.x, self.size.y, self.size.z, self.to.x, self.to.y, self.to.z
        )
    }
}

impl std::error::Error for BadScroll {}

/// Where cell `c` of a level whose storage is `dims` cells and wraps from cell `base` is stored: its offset from
/// the base, less the storage where that reaches past it. The one wrap rule the grid, its occupancy levels and
/// the light bricks share; the identity in a bounded world (base 0).
#[inline]
pub fn wrapped_cell(c: IVec3, base: IVec3, dims: IVec3) -> IVec3 {
    let s = c - base;
    IVec3::select(s.cmpge(dims), s - dims, s)
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
            window: (IVec3::ZERO, size.as_ivec3()),
            ring_lo: IVec3::ZERO,
            wrap_base: IVec3::ZERO,
        }
    }

    pub fn size(&self) -> UVec3 {
        self.size
    }

    /// World size in bricks.
    pub fn brick_dims(&self) -> UVec3 {
        self.bricks
    }

    /// Whether voxel `p` lies in the window the grid holds (`[0, size)` for a bounded world).
    #[inline]
    pub fn contains(&self, p: IVec3) -> bool {
        p.cmpge(self.window.0).all() && p.cmplt(self.window.1).all()
    }

    /// The voxels `[lo, hi)` the grid holds: `[0, size)` for a bounded world, wherever an endless world's window
    /// has scrolled to.
    pub fn window(&self) -> (IVec3, IVec3) {
        self.window
    }

    /// The voxel coordinates of storage voxel (0, 0, 0) before the wrap (`wrap_base`), for the GPU's copy.
    pub fn wrap_base(&self) -> IVec3 {
        self.wrap_base
    }

    /// Where brick `b` (inside the window) is stored: its offset from the wrap base, less the grid where that
    /// reaches past it. The identity in a bounded world.
    #[inline]
    fn storage_brick(&self, b: IVec3) -> IVec3 {
        wrapped_cell(b, self.wrap_base >> 3_i32, self.bricks.as_ivec3())
    }

    /// Index of the brick cell holding brick coordinate `b` (must be inside `storage_box`).
    #[inline]
    pub fn brick_index(&self, b: IVec3) -> usize {
        let s = self.storage_brick(b);
        (s.x as u32 + self.bricks.x * (s.y as u32 + self.bricks.y * s.z as u32)) as usize
    }

    /// Brick coordinate (inside `storage_box`) of a brick index.
    pub fn brick_coord(&self, index: u32) -> IVec3 {
        let x = index % self.bricks.x;
        let y = (index / self.bricks.x) % self.bricks.y;
        let z = index / (self.bricks.x * self.bricks.y);
        let b = IVec3::new(x as i32, y as i32, z as i32) + (self.wrap_base >> 3_i32);
        IVec3::select(b.cmplt(self.ring_lo >> 3_i32), b + self.bricks.as_ivec3(), b)
    }

    /// The decoded top cell of brick coordinate `b`, or `Empty` outside the window.
    #[inline]
    pub fn cell(&self, b: IVec3) -> BrickCell {
        let (lo, hi) = self.window;
        if b.cmplt(lo >> 3_i32).any() || b.cmpge((hi + BRICK_SIZE - 1) >> 3_i32).any() {
            return BrickCell::Empty;
        }
        BrickCell::decode(self.top[self.brick_index(b)])
    }

    /// Moves the window to start at voxel `lo` (x and z multiples of `WINDOW_STEP`, y 0; the size's x and z too):
    /// `begin_scroll` and `finish_scroll` at once. The caller writes every brick of `entered_boxes` (`put_brick`)
    /// before anything reads them.
    pub fn scroll_window(&mut self, lo: IVec3) -> Result<(), BadScroll> {
        self.begin_scroll(lo)?;
        self.finish_scroll();
        Ok(())
    }

    /// Starts moving the window to start at voxel `lo`: the window shrinks to what the old and new ones share
    /// (the bricks that leave are no longer read), and the storage is the new window's, so the bricks that enter
    /// can be written (`put_brick`, over the storage of those that left) a few at a time while the window shows
    /// only what it already held. Every brick inside both windows keeps its voxels and its storage.
    pub fn begin_scroll(&mut self, lo: IVec3) -> Result<(), BadScroll> {
        Self::check_scroll(self.size, lo)?;
        let size = self.size.as_ivec3();
        let shared_lo = self.window.0.max(lo);
        self.window = (shared_lo, self.window.1.min(lo + size).max(shared_lo));
        self.ring_lo = lo;
        self.wrap_base = IVec3::new(lo.x.div_euclid(size.x) * size.x, 0, lo.z.div_euclid(size.z) * size.z);
        self.occupancy.set_wrap_base(self.wrap_base >> 3_i32);
        Ok(())
    }

    /// Whether a grid of `size` can scroll its window to start at voxel `lo`: x and z whole steps (the size's
    /// too), y 0.
    pub fn check_scroll(size: UVec3, lo: IVec3) -> Result<(), BadScroll> {
        let step_ok = |v: i32| v.rem_euclid(WINDOW_STEP) == 0;
        let s = size.as_ivec3();
        if step_ok(lo.x) && step_ok(lo.z) && step_ok(s.x) && step_ok(s.z) && lo.y == 0 {
            Ok(())
        } else {
            Err(BadScroll { to: lo, size })
        }
    }

    /// Ends a scroll: the window is the whole of what the storage holds.
    pub fn finish_scroll(&mut self) {
        self.window = (self.ring_lo, self.ring_lo + self.size.as_ivec3());
    }

    /// The box of `size` the storage holds: the window, or the one a scroll under way goes to.
    pub fn storage_box(&self) -> (IVec3, IVec3) {
        (self.ring_lo, self.ring_lo + self.size.as_ivec3())
    }

    /// The boxes of voxels in the window starting at `new_lo` that the window starting at `old_lo` did not hold
    /// (at most two: the strip entered along x, then the rest along z), for a grid of `size`.
    pub fn entered_boxes(size: UVec3, old_lo: IVec3, new_lo: IVec3) -> Vec<(IVec3, IVec3)> {
        let size = size.as_ivec3();
        let (new_hi, old_hi) = (new_lo + size, old_lo + size);
        let overlap_lo = new_lo.max(old_lo);
        let overlap_hi = new_hi.min(old_hi);
        if overlap_hi.cmple(overlap_lo).any() {
            return vec![(new_lo, new_hi)];
        }
        let mut boxes = Vec::new();
        // Along x: the columns of the new window outside the old one's x range, every z.
        if new_lo.x < overlap_lo.x {
            boxes.push((new_lo, IVec3::new(overlap_lo.x, new_hi.y, new_hi.z)));
        }
        if new_hi.x > overlap_hi.x {
            boxes.push((IVec3::new(overlap_hi.x, new_lo.y, new_lo.z), new_hi));
        }
        // Along z: within the overlap's x range only (the corners are in the strips above).
        if new_lo.z < overlap_lo.z {
            boxes
                .push((IVec3::new(overlap_lo.x, new_lo.y, new_lo.z), IVec3::new(overlap_hi.x, new_hi.y, overlap_lo.z)));
        }
        if new_hi.z > overlap_hi.z {
            boxes
                .push((IVec3::new(overlap_lo.x, new_lo.y, overlap_hi.z), IVec3::new(overlap_hi.x, new_hi.y, new_hi.z)));
        }
        boxes
    }

    /// Makes brick `b` (inside `storage_box`) what `source`'s brick `from` is, whatever it held: the way a scroll
    /// writes the bricks that enter (an empty or uniform brick frees its pool slot, as an edit would).
    pub fn put_brick(&mut self, b: IVec3, source: &BrickGrid, from: IVec3) {
        match source.cell(from) {
            BrickCell::Empty => self.put_uniform(b, AIR),
            BrickCell::Homogeneous(m) => self.put_uniform(b, m),
            BrickCell::Pooled(slot) => {
                let voxels: &[Voxel; BRICK_VOXELS] = source.pool_brick(slot).try_into().expect("a slot is a brick");
                self.set_brick(b, voxels);
            }
        }
    }

    /// Makes the whole brick `b` one voxel (air: empty).
    fn put_uniform(&mut self, b: IVec3, voxel: Voxel) {
        let index = self.brick_index(b);
        let target = if voxel == AIR { BrickCell::Empty } else { BrickCell::Homogeneous(voxel) };
        let current = BrickCell::decode(self.top[index]);
        if current == target {
            return;
        }
        if let BrickCell::Pooled(slot) = current {
            self.free_slots.push(slot);
        }
        self.top[index] = target.encode();
        self.update_occupancy(index);
        self.dirty.insert(index as u32);
    }

    /// The occupancy masks rays skip empty space with.
    #[inline]
    pub fn occupancy(&self) -> &Occupancy {
        &self.occupancy
    }

    /// The voxels `[lo, hi)` of the bricks that may hold a solid voxel (`Occupancy::occupied_bricks`), within the
    /// window; an empty box (`lo == hi` on some axis) when none does.
    pub fn occupied_box(&self) -> (IVec3, IVec3) {
        match self.occupancy.occupied_bricks() {
            Some((lo, hi)) => {
                let (window_lo, window_hi) = self.window();
                let lo = (lo * BRICK_SIZE).max(window_lo);
                (lo, ((hi + 1) * BRICK_SIZE).min(window_hi).max(lo))
            }
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
