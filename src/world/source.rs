//! Where a world comes from on the command line: a file (world or recipe), a bundled scene, or the generator.

use super::VoxelWorld;
use super::format::{LoadError, MAX_FILE_BYTES, parse_world, read_limited};
use super::recipe::{generated_world, load_scene, parse_recipe};
use bevy::math::UVec3;
use std::path::PathBuf;

/// A world to open.
#[derive(Clone, Debug, PartialEq)]
pub enum WorldSource {
    /// A `.ron` world file or scene recipe.
    Path(PathBuf),
    /// `assets/scenes/NAME.ron`.
    Scene(String),
    /// The terrain generator.
    Generated { seed: u32, size: UVec3 },
}

impl WorldSource {
    pub fn load(&self) -> Result<VoxelWorld, LoadError> {
        match self {
            WorldSource::Path(path) => load_path(path),
            WorldSource::Scene(name) => load_scene(name),
            WorldSource::Generated { seed, size } => generated_world(*seed, *size),
        }
    }
}

/// Loads a path: a `.ron` world file or scene recipe (told apart by the world file's `format` tag), a thesis
/// `.vx` scene or a MagicaVoxel `.vox` model.
pub fn load_path(path: &std::path::Path) -> Result<VoxelWorld, LoadError> {
    let location = path.display().to_string();
    match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
        Some("ron") => {}
        Some("vx") => return super::import::vx::load_vx(path),
        Some("vox") => return super::import::vox::load_vox(path),
        other => {
            return Err(LoadError {
                location,
                message: format!("unsupported world file type {:?} (expected .ron, .vx or .vox)", other.unwrap_or("")),
            });
        }
    }
    // A save killed mid-write left its temporary beside the file: the next load clears it.
    super::format::remove_stale_temporaries(path);
    let text = read_limited(path, MAX_FILE_BYTES)?;
    if text.contains(super::format::FORMAT_TAG) {
        parse_world(&text, &location)
    } else {
        parse_recipe(&text, &location)
    }
}
