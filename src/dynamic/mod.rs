//! Moving voxel objects: entities with a small voxel model (`model`) and a translation that a motion drives.
//! Every GPU pass traces them (ray against the object's box, then a DDA through its voxels; `shaders/lib/traversal.wgsl`
//! `trace_scene`), so they show up in the image, cast shadows and reach the GI cache, which gives their faces
//! their own table (the static/dynamic split). Their emissive voxels are not in the light pool: they light the
//! world through the GI cache only.
//!
//! Objects translate but never rotate: their faces stay axis-aligned, so the G-buffer's face encoding, ReSTIR's
//! face tests and the per-face GI entries hold for them unchanged. A world file saves them (`saved`,
//! `world::objects`); the player collides with them and aims at them (`PlacedModel`), and the CPU reference draws
//! them at their saved phase (`reference::objects`).

pub mod model;
pub mod saved;

pub use model::VoxelModel;

use bevy::prelude::*;
use std::sync::Arc;

/// How an object moves, as a function of time since it was spawned.
#[derive(Clone, Debug, PartialEq)]
pub enum Motion {
    Still,
    /// A horizontal circle of `radius` around the spawn point, once per `period` seconds.
    Drift {
        radius: f32,
        period: f32,
    },
    /// A pendulum's bob below the spawn point (the pivot): arc of `length` and `amplitude` radians in the x-y plane.
    Swing {
        length: f32,
        amplitude: f32,
        period: f32,
    },
    /// Back and forth along `offset` from the spawn point (a triangle wave).
    Slide {
        offset: Vec3,
        period: f32,
    },
}

impl Motion {
    /// Offset from the spawn point at time `t`.
    pub fn offset(&self, t: f32) -> Vec3 {
        let phase = |period: f32| std::f32::consts::TAU * t / period.max(1e-3);
        match *self {
            Motion::Still => Vec3::ZERO,
            Motion::Drift { radius, period } => {
                let a = phase(period);
                Vec3::new(a.cos() - 1.0, 0.0, a.sin()) * radius
            }
            Motion::Swing { length, amplitude, period } => {
                let angle = amplitude * phase(period).sin();
                Vec3::new(angle.sin(), -angle.cos(), 0.0) * length
            }
            Motion::Slide { offset, period } => {
                let u = (t / period.max(1e-3)).rem_euclid(1.0);
                offset * (1.0 - (2.0 * u - 1.0).abs())
            }
        }
    }
}

/// A moving voxel object. Its `Transform`'s translation is the world position of the model's minimum corner.
#[derive(Component, Clone, Debug)]
pub struct DynamicObject {
    /// Stable id (1..=4095) that keys its GI entries; never reused while the object lives.
    pub id: u32,
    pub model: Arc<VoxelModel>,
    pub motion: Motion,
    /// Where the motion is centred (the pendulum's pivot for a swing).
    pub anchor: Vec3,
    /// Seconds since spawn, advanced by the object clock.
    pub age: f32,
}

/// An object whose phase follows another clock than the frame's (the server's, for a client): its age is that
/// clock's reading minus the reading it was born at, and the frame's object clock leaves it alone.
#[derive(Component, Clone, Copy, Debug, PartialEq)]
pub struct BornAt(pub f64);

/// Ids for new objects, and the object clock's step: fixed per frame, so headless runs are reproducible.
#[derive(Resource, Debug)]
pub struct ObjectClock {
    next_id: u32,
    /// Seconds per frame the motions advance (0 freezes them).
    pub step: f32,
}

impl Default for ObjectClock {
    fn default() -> Self {
        ObjectClock { next_id: 1, step: 1.0 / 60.0 }
    }
}

/// Largest number of objects the GPU holds; spawning more is refused with a message.
pub const MAX_OBJECTS: usize = 64;
/// Object ids fit in 12 bits of the G-buffer.
pub const MAX_OBJECT_ID: u32 = 4095;

impl ObjectClock {
    fn take_id(&mut self) -> u32 {
        let id = self.next_id;
        self.next_id = self.next_id % MAX_OBJECT_ID + 1;
        id
    }
}

/// Spawns an object at `anchor`. Errors when the GPU's object table is full.
pub fn spawn_object(
    commands: &mut Commands,
    clock: &mut ObjectClock,
    existing: usize,
    model: Arc<VoxelModel>,
    motion: Motion,
    anchor: Vec3,
) -> Result<Entity, String> {
    if existing >= MAX_OBJECTS {
        return Err(format!("cannot spawn '{}': {MAX_OBJECTS} objects is the most the renderer holds", model.name));
    }
    let object = DynamicObject { id: clock.take_id(), model, motion, anchor, age: 0.0 };
    let at = anchor + object.motion.offset(0.0);
    Ok(commands.spawn((object, Transform::from_translation(at))).id())
}

/// `spawn_object` for code holding the whole world (tests, headless tools).
pub fn spawn_object_in(
    world: &mut World,
    model: Arc<VoxelModel>,
    motion: Motion,
    anchor: Vec3,
) -> Result<Entity, String> {
    let existing = world.query::<&DynamicObject>().iter(world).count();
    if existing >= MAX_OBJECTS {
        return Err(format!("cannot spawn '{}': {MAX_OBJECTS} objects is the most the renderer holds", model.name));
    }
    let id = world.get_resource_or_init::<ObjectClock>().take_id();
    let at = anchor + motion.offset(0.0);
    let object = DynamicObject { id, model, motion, anchor, age: 0.0 };
    Ok(world.spawn((object, Transform::from_translation(at))).id())
}

/// Advances every object's motion by one clock step.
pub fn animate_objects(
    clock: Res<ObjectClock>,
    mut objects: Query<(&mut DynamicObject, &mut Transform), Without<BornAt>>,
) {
    for (mut object, mut transform) in &mut objects {
        object.age += clock.step;
        transform.translation = object.anchor + object.motion.offset(object.age);
    }
}

/// The models shipped in `assets/models`, embedded so the binary runs from any directory.
pub const BUILTIN_MODELS: [(&str, &str); 2] = [
    ("lantern", include_str!("../../assets/models/lantern.ron")),
    ("block", include_str!("../../assets/models/block.ron")),
];

/// A built-in model resolved against `palette`.
pub fn builtin_model(name: &str, palette: &crate::world::Palette) -> Result<VoxelModel, String> {
    let (_, text) = BUILTIN_MODELS
        .iter()
        .find(|(n, _)| *n == name)
        .ok_or_else(|| format!("no built-in model '{name}' (have: lantern, block)"))?;
    VoxelModel::from_ron(text, &format!("assets/models/{name}.ron"), palette)
}

/// A built-in model for this world: materials its legend names that the world's palette lacks are added from
/// the default palette first (they then save with the world like any material).
pub fn model_for_world(name: &str, world: &mut crate::world::VoxelWorld) -> Result<VoxelModel, String> {
    model_for_palette(name, &mut world.palette)
}

/// `model_for_world` on a palette alone: the CPU reference resolves saved objects in a copy of the world's
/// palette, adding the same materials in the same order, so its ids match the renderer's.
pub fn model_for_palette(name: &str, palette: &mut crate::world::Palette) -> Result<VoxelModel, String> {
    if let Err(first) = builtin_model(name, palette) {
        let defaults = crate::world::Palette::default_blocks();
        let (_, text) = BUILTIN_MODELS.iter().find(|(n, _)| *n == name).ok_or(first)?;
        for material in defaults.materials.iter().filter(|m| text.contains(&format!("\"{}\"", m.name))) {
            if palette.id_of(&material.name).is_none() && palette.id_count() < crate::world::palette::MAX_MATERIALS {
                palette.push(material.clone());
            }
        }
    }
    builtin_model(name, palette)
}

/// Object clock and motion (the GPU upload of objects is `render::scene::objects`).
pub struct DynamicObjectsPlugin;

impl Plugin for DynamicObjectsPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<ObjectClock>().add_systems(Update, animate_objects);
    }
}

/// An object's voxels where they are now (its model at its minimum corner), for the CPU's collision and
/// crosshair tests. Objects only translate, so a point's model voxel is `floor(point - min)`.
#[derive(Clone, Copy, Debug)]
pub struct PlacedModel<'a> {
    pub model: &'a VoxelModel,
    pub min: Vec3,
}

impl PlacedModel<'_> {
    fn solid_at(&self, local: IVec3) -> bool {
        local.cmpge(IVec3::ZERO).all() && self.model.get(local.x as u32, local.y as u32, local.z as u32) != 0
    }

    /// Whether a solid voxel of the object overlaps the open box `(lo, hi)` (world coordinates).
    pub fn overlaps_box(&self, lo: Vec3, hi: Vec3) -> bool {
        let a = (lo - self.min + 1e-4).floor().as_ivec3().max(IVec3::ZERO);
        let b = (hi - self.min - 1e-4).floor().as_ivec3().min(self.model.size.as_ivec3() - 1);
        (a.z..=b.z).any(|z| (a.y..=b.y).any(|y| (a.x..=b.x).any(|x| self.solid_at(IVec3::new(x, y, z)))))
    }

    /// Distance along the ray `origin + t * dir` (dir normalised) to the object's first solid voxel within
    /// `max_distance`: the entry into its box, then one voxel at a time (a model is at most 16^3 voxels).
    pub fn trace(&self, origin: Vec3, dir: Vec3, max_distance: f32) -> Option<f32> {
        let size = self.model.size.as_vec3();
        let inverse = dir.recip();
        let t0 = (self.min - origin) * inverse;
        let t1 = (self.min + size - origin) * inverse;
        let enter = t0.min(t1).max_element().max(0.0);
        let exit = t0.max(t1).min_element().min(max_distance);
        // Also refuses NaN bounds (a ray along a face of the box).
        if enter.partial_cmp(&exit).is_none_or(|order| order.is_gt()) {
            return None;
        }
        // March the ray through the box in 1/32-voxel steps (at most ~900 for a 16^3 model, one ray a frame):
        // it can only miss a voxel's corner clipped by less than a step, which a crosshair cannot tell apart.
        let step = 1.0 / 32.0;
        let mut t = enter;
        while t <= exit {
            let local = (origin + dir * (t + 1e-4) - self.min).floor().as_ivec3();
            if self.solid_at(local) {
                return Some(t);
            }
            t += step;
        }
        None
    }
}
