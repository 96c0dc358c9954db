//! Which light is at this voxel? A hash table from a light's cube (lowest corner, edge) to its alias column,
//! rebuilt with the alias table, so a shader can find the lights beside a surface (Voxel ReSTIR's local
//! candidates, `shaders/restir/common.wgsl`) and read their power pdf from the column.
//!
//! Open addressing with linear probing at a load of at most 1/2. An entry holds only the column: the key is
//! checked against the light itself (`lights[alias[column].slot]`), so an entry is 4 bytes. The table is never
//! edited in place (it is rebuilt whenever the pool changes, as the alias table is), so it needs no deletion.
//! `shaders/lib/lights.wgsl` (`light_hash`, `find_light`) mirrors this.

use super::AliasTable;
use bevy::math::IVec3;

/// An empty entry (shared with the shader through `render::gpu_types::shared_constants`).
pub const NO_COLUMN: u32 = u32::MAX;

/// `light_hash`'s multipliers: one odd constant per coordinate, then murmur3's two finaliser constants. Shared
/// with the shader through `render::gpu_types::shared_constants`.
pub const LIGHT_HASH_X: u32 = 0x8da6_b343;
pub const LIGHT_HASH_Y: u32 = 0xd816_3841;
pub const LIGHT_HASH_Z: u32 = 0xcb1a_b31f;
pub const LIGHT_HASH_MIX_1: u32 = 0x85eb_ca6b;
pub const LIGHT_HASH_MIX_2: u32 = 0xc2b2_ae35;

/// The home entry of a light cube (before the capacity mask): a multiply-xor of the coordinates and the edge,
/// then murmur3's finaliser so neighbouring voxels land far apart.
pub fn light_hash(min: IVec3, size: i32) -> u32 {
    let mut h = (min.x as u32).wrapping_mul(LIGHT_HASH_X)
        ^ (min.y as u32).wrapping_mul(LIGHT_HASH_Y)
        ^ (min.z as u32).wrapping_mul(LIGHT_HASH_Z)
        ^ size as u32;
    h ^= h >> 16;
    h = h.wrapping_mul(LIGHT_HASH_MIX_1);
    h ^= h >> 13;
    h = h.wrapping_mul(LIGHT_HASH_MIX_2);
    h ^ (h >> 16)
}

/// The table: a power-of-two number of entries, each an alias column or `NO_COLUMN`.
#[derive(Clone, Debug, PartialEq)]
pub struct LightIndex {
    pub entries: Vec<u32>,
}

impl Default for LightIndex {
    fn default() -> Self {
        LightIndex { entries: vec![NO_COLUMN] }
    }
}

impl LightIndex {
    /// Indexes every column of `alias`; `cube` gives a slot's light cube (corner, edge).
    pub fn build(alias: &AliasTable, cube: impl Fn(u32) -> Option<(IVec3, i32)>) -> Self {
        let capacity = (2 * alias.len()).next_power_of_two().max(1);
        let mask = capacity as u32 - 1;
        let mut entries = vec![NO_COLUMN; capacity];
        for (column, entry) in alias.entries.iter().enumerate() {
            let Some((min, size)) = cube(entry.slot) else { continue };
            let mut i = light_hash(min, size) & mask;
            while entries[i as usize] != NO_COLUMN {
                i = (i + 1) & mask;
            }
            entries[i as usize] = column as u32;
        }
        LightIndex { entries }
    }

    /// The alias column of the light whose cube is (`min`, `size`), as the shader looks it up.
    pub fn find(
        &self,
        alias: &AliasTable,
        cube: impl Fn(u32) -> Option<(IVec3, i32)>,
        min: IVec3,
        size: i32,
    ) -> Option<u32> {
        let mask = self.entries.len() as u32 - 1;
        let mut i = light_hash(min, size) & mask;
        for _ in 0..self.entries.len() {
            let column = self.entries[i as usize];
            if column == NO_COLUMN {
                return None;
            }
            if cube(alias.entries[column as usize].slot) == Some((min, size)) {
                return Some(column);
            }
            i = (i + 1) & mask;
        }
        None
    }

    /// The longest run of occupied entries (the worst probe count of a miss).
    pub fn longest_run(&self) -> usize {
        let n = self.entries.len();
        let mut longest = 0;
        let mut run = 0;
        // Twice round so a run that wraps is counted whole.
        for i in 0..2 * n {
            if self.entries[i % n] == NO_COLUMN {
                run = 0;
            } else {
                run += 1;
                longest = longest.max(run);
            }
        }
        longest.min(n)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cubes(n: i32) -> Vec<(IVec3, i32)> {
        // A dense floor of one-voxel lights plus a row of brick lights: neighbours that differ by one in x or z.
        let mut out: Vec<(IVec3, i32)> = (0..n * n).map(|i| (IVec3::new(i % n, 1, i / n), 1)).collect();
        out.extend((0..8).map(|b| (IVec3::new(8 * b, 16, 0), 8)));
        out
    }

    fn table(cubes: &[(IVec3, i32)]) -> AliasTable {
        let lights: Vec<(u32, f32)> = (0..cubes.len() as u32).map(|s| (s, 1.0 + s as f32)).collect();
        AliasTable::build(&lights)
    }

    #[test]
    fn every_light_is_found_at_its_column_and_nothing_else_is() {
        let cubes = cubes(64);
        let alias = table(&cubes);
        let cube = |slot: u32| cubes.get(slot as usize).copied();
        let index = LightIndex::build(&alias, cube);
        assert_eq!(index.entries.len(), (2 * cubes.len()).next_power_of_two());
        for (slot, &(min, size)) in cubes.iter().enumerate() {
            let column = index.find(&alias, cube, min, size).expect("indexed light");
            assert_eq!(alias.entries[column as usize].slot, slot as u32);
        }
        // Same corner, other edge; a voxel beside the floor; a corner inside a brick light.
        assert_eq!(index.find(&alias, cube, IVec3::new(0, 1, 0), 8), None);
        assert_eq!(index.find(&alias, cube, IVec3::new(0, 2, 0), 1), None);
        assert_eq!(index.find(&alias, cube, IVec3::new(1, 16, 0), 1), None);
        // Load 1/2 with a mixing hash keeps probe runs short even on a regular lattice.
        assert!(index.longest_run() < 64, "longest run {}", index.longest_run());
    }

    #[test]
    fn an_empty_pool_has_one_empty_entry() {
        let alias = AliasTable::default();
        let index = LightIndex::build(&alias, |_| None);
        assert_eq!(index.entries, vec![NO_COLUMN]);
        assert_eq!(index.find(&alias, |_| None, IVec3::ZERO, 1), None);
    }

    #[test]
    fn neighbouring_cubes_hash_apart() {
        // Voxels one apart on each axis, and a voxel light against the brick light with the same corner.
        let home = |min: IVec3, size: i32| light_hash(min, size) & 1023;
        assert_ne!(home(IVec3::new(1, 0, 0), 1), home(IVec3::new(0, 1, 0), 1));
        assert_ne!(home(IVec3::new(0, 1, 0), 1), home(IVec3::new(0, 0, 1), 1));
        assert_ne!(home(IVec3::new(8, 0, 0), 1), home(IVec3::new(8, 0, 0), 8));
    }
}
