//! Trees: a trunk of wood and a rounded, slightly ragged crown of leaves, on grass, one candidate spot per 7 x 7
//! cell (jittered), kept by the land's forest density; none on the village plaza.

use super::Blocks;
use super::columns::Ground;
use super::land::{BLEND, Land, Surface, VillageSite};
use crate::world::VoxelWorld;
use crate::world::grid::AIR;
use crate::world::terrain::hash_u32;
use bevy::math::{IVec2, IVec3};

const CELL: i32 = 7;

/// Plants the trees; returns how many.
pub fn plant_trees(
    world: &mut VoxelWorld,
    land: &Land,
    heights: &[i32],
    site: Option<&VillageSite>,
    seed: u32,
    blocks: &Blocks,
) -> u32 {
    let size = world.grid.size().as_ivec3();
    let mut planted = 0;
    for cz in 0..size.z / CELL {
        for cx in 0..size.x / CELL {
            let Some(tree) = Tree::of_cell(land, site, seed, cx, cz) else { continue };
            let (x, z, crown) = (tree.x, tree.z, tree.crown);
            let ground = heights[(z * size.x + x) as usize];
            let fits = ground + tree.trunk + crown + 1 < size.y && x >= crown && z >= crown;
            let on_grass = world.grid.get(IVec3::new(x, ground, z)) == blocks.grass;
            if !fits || !on_grass || x + crown >= size.x || z + crown >= size.z {
                continue;
            }
            grow_tree(world, IVec3::new(x, ground + 1, z), tree.trunk, crown, tree.hash, blocks);
            planted += 1;
        }
    }
    planted
}

/// The widest crown's reach from its trunk.
pub const MAX_CROWN: i32 = 3;

/// The tree a cell grows, if its spot is wooded enough and off the plaza: where, how tall, its crown.
struct Tree {
    x: i32,
    z: i32,
    trunk: i32,
    crown: i32,
    hash: u32,
}

impl Tree {
    fn of_cell(land: &Land, site: Option<&VillageSite>, seed: u32, cx: i32, cz: i32) -> Option<Tree> {
        let hash = hash_u32(seed ^ hash_u32(0x7eee ^ hash_u32(cx as u32) ^ hash_u32(cz as u32).rotate_left(16)));
        let x = cx * CELL + 1 + (hash % (CELL as u32 - 2)) as i32;
        let z = cz * CELL + 1 + ((hash >> 8) % (CELL as u32 - 2)) as i32;
        let chance = ((hash >> 16) & 0xffff) as f32 / 65536.0;
        if chance >= land.tree_density(x, z) || near_village(site, x, z) {
            return None;
        }
        let trunk = 4 + ((hash >> 4) % 4) as i32;
        Some(Tree { x, z, trunk, crown: if trunk >= 6 { MAX_CROWN } else { 2 }, hash })
    }
}

/// Plants the endless world's trees whose crowns reach into `world`, an area whose column (0, 0) is `min` (x, z).
/// Each tree is decided by its own cell and the ground alone, never by what else grew first, so a tree on a
/// region's border grows whole on both sides and regions come out the same in any order. Returns how many
/// trunks stand inside.
pub fn plant_trees_in(world: &mut VoxelWorld, min: IVec2, ground: &Ground, seed: u32, blocks: &Blocks) -> u32 {
    let size = world.grid.size().as_ivec3();
    let (lo, hi) = (min - MAX_CROWN, min + IVec2::new(size.x, size.z) + MAX_CROWN);
    let mut planted = 0;
    for cz in lo.y.div_euclid(CELL)..=hi.y.div_euclid(CELL) {
        for cx in lo.x.div_euclid(CELL)..=hi.x.div_euclid(CELL) {
            let Some(tree) = Tree::of_cell(ground.land, ground.site, seed, cx, cz) else { continue };
            let (x, z) = (tree.x, tree.z);
            if x < lo.x || x >= hi.x || z < lo.y || z >= hi.y {
                continue;
            }
            let h = ground.height(x, z);
            let fits = h + tree.trunk + tree.crown + 1 < size.y;
            if !fits || ground.surface(x, z) != Surface::Grass || ground.carved(x, h, z, h) {
                continue;
            }
            let base = IVec3::new(x - min.x, h + 1, z - min.y);
            // Voxels outside the area are left to the regions they fall in (`set` refuses them).
            grow_tree(world, base, tree.trunk, tree.crown, tree.hash, blocks);
            planted += u32::from(world.grid.contains(base));
        }
    }
    planted
}

fn near_village(site: Option<&VillageSite>, x: i32, z: i32) -> bool {
    site.is_some_and(|s| {
        let r = s.radius + BLEND * 0.5;
        ((x - s.centre.0).pow(2) + (z - s.centre.1).pow(2)) as f32 <= r * r
    })
}

fn grow_tree(world: &mut VoxelWorld, base: IVec3, trunk: i32, crown: i32, hash: u32, blocks: &Blocks) {
    let top = base + IVec3::Y * (trunk - 1);
    for dy in -crown..=crown {
        for dz in -crown..=crown {
            for dx in -crown..=crown {
                let d = IVec3::new(dx, dy, dz);
                // A squashed ball, its rim thinned by the hash so crowns are not perfect spheres.
                let r2 = dx * dx + dz * dz + 2 * dy * dy;
                let leaf_hash = hash_u32(hash ^ ((dx + 8) | (dy + 8) << 4 | (dz + 8) << 8) as u32);
                if r2 > crown * crown + 1 || (r2 >= crown * crown && leaf_hash.is_multiple_of(3)) {
                    continue;
                }
                let p = top + d + IVec3::Y;
                if world.grid.get(p) == AIR {
                    let _ = world.grid.set(p, blocks.leaves);
                }
            }
        }
    }
    for dy in 0..trunk {
        let _ = world.grid.set(base + IVec3::Y * dy, blocks.wood);
    }
}
