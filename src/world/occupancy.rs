//! The occupancy hierarchy over the brick grid: what lets a ray jump empty space whole cells at a time.
//!
//! Five levels, each cell 4^3 (or 2^3 at the bottom) of the level below, every one an integer shift of voxel
//! coordinates (`LEVEL_SHIFTS`):
//!
//! | level | cell edge | what says it is occupied                                      |
//! |-------|-----------|---------------------------------------------------------------|
//! | 4     | 128       | its region mask is not 0                                       |
//! | 3     | 32        | a bit of its region's mask (64 sectors)                        |
//! | 2     | 8 (brick) | a bit of its sector's mask (64 bricks)                         |
//! | 1     | 2         | a bit of its pooled brick's mask (64 cells of 2^3 voxels)      |
//! | 0     | 1 (voxel) | a bit of its pooled brick's voxel mask (8 words of 64 voxels)  |
//!
//! A ray holds the masks of the cells it is inside in registers, so a step through empty space below a region
//! costs no memory load at all. Any 2^3 or 3^3 box of a mask's children is a cell too (of 64 or 96, 16 or 24, 4 or
//! 6 voxels: empty when its 8 or 27 bits are 0), so a ray walks eight levels (`WALK_LEVELS`; a box counts as the
//! level above its children) for the memory of five;
//! `world::traversal` and `shaders/lib/traversal.wgsl` walk it the same way. Every mask is 64 bits, child
//! `(x & 3) + 4 (y & 3) + 16 (z & 3)` of the child coordinates; the GPU reads them as `vec2<u32>` (low word
//! first). Memory: 8 bytes per brick (its cell mask) and per sector and region, i.e. under 1% of a
//! pooled brick's 1 KiB; and the voxel mask of each pooled brick (`BrickGrid::voxel_mask`, 64 bytes: 6%), which
//! lets a ray read a material only where it hits.
//!
//! Kept current by `BrickGrid` on every change of a brick: one edit touches one brick mask, one sector mask and one
//! region mask, whatever the world's size.

use bevy::math::{IVec3, UVec3};

use super::grid::{BRICK_SIZE, BRICK_VOXELS, Voxel};

/// log2 of the cell edge of each level, voxel (0) to region (4).
pub const LEVEL_SHIFTS: [i32; 5] = [0, 1, 3, 5, 7];
/// The coarsest level.
pub const TOP_LEVEL: usize = 4;
/// The levels a ray walks (`world::traversal`): cells of edge `1 << level`, voxel (0) to region (7). Levels 2, 4
/// and 6 are derived: a 2^3 (or 3^3) box of a mask's children is empty when its 8 (27) bits are 0.
pub const WALK_LEVELS: usize = 8;
/// The walk level of a box of a brick's 2^3 cells: a ray new to a cell of this level or finer is still in its
/// brick.
pub const CELL_BOX_LEVEL: usize = 2;
/// The region's level in the walk.
pub const TOP_WALK_LEVEL: usize = WALK_LEVELS - 1;
/// log2 of a brick's edge in voxels.
pub const BRICK_SHIFT: i32 = LEVEL_SHIFTS[2];
/// log2 of a brick mask's cells' edge in voxels.
pub const CELL_SHIFT: i32 = LEVEL_SHIFTS[1];
/// log2 of a sector's edge in voxels (4^3 bricks).
pub const SECTOR_SHIFT: i32 = LEVEL_SHIFTS[3];
/// log2 of a region's edge in voxels (4^3 sectors).
pub const REGION_SHIFT: i32 = LEVEL_SHIFTS[4];
/// A homogeneous brick's mask: every cell solid.
pub const SOLID_BRICK: u64 = u64::MAX;

/// Bit of the child cell holding voxel `v` inside its level-`level + 1` parent, where `level` is the child's.
#[inline]
pub fn child_bit(v: IVec3, level: usize) -> u32 {
    let c = (v >> LEVEL_SHIFTS[level]) & 3;
    (c.x + 4 * (c.y + 4 * c.z)) as u32
}

/// Whether mask `m` has the child bit `bit`.
#[inline]
pub fn has_child(m: u64, bit: u32) -> bool {
    (m >> bit) & 1 != 0
}

/// The cells of 2^3 voxels of one pooled brick that hold a solid voxel (local index `x + 8 (y + 8 z)`), straight
/// from its voxels: the rebuild the tests hold `cells_of_voxel_mask` (what the grid keeps) against.
pub fn brick_cells(voxels: &[Voxel]) -> u64 {
    let mut mask = 0u64;
    for (i, &v) in voxels.iter().enumerate().take(BRICK_VOXELS) {
        if v != 0 {
            mask |= 1 << cell_of_local(i);
        }
    }
    mask
}

/// The 2^3 cell of local voxel index `i`.
#[inline]
fn cell_of_local(i: usize) -> u32 {
    let (x, y, z) = (i & 7, (i >> 3) & 7, i >> 6);
    ((x >> 1) + 4 * ((y >> 1) + 4 * (z >> 1))) as u32
}

/// Words of a pooled brick's voxel mask: one per 4^3 quadrant of the brick.
pub const VOXEL_MASK_WORDS: usize = 8;

/// The voxel mask word (the brick's 4^3 quadrant, `x + 2 (y + 2 z)`) and bit (`x + 4 (y + 4 z)` inside it) of
/// local voxel `local`: the layout of every other mask, one level down, so a ray holds its quadrant's word as it
/// holds a brick's cells.
#[inline]
pub fn voxel_word_bit(local: IVec3) -> (usize, u32) {
    let q = local >> 2_i32;
    ((q.x + 2 * (q.y + 2 * q.z)) as usize, child_bit(local, 0))
}

/// The solid voxels of one pooled brick (`voxel_word_bit`).
pub fn brick_voxel_mask(voxels: &[Voxel]) -> [u64; VOXEL_MASK_WORDS] {
    let mut words = [0u64; VOXEL_MASK_WORDS];
    for (i, &v) in voxels.iter().enumerate().take(BRICK_VOXELS) {
        if v != 0 {
            let local = IVec3::new(i as i32 & 7, (i as i32 >> 3) & 7, i as i32 >> 6);
            let (word, bit) = voxel_word_bit(local);
            words[word] |= 1 << bit;
        }
    }
    words
}

/// The 2^3 cells of a pooled brick (`brick_cells`) that hold a solid voxel of its voxel mask: each quadrant's word
/// holds 2^3 of them, each a box of 2^3 places (`box_bits`).
pub fn cells_of_voxel_mask(words: &[u64]) -> u64 {
    let mut cells = 0u64;
    for (q, &word) in words.iter().enumerate().take(VOXEL_MASK_WORDS) {
        let quadrant = IVec3::new(q as i32 & 1, (q as i32 >> 1) & 1, q as i32 >> 2) * 2;
        for c in 0..8 {
            let cell = IVec3::new(c & 1, (c >> 1) & 1, c >> 2);
            if word & box_bits(cell * 2) != 0 {
                let at = quadrant + cell;
                cells |= 1 << (at.x + 4 * (at.y + 4 * at.z));
            }
        }
    }
    cells
}

/// The bits of a 4^3 child mask (child `x + 4 y + 16 z`) of the 2^3 children whose lowest is `corner` (each
/// coordinate 0..=2).
#[inline(always)]
pub fn box_bits(corner: IVec3) -> u64 {
    // Children (0|1, 0|1, 0|1): bits 0, 1, 4, 5, 16, 17, 20, 21.
    const BOX: u64 = 0x0033_0033;
    BOX << (corner.x + 4 * corner.y + 16 * corner.z)
}

/// The bits of the 3^3 children whose lowest is `corner` (each coordinate 0..=1).
#[inline(always)]
pub fn box3_bits(corner: IVec3) -> u64 {
    // Children (0..3, 0..3, 0..3): rows of 0b111 at 0, 4, 8 in layers 0, 16, 32.
    const BOX3: u64 = 0x0777_0777_0777;
    BOX3 << (corner.x + 4 * corner.y + 16 * corner.z)
}

/// Grid dimensions of `level` for a world of `bricks` bricks.
fn dims(bricks: UVec3, shift_over_bricks: u32) -> UVec3 {
    let edge = 1 << shift_over_bricks;
    (bricks + UVec3::splat(edge - 1)) >> shift_over_bricks
}

#[inline]
fn index(c: IVec3, dims: UVec3) -> usize {
    (c.x as u32 + dims.x * (c.y as u32 + dims.y * c.z as u32)) as usize
}

/// The masks of levels 1-4 (level 0 is the brick pool itself), in one array as the GPU holds them: every brick's
/// cell mask (by brick index, as the top grid), then every sector's brick mask, then every region's sector mask.
#[derive(Clone, Debug)]
pub struct Occupancy {
    /// Bricks: their cells of 2^3 that hold a solid voxel (`SOLID_BRICK` homogeneous, 0 empty); sectors and
    /// regions: their children that are not empty.
    masks: Vec<u64>,
    sector_dims: UVec3,
    sector_base: usize,
    region_dims: UVec3,
    region_base: usize,
    /// The box of bricks (lowest, highest) that held a solid voxel since the masks were made: a ray leaves the
    /// world's solid part through it. It only grows (an edit that empties its edge leaves it as it was), so an
    /// edit stays one brick's work; a world loaded again gets a tight one.
    occupied: Option<(IVec3, IVec3)>,
    /// The brick coordinates of the storage's brick (0, 0, 0) before the wrap (`BrickGrid::scroll_window`): a
    /// sector or region is stored at its coordinates less this one's (scaled), less the grid where that reaches
    /// past it. Zero in a bounded world.
    wrap_base: IVec3,
}

impl Occupancy {
    /// All empty, for a grid of `bricks` bricks.
    pub fn new(bricks: UVec3) -> Self {
        let sector_dims = dims(bricks, 2);
        let region_dims = dims(sector_dims, 2);
        let count = |d: UVec3| (d.x * d.y * d.z) as usize;
        let sector_base = count(bricks);
        let region_base = sector_base + count(sector_dims);
        Occupancy {
            masks: vec![0; region_base + count(region_dims)],
            sector_dims,
            sector_base,
            region_dims,
            region_base,
            occupied: None,
            wrap_base: IVec3::ZERO,
        }
    }

    /// Where a scrolled window's storage wraps, in bricks (a multiple of the sizes of sectors and regions).
    pub(crate) fn set_wrap_base(&mut self, bricks: IVec3) {
        self.wrap_base = bricks;
    }

    /// The index of cell `c` of the level `shift` (log2 of its edge in bricks: 2 for sectors, 4 for regions).
    #[inline]
    fn wrapped(&self, c: IVec3, dims: UVec3, shift: i32) -> usize {
        index(super::grid::wrapped_cell(c, self.wrap_base >> shift, dims.as_ivec3()), dims)
    }

    /// The box of bricks (lowest, highest, inclusive) that may hold a solid voxel; `None` when none ever did.
    pub fn occupied_bricks(&self) -> Option<(IVec3, IVec3)> {
        self.occupied
    }

    /// The cell mask of brick index `i`.
    #[inline]
    pub fn brick(&self, i: usize) -> u64 {
        self.masks[i]
    }

    /// The brick mask of the sector holding voxel `v` (inside the world).
    #[inline]
    pub fn sector(&self, v: IVec3) -> u64 {
        self.masks[self.sector_base + self.wrapped(v >> SECTOR_SHIFT, self.sector_dims, 2)]
    }

    /// The sector mask of the region holding voxel `v` (inside the world).
    #[inline]
    pub fn region(&self, v: IVec3) -> u64 {
        self.masks[self.region_base + self.wrapped(v >> REGION_SHIFT, self.region_dims, 4)]
    }

    pub fn sector_dims(&self) -> UVec3 {
        self.sector_dims
    }

    pub fn region_dims(&self) -> UVec3 {
        self.region_dims
    }

    /// Where the sector masks and the region masks start in `masks`.
    pub fn bases(&self) -> (usize, usize) {
        (self.sector_base, self.region_base)
    }

    /// Every mask, for GPU upload.
    pub fn masks(&self) -> &[u64] {
        &self.masks
    }

    /// Indices in `masks` of brick `b`'s (index `i`) own mask, its sector's and its region's: what an edit of the
    /// brick may change.
    pub fn indices_of_brick(&self, i: usize, b: IVec3) -> [usize; 3] {
        [
            i,
            self.sector_base + self.wrapped(b >> 2, self.sector_dims, 2),
            self.region_base + self.wrapped(b >> 4, self.region_dims, 4),
        ]
    }

    /// Sets brick `b` (index `i`)'s cell mask and the bits above it.
    pub fn set_brick(&mut self, i: usize, b: IVec3, mask: u64) {
        if self.masks[i] == mask {
            return;
        }
        let was_empty = self.masks[i] == 0;
        self.masks[i] = mask;
        if mask != 0 {
            self.occupied = Some(self.occupied.map_or((b, b), |(lo, hi)| (lo.min(b), hi.max(b))));
        }
        if was_empty == (mask == 0) {
            return;
        }
        let [_, s, r] = self.indices_of_brick(i, b);
        let v = b * BRICK_SIZE;
        let sector_bit = 1u64 << child_bit(v, 2);
        let sector_was_empty = self.masks[s] == 0;
        if mask == 0 {
            self.masks[s] &= !sector_bit;
        } else {
            self.masks[s] |= sector_bit;
        }
        if sector_was_empty == (self.masks[s] == 0) {
            return;
        }
        let region_bit = 1u64 << child_bit(v, 3);
        if self.masks[s] == 0 {
            self.masks[r] &= !region_bit;
        } else {
            self.masks[r] |= region_bit;
        }
    }

    /// Bytes the masks take (the same on the GPU).
    pub fn bytes(&self) -> u64 {
        8 * self.masks.len() as u64
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn brick_cells_marks_the_cell_of_each_solid_voxel() {
        let mut voxels = vec![0u16; BRICK_VOXELS];
        assert_eq!(brick_cells(&voxels), 0);
        // Voxel (7, 0, 3): cell (3, 0, 1) = bit 3 + 16.
        voxels[7 + 8 * 8 * 3] = 5;
        assert_eq!(brick_cells(&voxels), 1 << 19);
        // The same cell from the voxel mask: (6, 1, 2) shares it, (5, 1, 2) does not.
        let cells = cells_of_voxel_mask(&brick_voxel_mask(&voxels));
        assert_eq!(cells, brick_cells(&voxels));
        assert!(has_child(cells, child_bit(IVec3::new(6, 1, 2), 1)));
        assert!(!has_child(cells, child_bit(IVec3::new(5, 1, 2), 1)));
    }

    #[test]
    fn the_voxel_mask_has_the_bit_of_each_solid_voxel() {
        let mut voxels = vec![0u16; BRICK_VOXELS];
        assert_eq!(brick_voxel_mask(&voxels), [0; VOXEL_MASK_WORDS]);
        // Voxel (7, 0, 3): quadrant (1, 0, 0) = word 1, place (3, 0, 3) = bit 3 + 48.
        voxels[7 + 8 * 8 * 3] = 5;
        let mut expected = [0; VOXEL_MASK_WORDS];
        expected[1] = 1 << 51;
        assert_eq!(brick_voxel_mask(&voxels), expected);
        assert_eq!(voxel_word_bit(IVec3::new(7, 0, 3)), (1, 51));
        // Voxel (4, 5, 6): quadrant (1, 1, 1) = word 7, place (0, 1, 2) = bit 4 + 32.
        assert_eq!(voxel_word_bit(IVec3::new(4, 5, 6)), (7, 4 + 32));
    }

    /// The bits of a 4^3 child mask whose children lie in the cube of `edge` children from `corner`.
    fn children_in_cube(corner: IVec3, edge: i32) -> u64 {
        (0..64)
            .filter(|bit| {
                let child = IVec3::new(bit & 3, (bit >> 2) & 3, bit >> 4);
                child.cmpge(corner).all() && child.cmplt(corner + edge).all()
            })
            .fold(0, |m, bit| m | 1 << bit)
    }

    /// A box's bits are those of the 8 (27) children from its corner to its corner + 1 (+ 2), wherever it lies.
    #[test]
    fn box_bits_are_the_children_of_the_box() {
        for corner in [IVec3::new(0, 0, 0), IVec3::new(2, 0, 1), IVec3::new(1, 2, 2), IVec3::new(2, 2, 2)] {
            assert_eq!(box_bits(corner), children_in_cube(corner, 2), "{corner}");
        }
        for corner in [IVec3::new(0, 0, 0), IVec3::new(1, 0, 1), IVec3::new(0, 1, 1), IVec3::new(1, 1, 1)] {
            assert_eq!(box3_bits(corner), children_in_cube(corner, 3), "{corner}");
        }
    }

    #[test]
    fn a_brick_sets_and_clears_its_sector_and_region_bits() {
        let bricks = UVec3::new(20, 3, 9);
        let mut occ = Occupancy::new(bricks);
        let b = IVec3::new(17, 2, 5);
        let i = (b.x + 20 * (b.y + 3 * b.z)) as usize;
        occ.set_brick(i, b, 0b10);
        let v = b * BRICK_SIZE;
        assert_eq!(occ.sector(v), 1 << (1 + 4 * 2 + 16));
        assert_eq!(occ.region(v), 1 << 16);
        assert_eq!(occ.brick(i), 0b10);
        occ.set_brick(i, b, 0);
        assert_eq!((occ.sector(v), occ.region(v)), (0, 0));
        assert_eq!(occ.sector_dims(), UVec3::new(5, 1, 3));
        assert_eq!(occ.region_dims(), UVec3::new(2, 1, 1));
    }
}
