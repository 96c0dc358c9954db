//! The voxel world: brick grid, palette, named camera views, edits, traversal, generation and files.

pub mod camera;
pub mod cell_map;
pub mod edit;
pub mod events;
pub mod follow;
pub mod font;
pub mod format;
pub mod generate;
pub mod grid;
pub mod history;
pub mod import;
pub mod objects;
pub mod occupancy;
pub mod palette;
pub mod recipe;
pub mod region_save;
pub mod source;
pub mod stream;
pub mod terrain;
pub mod traversal;

pub use camera::{camera_ray, view_transform, world_from_clip};
pub use edit::{Edit, EditError};
pub use grid::{AIR, BRICK_SIZE, BrickCell, BrickGrid, Voxel};
pub use palette::{Material, Palette};
pub use traversal::{Face, Hit, Ray, trace};

use bevy::math::{IVec3, UVec3, Vec3};
use bevy::prelude::Resource;
use serde::{Deserialize, Serialize};

/// A named camera placement, in voxel units with y up (the thesis' convention: origin and unit direction).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct CameraView {
    pub name: String,
    pub origin: [f32; 3],
    pub direction: [f32; 3],
    /// Vertical field of view in degrees.
    #[serde(default = "default_fov")]
    pub fov_deg: f32,
}

fn default_fov() -> f32 {
    60.0
}

impl CameraView {
    pub fn origin(&self) -> Vec3 {
        Vec3::from(self.origin)
    }

    pub fn direction(&self) -> Vec3 {
        Vec3::from(self.direction).normalize_or(Vec3::Z)
    }

    /// Why this view is unusable, if it is.
    pub fn problem(&self) -> Option<String> {
        if !self.origin.iter().all(|c| c.is_finite()) {
            return Some(format!("view '{}': origin must be finite", self.name));
        }
        let d = Vec3::from(self.direction);
        if !d.is_finite() || d.length_squared() < 1e-12 {
            return Some(format!("view '{}': direction must be finite and non-zero", self.name));
        }
        if !(self.fov_deg.is_finite() && self.fov_deg > 1.0 && self.fov_deg < 179.0) {
            return Some(format!("view '{}': fov_deg {} must be within (1, 179)", self.name, self.fov_deg));
        }
        None
    }
}

/// The game's world: what is traced, edited, saved and loaded.
#[derive(Resource, Clone, Debug)]
pub struct VoxelWorld {
    pub grid: BrickGrid,
    pub palette: Palette,
    pub views: Vec<CameraView>,
    /// The time of day the world was saved at, in hours (0-24); `None` in files from before it was saved, which
    /// then show the settings' time.
    pub time_of_day: Option<f32>,
    /// The moving objects the world was saved with; `None` in files from before objects were saved, which then
    /// get the game's default objects.
    pub objects: Option<Vec<objects::SavedObject>>,
    /// Whether homogeneous emissive bricks become one brick light (the default) or 512 voxel lights; the thesis
    /// measures its cornell box both ways. Not saved: a rule of the light pool, set by the bench.
    pub brick_lights: bool,
    /// The world coordinates of this grid's voxel (0, 0, 0): zero but in a window of the endless world
    /// (`generate::endless`). Per-voxel detail hashes world coordinates (`voxel_albedo`), so a voxel keeps its
    /// shade wherever the window lies. Not saved.
    pub detail_origin: IVec3,
    /// Identifies this world among those created in this process, so the renderer knows when the world was
    /// replaced (loaded or generated) rather than edited.
    pub instance: u64,
}

static NEXT_WORLD_INSTANCE: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

impl VoxelWorld {
    pub fn new(size: UVec3, palette: Palette) -> Self {
        let instance = NEXT_WORLD_INSTANCE.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        VoxelWorld {
            grid: BrickGrid::new(size),
            palette,
            views: Vec::new(),
            time_of_day: None,
            objects: None,
            brick_lights: true,
            detail_origin: IVec3::ZERO,
            instance,
        }
    }

    /// The albedo of the world voxel at `voxel` (grid coordinates) made of `material`, its per-voxel detail
    /// hashed at world coordinates.
    pub fn voxel_albedo(&self, material: &Material, voxel: IVec3) -> [f32; 3] {
        material.albedo_at(voxel + self.detail_origin)
    }

    /// The view called `name`, or the first view when `name` is `None`.
    pub fn view(&self, name: Option<&str>) -> Option<&CameraView> {
        match name {
            Some(name) => self.views.iter().find(|v| v.name == name),
            None => self.views.first(),
        }
    }

    /// A view over the world from just outside a corner, for worlds without views.
    pub fn overview(&self) -> CameraView {
        let size = self.grid.size().as_vec3();
        let target = size * Vec3::new(0.5, 0.3, 0.5);
        let origin = Vec3::new(-0.1 * size.x, size.y * 0.9 + 4.0, -0.1 * size.z);
        CameraView {
            name: "overview".into(),
            origin: origin.into(),
            direction: (target - origin).normalize().into(),
            fov_deg: 60.0,
        }
    }
}
