//! Moving objects as the CPU reference sees them: every object a world file saves, frozen where it is at its
//! saved phase (`age`), traced exactly like the world (each model is a small brick grid of its own, traversed by
//! the same DDA) so camera, shadow and bounce rays all meet it.
//!
//! Their emissive voxels are not in the light pool (on the GPU they light the world through the GI cache): the
//! reference counts their light where a bounce ray (or, at the last vertex, the cosine ray that leaves it) hits
//! them, so each light is still counted by one strategy only.

use crate::dynamic::model_for_palette;
use crate::world::palette::{Material, Palette};
use crate::world::traversal::Hit;
use crate::world::{BrickGrid, Ray, VoxelWorld, trace};
use bevy::math::{IVec3, Vec3};

/// One object where the reference draws it.
struct Placed {
    /// The model's voxels (model coordinates, from 0).
    grid: BrickGrid,
    /// World position of the model's minimum corner.
    min: Vec3,
}

/// The saved objects of a world, placed; empty for a world without any.
#[derive(Default)]
pub struct ReferenceObjects {
    /// The world's palette plus the materials the models add (`dynamic::model_for_world` adds the same ones in
    /// the same order, so material ids agree with the renderer's).
    palette: Option<Palette>,
    placed: Vec<Placed>,
    emissive: bool,
}

impl ReferenceObjects {
    /// The objects `world` saves, each at its saved phase. Errors name an object whose model cannot be built.
    pub fn of(world: &VoxelWorld) -> Result<ReferenceObjects, String> {
        let Some(saved) = world.objects.as_ref().filter(|s| !s.is_empty()) else {
            return Ok(ReferenceObjects::default());
        };
        let mut palette = world.palette.clone();
        let mut placed = Vec::with_capacity(saved.len());
        let mut emissive = false;
        for object in saved {
            let model = model_for_palette(&object.model, &mut palette)?;
            let mut grid = BrickGrid::new(model.size);
            for z in 0..model.size.z {
                for y in 0..model.size.y {
                    for x in 0..model.size.x {
                        let id = model.get(x, y, z);
                        emissive |= palette.is_emissive(id);
                        // Inside the model's own box: `set` cannot fail.
                        let _ = grid.set(IVec3::new(x as i32, y as i32, z as i32), id);
                    }
                }
            }
            let min = Vec3::from(object.anchor) + object.motion().offset(object.age);
            placed.push(Placed { grid, min });
        }
        Ok(ReferenceObjects { palette: Some(palette), placed, emissive })
    }

    /// Whether any object has an emissive voxel (the path sampler then looks for it on its last ray).
    pub fn emissive(&self) -> bool {
        self.emissive
    }

    /// A material by id: the palette with the models' materials when there are objects.
    pub fn material<'a>(&'a self, world: &'a VoxelWorld, id: u16) -> Option<&'a Material> {
        self.palette.as_ref().unwrap_or(&world.palette).get(id)
    }

    /// The nearest object voxel the ray meets within `max_distance` (`voxel` in model coordinates).
    pub fn trace(&self, ray: &Ray, max_distance: f32) -> Option<Hit> {
        let mut nearest: Option<Hit> = None;
        for object in &self.placed {
            let limit = nearest.map_or(max_distance, |h| h.distance);
            // Objects only translate: the ray in model coordinates has the same direction and distances.
            let local = Ray { origin: ray.origin - object.min, dir: ray.dir };
            if let Some(hit) = trace(&object.grid, &local, limit) {
                nearest = Some(hit);
            }
        }
        nearest
    }
}
