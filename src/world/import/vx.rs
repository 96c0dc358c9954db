//! The thesis' `.vx` scenes (`../shared/scenes/README.md`): a gzip stream of `i32 2, i32 1, i32 sx, sy, sz,
//! u32 n`, then `n` packed positions `x | y << 10 | z << 20`, then `n` u16 values (blue, green, red, strength
//! in 4 bits each, 0 = empty). Entries apply in order, the last write wins.
//!
//! Decompressed, a file is about 400 MB and positions come before values, so the importer opens the gzip stream
//! twice and reads positions and values side by side: memory stays bounded by the world, never the payload.
//! Colours follow the thesis: albedo = c / 15, emitted radiance = c / 15 x strength / pi.
//!
//! The thesis' renderer is left-handed (+x is to the right looking along +z, y up); ours is right-handed. The
//! importer mirrors x about the scene's own width rounded up to whole bricks (`mirror_width`: x -> W - 1 - x, a
//! multiple of 8 so aligned bricks stay aligned; the thesis' 1027-wide scenes give x -> 1031 - x) and mirrors the
//! thesis' camera views with it, so its letters read the right way round and its views see what the thesis shows.

use super::BrickBuilder;
use crate::progress::Progress;
use crate::world::format::LoadError;
use crate::world::grid::{BRICK_SIZE, MAX_WORLD_EDGE};
use crate::world::{CameraView, Material, Palette, VoxelWorld};
use bevy::math::{IVec3, UVec3};
use flate2::read::GzDecoder;
use std::collections::HashMap;
use std::fs::File;
use std::io::{BufReader, Read};
use std::path::Path;

/// Largest compressed file accepted.
const MAX_FILE_BYTES: u64 = 1 << 30;
/// Most entries accepted (the thesis' files hold about 67 million).
const MAX_ENTRIES: u32 = 400_000_000;

/// The decompressed stream of a `.vx` file.
pub fn open(path: &Path) -> Result<impl Read + use<>, String> {
    let file = File::open(path).map_err(|e| format!("cannot read: {e}"))?;
    Ok(GzDecoder::new(BufReader::with_capacity(1 << 16, file)))
}

fn read_u32(r: &mut impl Read, what: &str) -> Result<u32, String> {
    let mut b = [0u8; 4];
    r.read_exact(&mut b).map_err(|e| format!("truncated or corrupt while reading {what}: {e}"))?;
    Ok(u32::from_le_bytes(b))
}

/// Skips `bytes` of decompressed data.
fn skip(r: &mut impl Read, bytes: u64, what: &str) -> Result<(), String> {
    let copied = std::io::copy(&mut r.take(bytes), &mut std::io::sink()).map_err(|e| format!("corrupt {what}: {e}"))?;
    if copied != bytes { Err(format!("truncated: {what} ends after {copied} of {bytes} bytes")) } else { Ok(()) }
}

/// The material of a `.vx` value, by the thesis' conventions.
fn material_for(value: u16) -> Material {
    let channel = |shift: u16| ((value >> shift) & 15) as f32 / 15.0;
    let (r, g, b, s) = (channel(8), channel(4), channel(0), (value >> 12) & 15);
    let name = format!("vx-{:03x}-s{s}", value & 0x0fff);
    if s > 0 {
        Material::emissive(&name, [r, g, b], [r, g, b], s as f32 / std::f32::consts::PI)
    } else {
        Material::solid(&name, [r, g, b])
    }
}

/// The width a scene `width` voxels wide is mirrored about (and the imported world's x size): rounded up to whole
/// bricks. Voxel x becomes `mirror - 1 - x`; a point's x becomes `mirror - x`.
pub fn mirror_width(width: u32) -> u32 {
    width.div_ceil(BRICK_SIZE as u32) * BRICK_SIZE as u32
}

/// The thesis' camera views (README of `../shared/scenes`, vertical field of view 48.89 degrees), mirrored in x
/// about `mirror` like the voxels.
pub fn thesis_views(file_stem: &str, mirror: u32) -> Vec<CameraView> {
    let view = |name: &str, o: [f32; 3], d: [f32; 3]| CameraView {
        name: name.into(),
        origin: [mirror as f32 - o[0], o[1], o[2]],
        direction: [-d[0], d[1], d[2]],
        fov_deg: 48.89,
    };
    match file_stem {
        "letters" => vec![
            view("letters1", [152.32, 59.82, -49.48], [0.11, -0.22, 0.97]),
            view("letters2", [195.35, 84.76, 264.97], [-0.48, -0.28, -0.83]),
        ],
        "cornellbox" => vec![view("cornell1", [81.18, 196.95, -284.07], [0.11, -0.22, 0.97])],
        _ => Vec::new(),
    }
}

/// Imports a `.vx` file.
pub fn load_vx(path: &Path) -> Result<VoxelWorld, LoadError> {
    let location = path.display().to_string();
    let fail = |message: String| LoadError { location: location.clone(), message };
    let meta = std::fs::metadata(path).map_err(|e| fail(format!("cannot read: {e}")))?;
    if meta.len() > MAX_FILE_BYTES {
        return Err(fail(format!("file is {} bytes, larger than the {MAX_FILE_BYTES}-byte limit", meta.len())));
    }
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    read_vx(|| open(path), stem, &location)
}

/// Imports a `.vx` scene from its gzip stream, opened twice by `open` (positions and values are read side by
/// side). `stem` names the thesis scene whose camera views it gets.
pub fn read_vx<R: Read>(
    open: impl Fn() -> Result<R, String>,
    stem: &str,
    location: &str,
) -> Result<VoxelWorld, LoadError> {
    let fail = |message: String| LoadError { location: location.to_string(), message };
    let mut positions = open().map_err(&fail)?;
    let header: Vec<u32> = (0..6)
        .map(|i| read_u32(&mut positions, &format!("header word {i}")))
        .collect::<Result<_, _>>()
        .map_err(&fail)?;
    if header[0] != 2 || header[1] != 1 {
        return Err(fail(format!(
            "not a .vx scene: header starts {} {}, expected 2 1",
            header[0] as i32, header[1] as i32
        )));
    }
    let size = UVec3::new(header[2], header[3], header[4]);
    if size.cmpeq(UVec3::ZERO).any() {
        return Err(fail(format!("size {}x{}x{} has an empty axis", size.x, size.y, size.z)));
    }
    let n = header[5];
    if n > MAX_ENTRIES {
        return Err(fail(format!("{n} entries, at most {MAX_ENTRIES} allowed")));
    }
    let mirror = mirror_width(size.x);
    if size.with_x(mirror).cmpgt(UVec3::splat(MAX_WORLD_EDGE)).any() {
        return Err(fail(format!("size {}x{}x{} exceeds {MAX_WORLD_EDGE} per axis", size.x, size.y, size.z)));
    }
    let world_size = size.with_x(mirror);
    let mut world = VoxelWorld::new(world_size, Palette::default());
    world.views = thesis_views(stem, mirror);

    let mut values = open().map_err(&fail)?;
    skip(&mut values, 24 + 4 * n as u64, "the position block").map_err(&fail)?;
    let mut positions = BufReader::with_capacity(1 << 20, positions);
    let mut values = BufReader::with_capacity(1 << 20, values);
    let mut ids: HashMap<u16, u16> = HashMap::new();
    let mut builder = BrickBuilder::new();
    let (mut pos_buf, mut val_buf) = (vec![0u8; 4 << 16], vec![0u8; 2 << 16]);
    let mut done = 0u32;
    // The thesis' scenes hold tens of millions of entries (seconds): show how far the import is.
    let progress = (n >= 1 << 22).then(|| Progress::new("import", n as u64));
    while done < n {
        let count = (n - done).min(1 << 16) as usize;
        positions
            .read_exact(&mut pos_buf[..4 * count])
            .map_err(|e| fail(format!("truncated positions at entry {done}: {e}")))?;
        values
            .read_exact(&mut val_buf[..2 * count])
            .map_err(|e| fail(format!("truncated values at entry {done}: {e}")))?;
        for i in 0..count {
            let packed =
                u32::from_le_bytes([pos_buf[4 * i], pos_buf[4 * i + 1], pos_buf[4 * i + 2], pos_buf[4 * i + 3]]);
            let value = u16::from_le_bytes([val_buf[2 * i], val_buf[2 * i + 1]]);
            // x and y take 10 bits each; z takes the upper 12 (the scenes are 1027 deep).
            let x = mirror as i32 - 1 - (packed & 1023) as i32;
            let p = IVec3::new(x, ((packed >> 10) & 1023) as i32, (packed >> 20) as i32);
            if (packed & 1023) >= size.x || !world.grid.contains(p) {
                return Err(fail(format!(
                    "entry {}: position ({}, {}, {}) outside the {}x{}x{} scene",
                    done as usize + i,
                    packed & 1023,
                    p.y,
                    p.z,
                    size.x,
                    size.y,
                    size.z
                )));
            }
            let id = if value == 0 {
                0
            } else {
                match ids.get(&value) {
                    Some(&id) => id,
                    None => {
                        let id = world.palette.push(material_for(value));
                        ids.insert(value, id);
                        id
                    }
                }
            };
            builder.set(p, id);
        }
        done += count as u32;
        if let Some(progress) = &progress {
            progress.advance(count as u64);
        }
    }
    if let Some(progress) = progress {
        progress.finish();
    }
    builder.finish(&mut world);
    Ok(world)
}
