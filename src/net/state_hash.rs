//! Hashes of what every client must agree on: the voxels, the lights and the moving objects. Each hashes content,
//! not layout (the brick pool's slots and the light pool's slots differ between a world edited live and the same
//! world loaded), so two equal worlds hash equal however they came to be.

use crate::lights::{LightKey, LightPool};
use crate::world::objects::SavedObject;
use crate::world::{BrickCell, Palette, VoxelWorld};
use bevy::math::IVec3;

struct Fnv(u64);

impl Fnv {
    fn new() -> Self {
        Fnv(0xcbf2_9ce4_8422_2325)
    }
    fn bytes(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
    fn ivec(&mut self, v: IVec3) {
        self.bytes(bytemuck::cast_slice(&v.to_array()));
    }
}

/// Every non-air voxel with its position.
pub fn voxels_hash(world: &VoxelWorld) -> u64 {
    let mut h = Fnv::new();
    h.ivec(world.grid.size().as_ivec3());
    let dims = world.grid.brick_dims().as_ivec3();
    for z in 0..dims.z {
        for y in 0..dims.y {
            for x in 0..dims.x {
                let b = IVec3::new(x, y, z);
                if matches!(world.grid.cell(b), BrickCell::Empty) {
                    continue;
                }
                let voxels = world.grid.brick_voxels(b);
                if voxels.iter().all(|&v| v == 0) {
                    continue;
                }
                h.ivec(b);
                h.bytes(bytemuck::cast_slice(&voxels));
            }
        }
    }
    h.0
}

/// Every light (its cube, material, exposed faces and area), in key order.
pub fn lights_hash(pool: &LightPool) -> u64 {
    let mut lights: Vec<_> = pool.lights().map(|(_, l)| *l).collect();
    let key = |k: LightKey| match k {
        LightKey::Voxel(p) => (0, p.to_array()),
        LightKey::Brick(b) => (1, b.to_array()),
    };
    lights.sort_by_key(|l| key(l.key));
    let mut h = Fnv::new();
    for l in lights {
        let (kind, at) = key(l.key);
        h.bytes(&[kind, l.faces]);
        h.bytes(bytemuck::cast_slice(&at));
        h.ivec(l.min);
        h.bytes(&l.size.to_le_bytes());
        h.bytes(&l.material.to_le_bytes());
        h.bytes(&l.exposed_area.to_le_bytes());
    }
    h.0
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::Edit;
    use crate::world::source::WorldSource;

    #[test]
    fn equal_worlds_hash_equal_and_an_edit_changes_the_hash() {
        let world = WorldSource::Scene("cornell".into()).load().unwrap();
        // The same content reached another way: fill a box, then put back what it held.
        let mut edited = world.clone();
        let (min, max) = (IVec3::new(3, 3, 3), IVec3::new(12, 9, 11));
        let before = edited.grid.read_box(min, max + IVec3::ONE);
        edited.apply(Edit::FillBox { min, max, material: 1 }).unwrap();
        assert_ne!(voxels_hash(&edited), voxels_hash(&world));
        edited.apply(Edit::Restore { min, max, voxels: before.into() }).unwrap();
        assert_eq!(voxels_hash(&edited), voxels_hash(&world));

        let pool = LightPool::from_world(&world);
        let mut live = LightPool::from_world(&world);
        let emissive = (1..world.palette.id_count() as u16).find(|&m| world.palette.is_emissive(m)).unwrap();
        let mut lit = world.clone();
        // A lamp floating in the middle of the room.
        let centre = world.grid.size().as_ivec3() / 2;
        assert_eq!(world.grid.get(centre), 0);
        lit.apply(Edit::Place { at: centre, material: emissive }).unwrap();
        live.update_region(&lit, centre, centre);
        assert_ne!(lights_hash(&live), lights_hash(&pool));
        assert_eq!(lights_hash(&live), lights_hash(&LightPool::from_world(&lit)), "incremental = rebuilt");
    }
}

/// Every moving object's model, motion and anchor, in order (not its phase, which moves on).
pub fn objects_hash(objects: &[SavedObject]) -> u64 {
    let mut h = Fnv::new();
    for object in objects {
        h.bytes(object.model.as_bytes());
        h.bytes(format!("{:?}", object.motion).as_bytes());
        let (x, y, z) = object.anchor;
        h.bytes(bytemuck::cast_slice(&[x, y, z]));
    }
    h.0
}

/// Every material of the palette, in id order.
pub fn palette_hash(palette: &Palette) -> u64 {
    let mut h = Fnv::new();
    for m in &palette.materials {
        h.bytes(m.name.as_bytes());
        h.bytes(bytemuck::cast_slice(&m.albedo));
        h.bytes(bytemuck::cast_slice(&m.emission));
        h.bytes(bytemuck::cast_slice(&[m.strength, m.variation]));
    }
    h.0
}

/// The line a server (when it stops) and a bot (when it is done) print: edit number and hashes, equal on both
/// ends when the client followed the server.
pub fn state_line(seq: u64, world: &VoxelWorld, lights: &LightPool, objects: &[SavedObject]) -> String {
    format!(
        "state: seq={seq} voxels={:016x} lights={:016x} palette={:016x} objects={:016x}",
        voxels_hash(world),
        lights_hash(lights),
        palette_hash(&world.palette),
        objects_hash(objects)
    )
}
