//! The light pool (seed 000 §4.2, DESIGN.md "Light pool"): what Voxel ReSTIR samples from.
//!
//! - One *voxel light* per emissive voxel with at least one air neighbour; one *brick light* (a cube of 8) per
//!   homogeneous emissive brick that lies fully inside the world and touches air, replacing its 512 voxel
//!   lights. Enclosed emitters are not lights.
//! - Lights live in stable slots with generation counters: removing a light frees its slot and bumps the
//!   generation, so a reference held by a reservoir is detected as stale (`LightPool::get`).
//! - Edits update only the lights within one voxel of the edited region (`update_region`); `from_world` scans
//!   everything and is for loading only.
//! - Candidates are drawn from an alias table over emitted power (`alias`), rebuilt when the pool changed.

pub mod alias;
pub mod bricks;
pub mod daylight;
pub mod index;
pub mod plugin;
pub mod summary;
pub mod window;

pub use alias::{AliasEntry, AliasTable};
pub use bricks::LightBricks;
pub use index::LightIndex;

use crate::colour::luminance;
use crate::world::grid::{BRICK_SIZE, BrickCell, Voxel, wrapped_cell};
use crate::world::{AIR, VoxelWorld};
use bevy::math::{IVec3, UVec3};
use bevy::prelude::Resource;
use std::collections::{BTreeSet, HashMap};

/// What a light is made of: one voxel, or one whole brick (by brick coordinate).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LightKey {
    Voxel(IVec3),
    Brick(IVec3),
}

/// One emitter: an axis-aligned cube of voxels with one material.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Light {
    pub key: LightKey,
    /// Lowest corner of the cube, in voxels.
    pub min: IVec3,
    /// Edge length in voxels: 1 or 8.
    pub size: i32,
    pub material: Voxel,
    /// Emitted radiance (emission colour x strength).
    pub radiance: [f32; 3],
    /// Area of the cube's faces that touch air, in voxel faces.
    pub exposed_area: f32,
    /// Bit f set when face f (0 +X, 1 -X, 2 +Y, 3 -Y, 4 +Z, 5 -Z) touches air somewhere: a buried face can never
    /// light anything, so samplers skip it.
    pub faces: u8,
    /// Sampling weight: luminance(radiance) x exposed area.
    pub power: f32,
}

/// A reference to a light that survives pool changes: stale once the slot's generation moved on.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct LightRef {
    pub slot: u32,
    pub generation: u32,
}

#[derive(Clone, Debug, Default)]
struct Slot {
    light: Option<Light>,
    generation: u32,
}

/// All lights of a world, in stable slots.
#[derive(Resource, Clone, Debug, Default)]
pub struct LightPool {
    slots: Vec<Slot>,
    free_slots: Vec<u32>,
    by_key: HashMap<LightKey, u32>,
    /// Slots added, removed or changed since the last `take_changed`.
    changed: BTreeSet<u32>,
    alias: AliasTable,
    /// Light cube -> alias column, rebuilt with the alias table.
    index: LightIndex,
    /// The bricks holding a light, rebuilt with the alias table.
    bricks: LightBricks,
    /// The world's size in bricks (what `bricks` spans).
    brick_dims: UVec3,
    /// The grid's window and where its storage wraps, in bricks (`BrickGrid::window`, `wrap_base`): the light
    /// bricks are stored as the grid stores its bricks.
    window_bricks: (IVec3, IVec3),
    alias_stale: bool,
    /// Voxel lights per brick, so edits can skip bricks that have none and can have none.
    voxel_lights_per_brick: HashMap<IVec3, u32>,
}

const NEIGHBOURS: [IVec3; 6] = [IVec3::X, IVec3::NEG_X, IVec3::Y, IVec3::NEG_Y, IVec3::Z, IVec3::NEG_Z];

/// The material of brick `b` when it is a brick-light candidate: homogeneous, emissive, and fully inside the world.
fn brick_light_material(world: &VoxelWorld, b: IVec3) -> Option<Voxel> {
    if !world.brick_lights {
        return None;
    }
    let BrickCell::Homogeneous(m) = world.grid.cell(b) else { return None };
    let (lo, hi) = world.grid.window();
    let inside = (b * BRICK_SIZE).cmpge(lo).all() && ((b + IVec3::ONE) * BRICK_SIZE).cmple(hi).all();
    (inside && world.palette.is_emissive(m)).then_some(m)
}

fn make_light(
    world: &VoxelWorld,
    key: LightKey,
    min: IVec3,
    size: i32,
    material: Voxel,
    exposed: u32,
    faces: u8,
) -> Option<Light> {
    if exposed == 0 {
        return None;
    }
    let radiance = world.palette.get(material)?.radiance();
    let exposed_area = exposed as f32;
    let power = luminance(radiance) * exposed_area;
    Some(Light { key, min, size, material, radiance, exposed_area, faces, power })
}

/// The light voxel `p` should be, if any (never one inside a brick light).
pub fn voxel_light_at(world: &VoxelWorld, p: IVec3) -> Option<Light> {
    let material = world.grid.get(p);
    if material == AIR || !world.palette.is_emissive(material) || brick_light_material(world, p >> 3_i32).is_some() {
        return None;
    }
    let faces = (0..6).filter(|&f| world.grid.get(p + NEIGHBOURS[f]) == AIR).fold(0u8, |m, f| m | 1 << f);
    make_light(world, LightKey::Voxel(p), p, 1, material, faces.count_ones(), faces)
}

/// The light brick `b` should be, if any.
pub fn brick_light_at(world: &VoxelWorld, b: IVec3) -> Option<Light> {
    let material = brick_light_material(world, b)?;
    let lo = b * BRICK_SIZE;
    let mut exposed = 0;
    let mut faces = 0u8;
    for axis in 0..3 {
        let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
        // The +axis face is face 2 axis, the -axis face 2 axis + 1.
        for (plane, face) in [(lo[axis] + BRICK_SIZE, 2 * axis), (lo[axis] - 1, 2 * axis + 1)] {
            let mut face_exposed = 0;
            for i in 0..BRICK_SIZE {
                for j in 0..BRICK_SIZE {
                    let mut p = lo;
                    p[axis] = plane;
                    p[u] += i;
                    p[v] += j;
                    face_exposed += (world.grid.get(p) == AIR) as u32;
                }
            }
            exposed += face_exposed;
            faces |= ((face_exposed > 0) as u8) << face;
        }
    }
    make_light(world, LightKey::Brick(b), lo, BRICK_SIZE, material, exposed, faces)
}

impl LightPool {
    /// Scans the whole world (for loading; edits use `update_region`).
    pub fn from_world(world: &VoxelWorld) -> Self {
        let mut pool = LightPool {
            brick_dims: world.grid.brick_dims(),
            window_bricks: window_bricks(world),
            ..Default::default()
        };
        let grid = &world.grid;
        for (index, &raw) in grid.top_cells().iter().enumerate() {
            if let BrickCell::Homogeneous(_) = BrickCell::decode(raw)
                && let Some(light) = brick_light_at(world, grid.brick_coord(index as u32))
            {
                pool.set(light.key, Some(light));
            }
        }
        grid.for_each_solid(|p, m| {
            if world.palette.is_emissive(m)
                && let Some(light) = voxel_light_at(world, p)
            {
                pool.set(light.key, Some(light));
            }
        });
        // Stale even without lights, so the first read builds the light bricks for this world's size: a pool
        // whose last light was broken rebuilds them, and the two must be equal.
        pool.alias_stale = true;
        pool
    }

    /// Brings the lights within one voxel of the edited box `[min, max]` (inclusive) up to date: voxel lights
    /// there, the brick-light status of every brick the grown box touches, and all voxels of a brick whose
    /// brick-light status flipped (its 512 voxels stop or start being voxel lights). Cost follows the box, not
    /// the world.
    pub fn update_region(&mut self, world: &VoxelWorld, min: IVec3, max: IVec3) {
        self.brick_dims = world.grid.brick_dims();
        self.window_bricks = window_bricks(world);
        let (window_lo, window_hi) = world.grid.window();
        let lo = (min.min(max) - IVec3::ONE).max(window_lo);
        let hi = (min.max(max) + IVec3::ONE).min(window_hi - IVec3::ONE);
        if lo.cmpgt(hi).any() {
            return;
        }
        let mut flipped = Vec::new();
        for b in brick_range(lo, hi) {
            let was = self.by_key.contains_key(&LightKey::Brick(b));
            let light = brick_light_at(world, b);
            if was != light.is_some() {
                flipped.push(b);
            }
            self.set(LightKey::Brick(b), light);
        }
        self.update_voxels(world, lo, hi);
        for b in flipped {
            let brick_lo = b * BRICK_SIZE;
            let brick_hi = (brick_lo + IVec3::splat(BRICK_SIZE - 1)).min(window_hi - IVec3::ONE);
            self.update_voxels(world, brick_lo, brick_hi);
        }
    }

    /// After the grid's window scrolled (`BrickGrid::scroll_window`): frees the slots of the lights that left it
    /// (their generations move on, so a reservoir holding one drops it) and looks again at the lights on the
    /// window's sides. The caller then brings the bricks that entered up to date with `update_region`.
    pub fn follow_window(&mut self, world: &VoxelWorld) {
        self.drop_outside_window(world);
        for (a, b) in window_sides(world) {
            self.update_region(world, a, b);
        }
    }

    /// The first half of `follow_window`: frees the lights outside `world`'s window. The caller looks at the
    /// window's sides (`window_sides`) again before the pool is compared with one made from the world.
    pub fn drop_outside_window(&mut self, world: &VoxelWorld) {
        self.window_bricks = window_bricks(world);
        let (lo, hi) = world.grid.window();
        let left: Vec<LightKey> = self
            .by_key
            .keys()
            .filter(|key| {
                let (min, edge) = match **key {
                    LightKey::Voxel(p) => (p, 1),
                    LightKey::Brick(b) => (b * BRICK_SIZE, BRICK_SIZE),
                };
                min.cmplt(lo).any() || (min + edge).cmpgt(hi).any()
            })
            .copied()
            .collect();
        for key in left {
            self.set(key, None);
        }
        self.alias_stale = true;
    }

    /// Re-evaluates the voxel lights of every voxel in `[lo, hi]` (inclusive, inside the world). Bricks that hold
    /// no voxel light and cannot hold one (no emissive voxel, or uniform and whole) are skipped: a large fill
    /// costs per brick, not per voxel.
    fn update_voxels(&mut self, world: &VoxelWorld, lo: IVec3, hi: IVec3) {
        for b in brick_range(lo, hi) {
            let has_lights = self.voxel_lights_per_brick.contains_key(&b);
            if !has_lights && !brick_may_hold_voxel_lights(world, b) {
                continue;
            }
            let brick_lo = (b * BRICK_SIZE).max(lo);
            let brick_hi = (b * BRICK_SIZE + IVec3::splat(BRICK_SIZE - 1)).min(hi);
            self.update_voxels_in(world, brick_lo, brick_hi);
        }
    }

    fn update_voxels_in(&mut self, world: &VoxelWorld, lo: IVec3, hi: IVec3) {
        for z in lo.z..=hi.z {
            for y in lo.y..=hi.y {
                for x in lo.x..=hi.x {
                    let p = IVec3::new(x, y, z);
                    let light = voxel_light_at(world, p);
                    // Skip the hash lookup for the common case: no light wanted and none there.
                    if light.is_some() || self.by_key.contains_key(&LightKey::Voxel(p)) {
                        self.set(LightKey::Voxel(p), light);
                    }
                }
            }
        }
    }

    /// Adds, updates in place, or removes (bumping the generation) the light of `key`.
    fn set(&mut self, key: LightKey, light: Option<Light>) {
        match (self.by_key.get(&key).copied(), light) {
            (None, None) => {}
            (Some(slot), None) => {
                if let LightKey::Voxel(p) = key {
                    let brick = p >> 3_i32;
                    if let Some(n) = self.voxel_lights_per_brick.get_mut(&brick) {
                        *n -= 1;
                        if *n == 0 {
                            self.voxel_lights_per_brick.remove(&brick);
                        }
                    }
                }
                let s = &mut self.slots[slot as usize];
                s.light = None;
                s.generation = s.generation.wrapping_add(1);
                self.free_slots.push(slot);
                self.by_key.remove(&key);
                self.mark(slot);
            }
            (Some(slot), Some(light)) => {
                if self.slots[slot as usize].light != Some(light) {
                    self.slots[slot as usize].light = Some(light);
                    self.mark(slot);
                }
            }
            (None, Some(light)) => {
                let slot = self.free_slots.pop().unwrap_or_else(|| {
                    self.slots.push(Slot::default());
                    self.slots.len() as u32 - 1
                });
                self.slots[slot as usize].light = Some(light);
                self.by_key.insert(key, slot);
                if let LightKey::Voxel(p) = key {
                    *self.voxel_lights_per_brick.entry(p >> 3_i32).or_insert(0) += 1;
                }
                self.mark(slot);
            }
        }
    }

    fn mark(&mut self, slot: u32) {
        self.changed.insert(slot);
        self.alias_stale = true;
    }

    /// Number of live lights.
    pub fn len(&self) -> usize {
        self.by_key.len()
    }

    pub fn is_empty(&self) -> bool {
        self.by_key.is_empty()
    }

    /// Number of slots (live or free); GPU buffers hold this many.
    pub fn slot_count(&self) -> u32 {
        self.slots.len() as u32
    }

    /// The light in `slot` and the slot's generation.
    pub fn slot(&self, slot: u32) -> Option<(Option<&Light>, u32)> {
        self.slots.get(slot as usize).map(|s| (s.light.as_ref(), s.generation))
    }

    /// The light a reference points to, or `None` when it was removed (even if the slot was reused since).
    pub fn get(&self, r: LightRef) -> Option<&Light> {
        let s = self.slots.get(r.slot as usize)?;
        if s.generation == r.generation { s.light.as_ref() } else { None }
    }

    /// A reference to the light of `key`, if it exists.
    pub fn find(&self, key: LightKey) -> Option<LightRef> {
        let slot = *self.by_key.get(&key)?;
        Some(LightRef { slot, generation: self.slots[slot as usize].generation })
    }

    /// Live lights with their slots, in slot order.
    pub fn lights(&self) -> impl Iterator<Item = (u32, &Light)> {
        self.slots.iter().enumerate().filter_map(|(i, s)| s.light.as_ref().map(|l| (i as u32, l)))
    }

    /// Counts of (voxel lights, brick lights).
    pub fn counts(&self) -> (usize, usize) {
        let bricks = self.by_key.keys().filter(|k| matches!(k, LightKey::Brick(_))).count();
        (self.len() - bricks, bricks)
    }

    /// Slots changed since the last call, ascending; clears the set.
    pub fn take_changed(&mut self) -> Vec<u32> {
        std::mem::take(&mut self.changed).into_iter().collect()
    }

    /// The power alias table over the live lights, rebuilt first if the pool changed since it was built.
    pub fn alias(&mut self) -> &AliasTable {
        if self.alias_stale {
            self.rebuild_alias();
        }
        &self.alias
    }

    /// The light cube -> alias column table (`index`), rebuilt first if the pool changed since it was built.
    pub fn light_index(&mut self) -> &LightIndex {
        if self.alias_stale {
            self.rebuild_alias();
        }
        &self.index
    }

    /// The bricks holding a light (`bricks`), rebuilt first if the pool changed since they were built.
    pub fn light_bricks(&mut self) -> &LightBricks {
        if self.alias_stale {
            self.rebuild_alias();
        }
        &self.bricks
    }

    /// The cube (corner, edge) of the light in `slot`, if the slot is live.
    pub fn cube(&self, slot: u32) -> Option<(IVec3, i32)> {
        self.slots.get(slot as usize)?.light.as_ref().map(|l| (l.min, l.size))
    }

    /// Whether the alias table is out of date (it is rebuilt by `alias`).
    pub fn alias_is_stale(&self) -> bool {
        self.alias_stale
    }

    /// Rebuilds the alias table, the light index and the light bricks, in time linear in the number of lights
    /// (and the world's bricks / 32 for the last).
    pub fn rebuild_alias(&mut self) {
        let lights: Vec<(u32, f32)> = self.lights().map(|(slot, l)| (slot, l.power)).collect();
        self.alias = AliasTable::build(&lights);
        self.index = LightIndex::build(&self.alias, |slot| self.cube(slot));
        let (window_lo, wrap_base) = self.window_bricks;
        let dims = self.brick_dims.as_ivec3();
        // Each light's corner where the grid stores its brick (the identity in a bounded world).
        let stored = |min: IVec3| {
            let s = wrapped_cell(min >> 3_i32, wrap_base, dims);
            debug_assert!((min >> 3_i32).cmpge(window_lo).all(), "a light inside the window");
            s * BRICK_SIZE
        };
        self.bricks = LightBricks::build(self.brick_dims, self.lights().map(|(_, l)| stored(l.min)));
        self.alias_stale = false;
    }
}

/// The four sides of `world`'s window (inclusive boxes one voxel thick). A light on the window's edge sees air
/// beyond it (outside the window is air), as a pool made from the scrolled world would: after a scroll they are
/// looked at again.
pub fn window_sides(world: &VoxelWorld) -> [(IVec3, IVec3); 4] {
    let (lo, hi) = world.grid.window();
    let last = hi - IVec3::ONE;
    [
        (lo, IVec3::new(lo.x, last.y, last.z)),
        (IVec3::new(last.x, lo.y, lo.z), last),
        (lo, IVec3::new(last.x, last.y, lo.z)),
        (IVec3::new(lo.x, lo.y, last.z), last),
    ]
}

/// The grid's window's lowest brick and the brick its storage wraps from.
fn window_bricks(world: &VoxelWorld) -> (IVec3, IVec3) {
    (world.grid.window().0 >> 3_i32, world.grid.wrap_base() >> 3_i32)
}

/// Whether brick `b` could hold a voxel light: it has an emissive voxel and is not a whole uniform brick (a whole
/// uniform emissive brick is a brick light or enclosed; either way none of its voxels is a voxel light).
fn brick_may_hold_voxel_lights(world: &VoxelWorld, b: IVec3) -> bool {
    match world.grid.cell(b) {
        BrickCell::Empty => false,
        BrickCell::Homogeneous(m) => world.palette.is_emissive(m) && brick_light_material(world, b).is_none(),
        BrickCell::Pooled(slot) => world.grid.pool_brick(slot).iter().any(|&v| world.palette.is_emissive(v)),
    }
}

/// Brick coordinates overlapping the voxel box `[lo, hi]` (inclusive).
fn brick_range(lo: IVec3, hi: IVec3) -> impl Iterator<Item = IVec3> {
    let (blo, bhi) = (lo >> 3_i32, hi >> 3_i32);
    (blo.z..=bhi.z)
        .flat_map(move |z| (blo.y..=bhi.y).flat_map(move |y| (blo.x..=bhi.x).map(move |x| IVec3::new(x, y, z))))
}
