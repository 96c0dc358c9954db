//! The village on its plaza: houses in a ring facing a glowing fountain, each with plaster walls on a cobble
//! footing, a door towards the plaza, windows on the other walls, a stepped gable roof and a warm lamp hung from
//! the ridge; lamp posts around the fountain and cobble paths to every door. Interiors and night give the
//! lighting its work: light through doors and windows, shade under roofs.

use super::Blocks;
use super::land::VillageSite;
use crate::world::VoxelWorld;
use crate::world::grid::{AIR, Voxel};
use crate::world::terrain::hash_u32;
use bevy::math::IVec3;
use std::f32::consts::TAU;

/// One house as built, for the views.
#[derive(Clone, Debug)]
pub struct House {
    /// Footprint `[min, max)` in x and z at floor level.
    pub min: IVec3,
    pub max: IVec3,
    /// The door's lower voxel and the unit step from it into the house.
    pub door: IVec3,
    pub inward: IVec3,
}

/// Where the game hangs its swinging block, from the plaza's centre voxel (`game::objects` spawns it there: the
/// lantern marker is 5 above the plaza, the pivot 6 across and 12 up); the village builds a frame to hang it from.
pub const SWING_PIVOT: IVec3 = IVec3::new(6, 12, 0);

/// Walls stand this many voxels above the floor.
const WALL_HEIGHT: i32 = 4;

/// Builds the village; returns its houses (possibly none, when the site is too cramped).
pub fn build_village(world: &mut VoxelWorld, site: &VillageSite, seed: u32, blocks: &Blocks) -> Vec<House> {
    let g = site.ground;
    let c = IVec3::new(site.centre.0, g, site.centre.1);
    let count = ((site.radius / 5.0) as i32).clamp(4, 8);
    let mut houses: Vec<House> = Vec::new();
    for i in 0..count {
        let hash = hash_u32(seed ^ hash_u32(0x4015e + i as u32));
        let angle = TAU * (i as f32 + 0.3 * ((hash & 0xff) as f32 / 255.0 - 0.5)) / count as f32;
        let distance = site.radius * 0.62;
        let centre = c + IVec3::new((angle.cos() * distance) as i32, 0, (angle.sin() * distance) as i32);
        let (w, d) = (7 + 2 * ((hash >> 8) % 3) as i32, 7 + 2 * ((hash >> 12) % 2) as i32);
        let min = centre - IVec3::new(w / 2, 0, d / 2);
        let max = min + IVec3::new(w, 0, d);
        let clear = houses
            .iter()
            .all(|h| min.x >= h.max.x + 3 || max.x + 3 <= h.min.x || min.z >= h.max.z + 3 || max.z + 3 <= h.min.z);
        let size = world.grid.size().as_ivec3();
        let inside = min.x >= 2 && min.z >= 2 && max.x + 2 <= size.x && max.z + 2 <= size.z;
        if clear && inside && g + WALL_HEIGHT + d.max(w) / 2 + 3 < size.y {
            houses.push(build_house(world, blocks, min, max, c, hash));
        }
    }
    for house in &houses {
        lay_path(world, blocks, c, house.door - house.inward, g);
    }
    build_fountain(world, blocks, c);
    build_swing_frame(world, blocks, c + SWING_PIVOT);
    for k in 0..5 {
        let angle = TAU * (k as f32 + 0.5) / 5.0;
        let r = site.radius * 0.3;
        let base = c + IVec3::new((angle.cos() * r) as i32, 1, (angle.sin() * r) as i32);
        for dy in 0..3 {
            let _ = world.grid.set(base + IVec3::Y * dy, blocks.wood);
        }
        let _ = world.grid.set(base + IVec3::Y * 3, blocks.lamp_warm);
    }
    houses
}

fn fill(world: &mut VoxelWorld, min: IVec3, max: IVec3, voxel: Voxel) {
    // Every caller checked that the house fits the world; a box that does not is skipped, not an error.
    let _ = world.grid.fill_box(min, max, voxel);
}

fn build_house(world: &mut VoxelWorld, blocks: &Blocks, min: IVec3, max: IVec3, plaza: IVec3, hash: u32) -> House {
    let g = min.y;
    let top = g + WALL_HEIGHT;
    let (w, d) = (max.x - min.x, max.z - min.z);
    // Footing down into the ground, floor, then air for the rooms and the roof.
    fill(world, IVec3::new(min.x, g - 3, min.z), IVec3::new(max.x, g, max.z), blocks.cobble);
    fill(world, IVec3::new(min.x, g, min.z), IVec3::new(max.x, g + 1, max.z), blocks.planks);
    fill(world, IVec3::new(min.x - 1, g + 1, min.z - 1), IVec3::new(max.x + 1, top + w.max(d) / 2 + 3, max.z + 1), AIR);
    // Walls, with wooden corner posts.
    fill(world, IVec3::new(min.x, g + 1, min.z), IVec3::new(max.x, top + 1, max.z), blocks.plaster);
    fill(world, IVec3::new(min.x + 1, g + 1, min.z + 1), IVec3::new(max.x - 1, top + 1, max.z - 1), AIR);
    for (x, z) in [(min.x, min.z), (max.x - 1, min.z), (min.x, max.z - 1), (max.x - 1, max.z - 1)] {
        fill(world, IVec3::new(x, g + 1, z), IVec3::new(x + 1, top + 1, z + 1), blocks.wood);
    }
    // The door faces the plaza: the side whose outward normal points most towards it.
    let centre = (min + max) / 2;
    let to_plaza = plaza - centre;
    let inward = if to_plaza.x.abs() >= to_plaza.z.abs() {
        IVec3::new(-to_plaza.x.signum(), 0, 0)
    } else {
        IVec3::new(0, 0, -to_plaza.z.signum())
    };
    let door = match (inward.x, inward.z) {
        (1, _) => IVec3::new(min.x, g + 1, centre.z),
        (-1, _) => IVec3::new(max.x - 1, g + 1, centre.z),
        (_, 1) => IVec3::new(centre.x, g + 1, min.z),
        _ => IVec3::new(centre.x, g + 1, max.z - 1),
    };
    fill(world, door, door + IVec3::new(1, 2, 1), AIR);
    // Windows, two voxels tall, in the middle of every other wall.
    for (window, side) in [
        (IVec3::new(min.x, g + 2, centre.z), IVec3::X),
        (IVec3::new(max.x - 1, g + 2, centre.z), -IVec3::X),
        (IVec3::new(centre.x, g + 2, min.z), IVec3::Z),
        (IVec3::new(centre.x, g + 2, max.z - 1), -IVec3::Z),
    ] {
        if side != inward {
            fill(world, window, window + IVec3::new(1, 2, 1), AIR);
        }
    }
    build_roof(world, blocks, min, max, top + 1, hash);
    // The lamp hangs from the ridge on a wooden rod, just under the wall tops.
    let lamp = IVec3::new(centre.x, top, centre.z);
    let _ = world.grid.set(lamp, blocks.lamp_warm);
    let mut rod = lamp + IVec3::Y;
    while world.grid.contains(rod) && world.grid.get(rod) == AIR {
        let _ = world.grid.set(rod, blocks.wood);
        rod += IVec3::Y;
    }
    House { min, max, door, inward }
}

/// A stepped gable roof with a one-voxel overhang, its ridge along the house's longer side; the gable ends are
/// walled in.
fn build_roof(world: &mut VoxelWorld, blocks: &Blocks, min: IVec3, max: IVec3, y0: i32, hash: u32) {
    let along_x = (max.x - min.x) >= (max.z - min.z) || (hash >> 20) & 1 == 1 && max.x - min.x == max.z - min.z;
    // (u, v): u along the ridge, v across it; `at` maps back to the world.
    let (u0, u1, v0, v1) = if along_x { (min.x, max.x, min.z, max.z) } else { (min.z, max.z, min.x, max.x) };
    let at = |u: i32, y: i32, v: i32| if along_x { IVec3::new(u, y, v) } else { IVec3::new(v, y, u) };
    let mut k = 0;
    loop {
        let (lo, hi) = (v0 - 1 + k, v1 + 1 - k);
        let y = y0 + k;
        if hi - lo <= 0 {
            break;
        }
        // Gable ends first, then the roof strips over them.
        for v in lo.max(v0)..hi.min(v1) {
            let _ = world.grid.set(at(u0, y, v), blocks.plaster);
            let _ = world.grid.set(at(u1 - 1, y, v), blocks.plaster);
        }
        let ridge = hi - lo <= 3;
        for u in u0 - 1..u1 + 1 {
            for v in lo..hi {
                if ridge || v < lo + 2 || v >= hi - 2 {
                    let _ = world.grid.set(at(u, y, v), blocks.roof);
                }
            }
        }
        if ridge {
            break;
        }
        k += 1;
    }
}

/// A two-voxel-wide cobble path on the plaza from `from` to `to`, at ground level `g`.
fn lay_path(world: &mut VoxelWorld, blocks: &Blocks, from: IVec3, to: IVec3, g: i32) {
    let steps = (to - from).abs().max_element().max(1);
    for s in 0..=steps {
        let t = s as f32 / steps as f32;
        let p = from.as_vec3().lerp(to.as_vec3(), t).round().as_ivec3();
        for offset in [IVec3::ZERO, IVec3::X, IVec3::Z] {
            let q = IVec3::new(p.x, g, p.z) + offset;
            if world.grid.contains(q) && world.grid.get(q) == blocks.grass {
                let _ = world.grid.set(q, blocks.cobble);
            }
        }
    }
}

/// A 5 x 5 cobble basin at the plaza's centre around a 3 x 3 pool that glows blue.
fn build_fountain(world: &mut VoxelWorld, blocks: &Blocks, c: IVec3) {
    fill(world, c + IVec3::new(-3, 0, -3), c + IVec3::new(4, 1, 4), blocks.cobble);
    fill(world, c + IVec3::new(-2, 1, -2), c + IVec3::new(3, 2, 3), blocks.cobble);
    fill(world, c + IVec3::new(-1, 0, -1), c + IVec3::new(2, 2, 2), AIR);
    fill(world, c + IVec3::new(-1, 0, -1), c + IVec3::new(2, 1, 2), blocks.lamp_blue);
}

/// Two wooden posts and a beam over the pivot of the game's swinging block, so it hangs from something.
fn build_swing_frame(world: &mut VoxelWorld, blocks: &Blocks, pivot: IVec3) {
    let beam_y = pivot.y + 2;
    for z in [pivot.z - 4, pivot.z + 6] {
        fill(world, IVec3::new(pivot.x, pivot.y - 12 + 1, z), IVec3::new(pivot.x + 2, beam_y, z + 1), blocks.wood);
    }
    fill(
        world,
        IVec3::new(pivot.x, beam_y, pivot.z - 4),
        IVec3::new(pivot.x + 2, beam_y + 1, pivot.z + 7),
        blocks.wood,
    );
}
