//! RON world files: a versioned, validated, compact encoding of a `VoxelWorld`.
//!
//! ```ron
//! (
//!     format: "glowbrick-world",
//!     version: 1,
//!     size: (64, 32, 64),
//!     palette: [(name: "stone", albedo: (0.45, 0.45, 0.47), emission: (0, 0, 0), strength: 0)],
//!     views: [(name: "overview", origin: (-16, 46, -16), direction: (0.6, -0.5, 0.6), fov_deg: 60)],
//!     time_of_day: Some(17.5),
//!     objects: Some([(model: "lantern", motion: Drift(radius: 5.0, period: 12.0), anchor: (30, 12, 30), age: 3.5)]),
//!     bricks: [
//!         (at: (0, 0, 0), fill: Uniform(1)),
//!         (at: (1, 0, 0), fill: Runs([(64, 1), (448, 0)])),
//!     ],
//! )
//! ```
//! Voxel id `k > 0` is `palette[k - 1]`; 0 is air. Bricks not listed are air. `Runs` are `(count, id)` pairs in
//! the brick's local order `x + 8 * (y + 8 * z)` and must cover exactly 512 voxels.
//!
//! Loading never modifies the file and reports the first problem as one line with its location; saving writes a
//! temporary file next to the target and renames it over the target, so a failed save leaves the old file intact.

use super::grid::{BRICK_VOXELS, BrickCell, MAX_WORLD_EDGE, Voxel};
use super::palette::{MAX_MATERIALS, Material, Palette};
use super::{CameraView, VoxelWorld};
use bevy::math::{IVec3, UVec3};
use serde::{Deserialize, Serialize};
use std::io::Write;
use std::path::Path;

/// The `format` tag every world file carries.
pub const FORMAT_TAG: &str = "glowbrick-world";
/// The version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;
/// Files larger than this are refused before reading (a full 1024x1024x1024 world of noise is far smaller in RLE
/// than its dense size, and a hostile file must not exhaust memory).
pub const MAX_FILE_BYTES: u64 = 512 * 1024 * 1024;
/// Most camera views a file may hold.
pub const MAX_VIEWS: usize = 1024;

/// How one brick's voxels are stored.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum BrickFill {
    /// All 512 voxels are this id.
    Uniform(Voxel),
    /// Run-length encoded `(count, id)` pairs covering 512 voxels.
    Runs(Vec<(u16, Voxel)>),
}

/// One non-empty brick.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct BrickRecord {
    /// Brick coordinate (voxel position / 8).
    pub at: (u32, u32, u32),
    pub fill: BrickFill,
}

/// The file as serialised.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WorldFile {
    pub format: String,
    pub version: u32,
    pub size: (u32, u32, u32),
    pub palette: Palette,
    #[serde(default)]
    pub views: Vec<CameraView>,
    /// Hours, 0-24; absent in files written before the time of day was saved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub time_of_day: Option<f32>,
    /// Moving objects (`world::objects`); absent in files written before objects were saved.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub objects: Option<Vec<super::objects::SavedObject>>,
    pub bricks: Vec<BrickRecord>,
}

/// A world file that could not be read, with where the problem is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LoadError {
    /// Where: `path` or `path:line:col`.
    pub location: String,
    pub message: String,
}

impl std::fmt::Display for LoadError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", one_line(&self.location), one_line(&self.message))
    }
}

/// `text` with its control characters escaped (`\n`), so an error quoting hostile input stays one line.
pub fn one_line(text: &str) -> String {
    let mut line = String::with_capacity(text.len());
    for c in text.chars() {
        if c.is_control() {
            line.extend(c.escape_default());
        } else {
            line.push(c);
        }
    }
    line
}

impl std::error::Error for LoadError {}

/// Encodes one brick's voxels compactly.
pub fn encode_brick(voxels: &[Voxel; BRICK_VOXELS]) -> BrickFill {
    let mut runs: Vec<(u16, Voxel)> = Vec::new();
    for &v in voxels {
        match runs.last_mut() {
            Some((count, id)) if *id == v => *count += 1,
            _ => runs.push((1, v)),
        }
    }
    if runs.len() == 1 { BrickFill::Uniform(runs[0].1) } else { BrickFill::Runs(runs) }
}

impl WorldFile {
    /// Captures a world (non-empty bricks only).
    pub fn from_world(world: &VoxelWorld) -> Self {
        let grid = &world.grid;
        let mut bricks = Vec::new();
        for (index, &raw) in grid.top_cells().iter().enumerate() {
            let cell = BrickCell::decode(raw);
            if cell == BrickCell::Empty {
                continue;
            }
            let b = grid.brick_coord(index as u32);
            let fill = match cell {
                BrickCell::Homogeneous(m) => BrickFill::Uniform(m),
                _ => encode_brick(&grid.brick_voxels(b)),
            };
            bricks.push(BrickRecord { at: (b.x as u32, b.y as u32, b.z as u32), fill });
        }
        let size = grid.size();
        WorldFile {
            format: FORMAT_TAG.to_string(),
            version: FORMAT_VERSION,
            size: (size.x, size.y, size.z),
            palette: world.palette.clone(),
            views: world.views.clone(),
            time_of_day: world.time_of_day,
            objects: world.objects.clone(),
            bricks,
        }
    }

    /// Validates everything and builds the world. `location` names the source in messages.
    pub fn into_world(self, location: &str) -> Result<VoxelWorld, LoadError> {
        let fail = |message: String| LoadError { location: location.to_string(), message };
        if self.format != FORMAT_TAG {
            return Err(fail(format!("format is '{}', expected '{FORMAT_TAG}'", self.format)));
        }
        if self.version != FORMAT_VERSION {
            return Err(fail(format!("version {} is not supported (this build reads {FORMAT_VERSION})", self.version)));
        }
        let (sx, sy, sz) = self.size;
        check_world_header(self.size, &self.palette.materials, "palette", &self.views).map_err(fail)?;
        if let Some(hours) = self.time_of_day.filter(|h| !(h.is_finite() && (0.0..=24.0).contains(h))) {
            return Err(fail(format!("time_of_day {hours} must be within 0..24 hours")));
        }
        if let Some(objects) = &self.objects {
            super::objects::check_objects(objects, UVec3::new(sx, sy, sz)).map_err(fail)?;
        }
        let mut world = VoxelWorld::new(UVec3::new(sx, sy, sz), self.palette);
        world.views = self.views;
        world.time_of_day = self.time_of_day;
        world.objects = self.objects;
        let dims = world.grid.brick_dims();
        let ids = world.palette.id_count();
        let mut seen = vec![false; (dims.x * dims.y * dims.z) as usize];
        for (i, record) in self.bricks.iter().enumerate() {
            let (bx, by, bz) = record.at;
            let here = |message: String| fail(format!("bricks[{i}] at ({bx}, {by}, {bz}): {message}"));
            if bx >= dims.x || by >= dims.y || bz >= dims.z {
                return Err(here(format!("outside the world's {}x{}x{} bricks", dims.x, dims.y, dims.z)));
            }
            let b = IVec3::new(bx as i32, by as i32, bz as i32);
            let index = world.grid.brick_index(b);
            if std::mem::replace(&mut seen[index], true) {
                return Err(here("listed twice".to_string()));
            }
            match &record.fill {
                BrickFill::Uniform(id) => {
                    if *id as usize >= ids {
                        return Err(here(format!("material id {id} out of range (palette ids 0..{})", ids - 1)));
                    }
                    world.grid.set_brick(b, &[*id; BRICK_VOXELS]);
                }
                BrickFill::Runs(runs) => {
                    let mut voxels = [0 as Voxel; BRICK_VOXELS];
                    let mut filled = 0usize;
                    for (r, &(count, id)) in runs.iter().enumerate() {
                        if id as usize >= ids {
                            return Err(here(format!(
                                "run {r}: material id {id} out of range (palette ids 0..{})",
                                ids - 1
                            )));
                        }
                        let end = filled + count as usize;
                        if end > BRICK_VOXELS {
                            return Err(here(format!("runs cover more than {BRICK_VOXELS} voxels")));
                        }
                        voxels[filled..end].fill(id);
                        filled = end;
                    }
                    if filled != BRICK_VOXELS {
                        return Err(here(format!("runs cover {filled} voxels, expected {BRICK_VOXELS}")));
                    }
                    world.grid.set_brick(b, &voxels);
                }
            }
        }
        Ok(world)
    }
}

/// Checks what world files and scene recipes share: size, materials (the list called `materials_key` in
/// messages) and camera views. Returns the first problem.
pub(crate) fn check_world_header(
    size: (u32, u32, u32),
    materials: &[Material],
    materials_key: &str,
    views: &[CameraView],
) -> Result<(), String> {
    let (sx, sy, sz) = size;
    for (axis, v) in [("x", sx), ("y", sy), ("z", sz)] {
        if v == 0 || v > MAX_WORLD_EDGE {
            return Err(format!("size.{axis} = {v} must be within 1..={MAX_WORLD_EDGE}"));
        }
    }
    if materials.len() > MAX_MATERIALS {
        return Err(format!("{materials_key} has {} materials, at most {MAX_MATERIALS} allowed", materials.len()));
    }
    if let Some((i, problem)) = materials.iter().enumerate().find_map(|(i, m)| m.problem().map(|p| (i, p))) {
        return Err(format!("{materials_key}[{i}]: {problem}"));
    }
    if views.len() > MAX_VIEWS {
        return Err(format!("{} views, at most {MAX_VIEWS} allowed", views.len()));
    }
    if let Some((i, problem)) = views.iter().enumerate().find_map(|(i, v)| v.problem().map(|p| (i, p))) {
        return Err(format!("views[{i}]: {problem}"));
    }
    Ok(())
}

/// Parses RON text with the loaders' nesting limit; a syntax or type error is located as `location:line:col`.
pub(crate) fn parse_ron<T: serde::de::DeserializeOwned>(text: &str, location: &str) -> Result<T, LoadError> {
    ron::Options::default()
        .with_recursion_limit(32)
        .from_str(text)
        .map_err(|e| LoadError { location: format!("{location}:{}", e.span.start), message: e.code.to_string() })
}

/// Parses world-file text (already read) into a world. `location` names the source in messages.
pub fn parse_world(text: &str, location: &str) -> Result<VoxelWorld, LoadError> {
    parse_ron::<WorldFile>(text, location)?.into_world(location)
}

/// Reads text from a file with a size limit, never modifying it.
pub fn read_limited(path: &Path, limit: u64) -> Result<String, LoadError> {
    let location = path.display().to_string();
    let fail = |message: String| LoadError { location: location.clone(), message };
    let meta = std::fs::metadata(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    if !meta.is_file() {
        return Err(fail("not a regular file".to_string()));
    }
    if meta.len() > limit {
        return Err(fail(format!("file is {} bytes, larger than the {limit}-byte limit", meta.len())));
    }
    let bytes = std::fs::read(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    text_from_bytes(bytes, &location)
}

/// The bytes of a text file as text, or why they are not.
pub fn text_from_bytes(bytes: Vec<u8>, location: &str) -> Result<String, LoadError> {
    String::from_utf8(bytes).map_err(|e| LoadError {
        location: location.to_string(),
        message: format!("not UTF-8 text (byte {})", e.utf8_error().valid_up_to()),
    })
}

/// Loads a RON world file.
pub fn load_world(path: &Path) -> Result<VoxelWorld, LoadError> {
    let text = read_limited(path, MAX_FILE_BYTES)?;
    parse_world(&text, &path.display().to_string())
}

/// Serialises a world to RON text.
pub fn world_to_string(world: &VoxelWorld) -> String {
    let config = ron::ser::PrettyConfig::new().depth_limit(3).struct_names(false);
    // Serialising plain data into a String cannot fail; fall back to the compact form if it ever does.
    ron::ser::to_string_pretty(&WorldFile::from_world(world), config)
        .unwrap_or_else(|e| format!("// serialisation failed: {e}\n"))
}

/// `<path>.bak`.
pub fn backup_path(path: &Path) -> std::path::PathBuf {
    let mut name = path.file_name().unwrap_or_default().to_os_string();
    name.push(".bak");
    path.with_file_name(name)
}

/// Saves with one backup: the previous save is copied to `.bak` (itself atomically) before the new one
/// replaces it, so at every moment a complete save exists on disk (the game's F5 and the server).
pub fn save_with_backup(world: &VoxelWorld, path: &Path) -> std::io::Result<()> {
    if path.is_file() {
        let previous = std::fs::read(path)?;
        write_atomically(&backup_path(path), &previous)?;
    }
    save_world(world, path)
}

/// Saves a world atomically: writes `<path>.tmp`, syncs it, then renames it over `path`.
pub fn save_world(world: &VoxelWorld, path: &Path) -> std::io::Result<()> {
    let text = world_to_string(world);
    write_atomically(path, text.as_bytes())
}

/// Writes bytes to a temporary sibling of `path` and renames it into place, so readers never see half a file.
pub fn write_atomically(path: &Path, bytes: &[u8]) -> std::io::Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir)?;
    }
    let mut tmp_name = path.file_name().unwrap_or_default().to_os_string();
    tmp_name.push(format!(".tmp{}", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let result = (|| {
        let mut file = std::fs::File::create(&tmp)?;
        file.write_all(bytes)?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    } else {
        remove_stale_temporaries(path);
    }
    result
}

/// Removes the temporaries a killed save of `path` (or of its `.bak`) left behind: `<name>.tmp<pid>` and
/// `<name>.bak.tmp<pid>` of a process that is no longer running, or older than an hour where the platform
/// cannot tell. Returns how many it removed. A save still running elsewhere keeps its temporary.
pub fn remove_stale_temporaries(path: &Path) -> usize {
    let mut removed = 0;
    for (temporary, pid) in temporaries_of(path) {
        if pid != std::process::id() && temporary_is_stale(pid, &temporary) {
            removed += std::fs::remove_file(&temporary).is_ok() as usize;
        }
    }
    removed
}

/// The temporaries of saves of `path` and of its `.bak` that exist now, with the PID of the process that wrote
/// each (`<name>.tmp<pid>`, `<name>.bak.tmp<pid>`).
pub fn temporaries_of(path: &Path) -> Vec<(std::path::PathBuf, u32)> {
    let Some(name) = path.file_name().and_then(|n| n.to_str()) else { return Vec::new() };
    let dir = path.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    let Ok(entries) = std::fs::read_dir(dir) else { return Vec::new() };
    let pid_of = |file_name: &str| {
        let rest = file_name.strip_prefix(name)?.strip_prefix('.')?;
        let rest = rest.strip_prefix("bak.").unwrap_or(rest);
        rest.strip_prefix("tmp")?.parse::<u32>().ok()
    };
    entries.flatten().filter_map(|e| Some((e.path(), e.file_name().to_str().and_then(pid_of)?))).collect()
}

fn temporary_is_stale(pid: u32, temporary: &Path) -> bool {
    if Path::new("/proc/self").exists() {
        return !Path::new(&format!("/proc/{pid}")).exists();
    }
    let age = std::fs::metadata(temporary).and_then(|m| m.modified()).ok().and_then(|t| t.elapsed().ok());
    age.is_some_and(|a| a > std::time::Duration::from_secs(3600))
}

#[cfg(test)]
mod tests {
    use super::LoadError;

    /// Found by the recipe fuzzer: a text quoting a newline from the file printed as two lines.
    #[test]
    fn an_error_quoting_a_control_character_stays_one_line() {
        let e = LoadError { location: "a.ron".into(), message: "the font has no '\n' (A-Z)".into() };
        assert_eq!(e.to_string(), "a.ron: the font has no '\\n' (A-Z)");
    }
}
