//! Which bricks hold a light: one bit per brick of the world, in top-grid order, rebuilt with the alias table.
//!
//! Voxel ReSTIR looks for the lights beside every surface it shades (`local_lights` in
//! `shaders/restir/common.wgsl`: 17 voxels, each a grid lookup and, where emissive, a light-index probe). Almost
//! every surface has none, and the bricks its 17 voxels lie in (one or two) say so in one load each: a voxel can
//! only be (part of) a light whose cube lies in its own brick, a voxel light or its brick's brick light.
//! `shaders/lib/lights.wgsl` (`brick_has_light`) reads the same bits.

use bevy::math::{IVec3, UVec3};

/// The bits, 32 bricks a word, brick `x + bx * (y + by * z)` at bit `i % 32` of word `i / 32`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LightBricks {
    dims: UVec3,
    words: Vec<u32>,
}

impl LightBricks {
    /// The bricks of a world `dims` bricks wide holding the lights whose lowest corners are `corners`.
    pub fn build(dims: UVec3, corners: impl Iterator<Item = IVec3>) -> Self {
        let count = dims.x as usize * dims.y as usize * dims.z as usize;
        let mut bricks = LightBricks { dims, words: vec![0; count.div_ceil(32)] };
        for corner in corners {
            if let Some(i) = bricks.index(corner >> 3_i32) {
                bricks.words[i / 32] |= 1 << (i % 32);
            }
        }
        bricks
    }

    fn index(&self, b: IVec3) -> Option<usize> {
        let inside = b.cmpge(IVec3::ZERO).all() && b.cmplt(self.dims.as_ivec3()).all();
        inside.then(|| (b.x as u32 + self.dims.x * (b.y as u32 + self.dims.y * b.z as u32)) as usize)
    }

    /// Whether brick `b` holds a light (false outside the world).
    pub fn contains(&self, b: IVec3) -> bool {
        self.index(b).is_some_and(|i| self.words[i / 32] >> (i % 32) & 1 == 1)
    }

    /// The words as the GPU holds them.
    pub fn words(&self) -> &[u32] {
        &self.words
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_light_marks_its_own_brick_only() {
        let dims = UVec3::new(5, 3, 4);
        let corners = [IVec3::new(0, 0, 0), IVec3::new(17, 9, 31), IVec3::new(32, 16, 24)];
        let bricks = LightBricks::build(dims, corners.into_iter());
        let marked: Vec<IVec3> = (0..4)
            .flat_map(|z| (0..3).flat_map(move |y| (0..5).map(move |x| IVec3::new(x, y, z))))
            .filter(|&b| bricks.contains(b))
            .collect();
        assert_eq!(marked, vec![IVec3::new(0, 0, 0), IVec3::new(2, 1, 3), IVec3::new(4, 2, 3)]);
        assert!(!bricks.contains(IVec3::new(-1, 0, 0)) && !bricks.contains(IVec3::new(5, 0, 0)));
        // 60 bricks: two words; bricks 52 and 59 at bits 20 and 27 of the second.
        assert_eq!(bricks.words(), [1, 1 << 20 | 1 << 27]);
        assert!(LightBricks::default().words().is_empty());
    }
}
