//! Saving and restoring live moving objects (`world::objects` is what the file holds and its validation).

use super::{DynamicObject, Motion, model_for_world, spawn_object_in};
use crate::world::VoxelWorld;
use crate::world::objects::{MODEL_NAMES, SavedMotion, SavedObject};
use bevy::prelude::*;
use std::sync::Arc;

impl SavedObject {
    /// What to save for a live object.
    pub fn of(object: &DynamicObject) -> SavedObject {
        SavedObject::new(&object.model.name, &object.motion, object.anchor, object.age)
    }

    /// An object of built-in model `model`.
    pub fn new(model: &str, motion: &Motion, anchor: Vec3, age: f32) -> SavedObject {
        let motion = match *motion {
            Motion::Still => SavedMotion::Still,
            Motion::Drift { radius, period } => SavedMotion::Drift { radius, period },
            Motion::Swing { length, amplitude, period } => SavedMotion::Swing { length, amplitude, period },
            Motion::Slide { offset, period } => SavedMotion::Slide { offset: offset.into(), period },
        };
        SavedObject { model: model.to_string(), motion, anchor: anchor.into(), age }
    }

    pub fn motion(&self) -> Motion {
        match self.motion {
            SavedMotion::Still => Motion::Still,
            SavedMotion::Drift { radius, period } => Motion::Drift { radius, period },
            SavedMotion::Swing { length, amplitude, period } => Motion::Swing { length, amplitude, period },
            SavedMotion::Slide { offset, period } => Motion::Slide { offset: offset.into(), period },
        }
    }
}

/// Every live object of a built-in model, in spawn (id) order, for saving (an object of another model, which
/// only code can spawn, has no name a file could load it by).
pub fn saved_objects<'a>(objects: impl Iterator<Item = &'a DynamicObject>) -> Vec<SavedObject> {
    let mut live: Vec<&DynamicObject> = objects.filter(|o| MODEL_NAMES.contains(&o.model.name.as_str())).collect();
    live.sort_by_key(|o| o.id);
    live.into_iter().map(SavedObject::of).collect()
}

/// Spawns a world's saved objects, each at its saved phase. Models are resolved against the world's palette
/// (adding a model's materials it lacks, as `model_for_world` does).
pub fn spawn_saved(app_world: &mut World, saved: &[SavedObject]) -> Result<(), String> {
    for object in saved {
        let model = {
            let mut world = app_world.resource_mut::<VoxelWorld>();
            Arc::new(model_for_world(&object.model, &mut world)?)
        };
        let entity = spawn_object_in(app_world, model, object.motion(), Vec3::from(object.anchor))?;
        let mut entity = app_world.entity_mut(entity);
        let at = {
            let mut live = entity.get_mut::<DynamicObject>().expect("just spawned");
            live.age = object.age;
            live.anchor + live.motion.offset(live.age)
        };
        entity.get_mut::<Transform>().expect("just spawned").translation = at;
    }
    Ok(())
}
