//! A hash map keyed by grid cells (`IVec3`) with a cheap hash. The CPU reference looks up 27 cells of its nearby
//! lights per shading point and the importers one brick per voxel read; the standard library's SipHash made those
//! lookups a large share of the reference's time and of a `.vx` import's (docs/bench/why.md). Its keys are the world's own cells, so it needs no resistance
//! to chosen keys; it has no random seed, so iteration order is the same every run.

use bevy::math::IVec3;
use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};

/// Hashes a cell's coordinates with a multiply and a rotate each.
#[derive(Default)]
pub struct CellHasher(u64);

impl CellHasher {
    fn add(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(23) ^ word).wrapping_mul(0x9e37_79b9_7f4a_7c15);
    }
}

impl Hasher for CellHasher {
    fn write(&mut self, bytes: &[u8]) {
        for &byte in bytes {
            self.add(byte as u64);
        }
    }

    fn write_i32(&mut self, value: i32) {
        self.add(value as u32 as u64);
    }

    /// The product's high bits are its best mixed; fold them into the low ones the table indexes by.
    fn finish(&self) -> u64 {
        self.0 ^ (self.0 >> 32)
    }
}

pub type CellMap<V> = HashMap<IVec3, V, BuildHasherDefault<CellHasher>>;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn neighbouring_cells_land_in_different_buckets_of_a_small_table() {
        // hashbrown indexes by the low bits: the 27 cells around a point must not pile up there.
        let mut low = std::collections::HashSet::new();
        for z in -1..=1 {
            for y in -1..=1 {
                for x in -1..=1 {
                    let mut h = CellHasher::default();
                    std::hash::Hash::hash(&IVec3::new(100 + x, 7 + y, -3 + z), &mut h);
                    low.insert(h.finish() & 63);
                }
            }
        }
        assert!(low.len() >= 16, "27 neighbours spread over {} of 64 buckets", low.len());
    }
}
