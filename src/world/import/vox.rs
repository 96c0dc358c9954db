//! MagicaVoxel `.vox` models: the RIFF-like chunk format (`VOX ` version, `MAIN` with `SIZE` + `XYZI` per model
//! and an optional `RGBA` palette). Unknown chunks (scene graph, materials, layers) are skipped. MagicaVoxel is
//! z-up; voxel (x, y, z) becomes (x, z, y) here (y up). Every read is bounds-checked: a truncated or corrupt
//! file gives one error, never a panic, and memory stays within the file's declared (and checked) sizes.

use super::BrickBuilder;
use crate::colour::srgb_to_linear;
use crate::world::format::LoadError;
use crate::world::grid::MAX_WORLD_EDGE;
use crate::world::{Material, Palette, VoxelWorld};
use bevy::math::{IVec3, UVec3};
use std::path::Path;

/// Largest `.vox` accepted (MagicaVoxel's own limit is 256^3 per model and a few hundred models).
const MAX_FILE_BYTES: u64 = 256 << 20;

/// One model as stored: its size (MagicaVoxel axes) and voxels `(x, y, z, colour index 1..=255)`.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxModel {
    pub size: [u32; 3],
    pub voxels: Vec<[u8; 4]>,
}

/// A parsed file: models and the 256-colour palette (entry `i` is colour index `i + 1`).
#[derive(Clone, Debug, PartialEq)]
pub struct VoxFile {
    pub models: Vec<VoxModel>,
    pub palette: Vec<[u8; 4]>,
}

struct Cursor<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Cursor<'a> {
    fn take(&mut self, n: usize, what: &str) -> Result<&'a [u8], String> {
        let end = self.at.checked_add(n).filter(|&e| e <= self.bytes.len());
        let end = end.ok_or_else(|| format!("truncated at byte {}: {what} needs {n} bytes", self.at))?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    fn u32(&mut self, what: &str) -> Result<u32, String> {
        let b = self.take(4, what)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }
}

/// Parses `.vox` bytes.
pub fn parse_vox(bytes: &[u8]) -> Result<VoxFile, String> {
    let mut c = Cursor { bytes, at: 0 };
    if c.take(4, "magic")? != b"VOX " {
        return Err("not a MagicaVoxel file (no 'VOX ' magic)".into());
    }
    let _version = c.u32("version")?;
    if c.take(4, "MAIN chunk id")? != b"MAIN" {
        return Err("the first chunk is not MAIN".into());
    }
    let main_content = c.u32("MAIN size")? as usize;
    let main_children = c.u32("MAIN children size")? as usize;
    c.take(main_content, "MAIN content")?;
    // Some exporters overstate MAIN's children size; the chunks themselves are still checked one by one.
    let end = c.at.saturating_add(main_children).min(bytes.len());
    let mut models = Vec::new();
    let mut pending_size: Option<[u32; 3]> = None;
    let mut palette = default_palette();
    while c.at < end {
        let id = c.take(4, "chunk id")?;
        let content = c.u32("chunk size")? as usize;
        let children = c.u32("chunk children size")? as usize;
        let body = c.take(content, "chunk content")?;
        c.take(children, "chunk children")?;
        let mut b = Cursor { bytes: body, at: 0 };
        match id {
            b"SIZE" => {
                let size = [b.u32("SIZE x")?, b.u32("SIZE y")?, b.u32("SIZE z")?];
                if size.iter().any(|&s| s == 0 || s > 256) {
                    return Err(format!("model {}: size {size:?} must be 1..=256 per axis", models.len()));
                }
                pending_size = Some(size);
            }
            b"XYZI" => {
                let size = pending_size.take().ok_or("XYZI chunk without a SIZE before it")?;
                let count = b.u32("XYZI count")? as usize;
                let data = b.take(count.checked_mul(4).ok_or("XYZI count overflows")?, "XYZI voxels")?;
                let voxels: Vec<[u8; 4]> = data.chunks_exact(4).map(|v| [v[0], v[1], v[2], v[3]]).collect();
                if let Some(v) = voxels.iter().find(|v| (0..3).any(|a| v[a] as u32 >= size[a])) {
                    return Err(format!("model {}: voxel {v:?} outside its size {size:?}", models.len()));
                }
                models.push(VoxModel { size, voxels });
            }
            b"RGBA" => {
                let data = b.take(1024, "RGBA palette")?;
                palette = data.chunks_exact(4).map(|p| [p[0], p[1], p[2], p[3]]).collect();
            }
            _ => {}
        }
    }
    if models.is_empty() {
        return Err("no models (SIZE + XYZI) in the file".into());
    }
    Ok(VoxFile { models, palette })
}

/// MagicaVoxel's palette when a file has no RGBA chunk: a 6x6x6 colour cube and ramps, close enough to tell
/// colours apart.
fn default_palette() -> Vec<[u8; 4]> {
    (0..256u32)
        .map(|i| {
            let (r, g, b) = (i % 6, (i / 6) % 6, (i / 36) % 6);
            [(r * 51) as u8, (g * 51) as u8, (b * 51) as u8, 255]
        })
        .collect()
}

/// Builds a world holding every model side by side along x (2 voxels apart), standing on y = 0.
pub fn vox_world(file: &VoxFile) -> Result<VoxelWorld, String> {
    let (mut width, mut height, mut depth) = (0u32, 1u32, 1u32);
    for m in &file.models {
        width += m.size[0] + 2;
        depth = depth.max(m.size[1]);
        height = height.max(m.size[2]);
    }
    let size = UVec3::new(width, height, depth);
    if size.cmpgt(UVec3::splat(MAX_WORLD_EDGE)).any() {
        return Err(format!(
            "the models need a {}x{}x{} world, larger than {MAX_WORLD_EDGE} per axis",
            size.x, size.y, size.z
        ));
    }
    let mut palette = Palette::default();
    let mut ids = [0u16; 256];
    let mut builder = BrickBuilder::new();
    let mut offset = 1i32;
    for model in &file.models {
        for v in &model.voxels {
            let index = v[3] as usize;
            if index == 0 {
                continue;
            }
            if ids[index] == 0 {
                let [r, g, b, _] = file.palette[index - 1];
                let albedo = [srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b)];
                ids[index] = palette.push(Material::solid(&format!("vox-{index}"), albedo));
            }
            builder.set(IVec3::new(offset + v[0] as i32, v[2] as i32, v[1] as i32), ids[index]);
        }
        offset += model.size[0] as i32 + 2;
    }
    let mut world = VoxelWorld::new(size, palette);
    builder.finish(&mut world);
    Ok(world)
}

/// Imports a `.vox` file as a world.
pub fn load_vox(path: &Path) -> Result<VoxelWorld, LoadError> {
    let fail = |message: String| LoadError { location: path.display().to_string(), message };
    let meta = std::fs::metadata(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    if meta.len() > MAX_FILE_BYTES {
        return Err(fail(format!("file is {} bytes, larger than the {MAX_FILE_BYTES}-byte limit", meta.len())));
    }
    let bytes = std::fs::read(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    let file = parse_vox(&bytes).map_err(&fail)?;
    vox_world(&file).map_err(fail)
}
