//! Moving objects as a world file stores them (`objects:` in `world::format`): which built-in model, how it
//! moves, where its motion is centred and how far into its motion it is, so a loaded world shows every object
//! where it was saved. Validated like the rest of the file: a hostile entry (unknown model, a period of 1e-30
//! seconds, a NaN phase, an anchor a million voxels away) is one error line, never a panic. The live objects
//! and their spawning are `dynamic` (`dynamic::saved`).
//!
//! ```ron
//! objects: Some([
//!     (model: "lantern", motion: Drift(radius: 5.0, period: 12.0), anchor: (30.0, 12.0, 30.0), age: 3.5),
//!     (model: "block", motion: Swing(length: 7.0, amplitude: 0.7, period: 5.0), anchor: (36, 20, 30), age: 0),
//! ])
//! ```

use bevy::math::{UVec3, Vec3};
use serde::{Deserialize, Serialize};

/// The built-in models a saved object may name (`dynamic::BUILTIN_MODELS` holds their files; a test keeps the
/// two lists equal).
pub const MODEL_NAMES: [&str; 2] = ["lantern", "block"];
/// Most objects a world holds (the renderer's object table, `dynamic::MAX_OBJECTS`).
pub const MAX_SAVED_OBJECTS: usize = 64;

/// A motion as saved (`dynamic::Motion` with plain tuples).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum SavedMotion {
    Still,
    Drift { radius: f32, period: f32 },
    Swing { length: f32, amplitude: f32, period: f32 },
    Slide { offset: (f32, f32, f32), period: f32 },
}

/// One moving object as saved.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SavedObject {
    /// A built-in model's name (`assets/models`).
    pub model: String,
    pub motion: SavedMotion,
    /// Where the motion is centred (a swing's pivot), in voxels.
    pub anchor: (f32, f32, f32),
    /// Seconds into its motion (the phase).
    pub age: f32,
}

/// Periods and ages the loader accepts: a period under 0.1 s moves an object further than a frame can show, and
/// an age beyond a year of play is a corrupt field rather than a long session.
const PERIOD_RANGE: (f32, f32) = (0.1, 3600.0);
const MAX_AGE_SECONDS: f32 = 3.2e7;

impl SavedObject {
    /// The first problem with this entry, for a world of `size` voxels.
    pub fn check(&self, size: Vec3) -> Result<(), String> {
        if !MODEL_NAMES.contains(&self.model.as_str()) {
            return Err(format!("model '{}' is not a built-in model ({})", self.model, MODEL_NAMES.join(", ")));
        }
        // Lengths within the world's largest edge: the motion stays near the world.
        let reach = size.max_element();
        let length = |name: &str, v: f32| {
            if v.is_finite() && v.abs() <= reach { Ok(()) } else { Err(format!("{name} {v} must be within +-{reach}")) }
        };
        let period = |v: f32| {
            if v.is_finite() && (PERIOD_RANGE.0..=PERIOD_RANGE.1).contains(&v) {
                Ok(())
            } else {
                Err(format!("period {v} must be within {}..{} seconds", PERIOD_RANGE.0, PERIOD_RANGE.1))
            }
        };
        match self.motion {
            SavedMotion::Still => {}
            SavedMotion::Drift { radius, period: p } => {
                length("radius", radius)?;
                period(p)?;
            }
            SavedMotion::Swing { length: l, amplitude, period: p } => {
                length("length", l)?;
                if !(amplitude.is_finite() && amplitude.abs() <= std::f32::consts::PI) {
                    return Err(format!("amplitude {amplitude} must be within +-pi radians"));
                }
                period(p)?;
            }
            SavedMotion::Slide { offset, period: p } => {
                length("offset x", offset.0)?;
                length("offset y", offset.1)?;
                length("offset z", offset.2)?;
                period(p)?;
            }
        }
        let anchor = Vec3::from(self.anchor);
        let margin = Vec3::splat(reach);
        if !anchor.is_finite() || anchor.cmplt(-margin).any() || anchor.cmpgt(size + margin).any() {
            return Err(format!("anchor {:?} is outside the world and its margin", self.anchor));
        }
        if !(self.age.is_finite() && (0.0..=MAX_AGE_SECONDS).contains(&self.age)) {
            return Err(format!("age {} must be within 0..{MAX_AGE_SECONDS} seconds", self.age));
        }
        Ok(())
    }
}

/// The first problem with a file's object list, naming the entry.
pub fn check_objects(objects: &[SavedObject], size: UVec3) -> Result<(), String> {
    if objects.len() > MAX_SAVED_OBJECTS {
        return Err(format!("{} objects, the most a world holds is {MAX_SAVED_OBJECTS}", objects.len()));
    }
    for (i, object) in objects.iter().enumerate() {
        object.check(size.as_vec3()).map_err(|e| format!("objects[{i}]: {e}"))?;
    }
    Ok(())
}
