//! MagicaVoxel `.vox` models: the RIFF-like chunk format (`VOX ` version, `MAIN` with `SIZE` + `XYZI` per model,
//! an optional `RGBA` palette, and in files from MagicaVoxel 0.99 on the scene graph and materials). With a
//! scene graph (`nTRN` transforms, `nGRP` groups, `nSHP` shapes, `LAYR` layers) the models are laid out as the
//! artist placed them: translations summed from the root, hidden nodes and hidden layers left out, a shape's
//! first model used (the others are animation frames), rotations ignored (stated in the import summary's
//! counts: `rotated`). Without one, the models stand side by side. `MATL` materials of type `_emit` become
//! emissive materials (strength `EMIT_STRENGTH * _emit * (1 + _flux)`, so they join the light pool); every other
//! type is read as diffuse. MagicaVoxel is z-up; voxel (x, y, z) becomes (x, z, y) here (y up). Every read is bounds-checked: a truncated or corrupt
//! file gives one error, never a panic, and memory stays within the file's declared (and checked) sizes.
//!
//! Why our own reader and not the `dot_vox` crate (5.x), which reads the same chunks: the product's dependencies
//! are the ones its card names (bevy, wgpu, glam, noise, serde, ron), and this reader's guarantees are measured
//! where a player's files reach it: `glowbrick stress --fuzz` runs it on mutated MagicaVoxel files, scene graphs
//! included (2,000,000 inputs, 0 findings after the one fixed: `docs/bench/stress.md`), with its heap counted per
//! input. A crate swap would have to pass the same run.

use super::BrickBuilder;
use crate::colour::srgb_to_linear;
use crate::world::format::{LoadError, one_line};
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

/// A parsed file: models, the 256-colour palette (entry `i` is colour index `i + 1`), the placed models of its
/// scene graph (empty without one) and the emission of its emissive materials by colour index.
#[derive(Clone, Debug, PartialEq)]
pub struct VoxFile {
    pub models: Vec<VoxModel>,
    pub palette: Vec<[u8; 4]>,
    pub placed: Vec<Placed>,
    /// `(colour index 1..=255, strength)` of materials of type `_emit`.
    pub emissive: Vec<(u8, f32)>,
    /// Shapes whose transform had a rotation (laid out unrotated).
    pub rotated: u32,
}

/// A model placed by the scene graph: its index and the translation of its centre (MagicaVoxel axes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Placed {
    pub model: usize,
    pub translation: [i32; 3],
}

/// A material of type `_emit` with `_emit = 1` and `_flux = 0` gets this strength (the thesis' white lamp is
/// 15 / pi = 4.8).
pub const EMIT_STRENGTH: f32 = 5.0;
/// Most scene-graph nodes and dictionary entries read (MagicaVoxel writes a few per model): a hostile count
/// cannot make the importer allocate more.
const MAX_NODES: usize = 1 << 16;
const MAX_DICT_ENTRIES: usize = 256;

/// A scene-graph node.
#[derive(Clone, Debug)]
enum Node {
    Transform { child: i32, layer: i32, translation: [i32; 3], rotated: bool, hidden: bool },
    Group { children: Vec<i32> },
    Shape { model: Option<usize> },
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

    fn i32(&mut self, what: &str) -> Result<i32, String> {
        Ok(self.u32(what)? as i32)
    }

    fn string(&mut self, what: &str) -> Result<String, String> {
        let len = self.u32(what)? as usize;
        Ok(String::from_utf8_lossy(self.take(len, what)?).into_owned())
    }

    /// A `DICT`: a count, then key and value strings.
    fn dict(&mut self, what: &str) -> Result<Vec<(String, String)>, String> {
        let count = self.u32(what)? as usize;
        if count > MAX_DICT_ENTRIES {
            return Err(format!("{what}: {count} dictionary entries (at most {MAX_DICT_ENTRIES})"));
        }
        (0..count).map(|_| Ok((self.string(what)?, self.string(what)?))).collect()
    }
}

fn lookup<'a>(dict: &'a [(String, String)], key: &str) -> Option<&'a str> {
    dict.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

/// A scene-graph node's chunk body, its id and the node.
fn parse_node(id: &[u8], b: &mut Cursor) -> Result<(i32, Node), String> {
    let node_id = b.i32("node id")?;
    let attributes = b.dict("node attributes")?;
    let hidden = lookup(&attributes, "_hidden") == Some("1");
    let node = match id {
        b"nTRN" => {
            let child = b.i32("nTRN child")?;
            let _reserved = b.i32("nTRN reserved")?;
            let layer = b.i32("nTRN layer")?;
            let frames = b.u32("nTRN frames")?;
            let mut translation = [0; 3];
            let mut rotated = false;
            // The first frame places the node (more frames are an animation).
            if frames > 0 {
                let frame = b.dict("nTRN frame")?;
                if let Some(t) = lookup(&frame, "_t") {
                    let parts: Vec<i32> = t.split_whitespace().filter_map(|p| p.parse().ok()).collect();
                    if parts.len() != 3 || parts.iter().any(|p| p.unsigned_abs() > 1 << 20) {
                        // Quoted escaped: the file's text may hold line breaks (found by the fuzzer).
                        return Err(format!("node {node_id}: translation '{}' is not three integers", one_line(t)));
                    }
                    translation = [parts[0], parts[1], parts[2]];
                }
                // _r is a packed rotation; 4 is MagicaVoxel's identity (rows x, y, z in place, no signs).
                rotated = lookup(&frame, "_r").is_some_and(|r| r != "4");
            }
            Node::Transform { child, layer, translation, rotated, hidden }
        }
        b"nGRP" => {
            let count = b.u32("nGRP children")? as usize;
            if count > MAX_NODES {
                return Err(format!("node {node_id}: {count} children (at most {MAX_NODES})"));
            }
            Node::Group { children: (0..count).map(|_| b.i32("nGRP child")).collect::<Result<_, _>>()? }
        }
        _ => {
            let count = b.u32("nSHP models")?;
            // The first model is the shape; the others are animation frames.
            let model = if count > 0 { Some(b.u32("nSHP model")? as usize) } else { None };
            Node::Shape { model }
        }
    };
    Ok((node_id, node))
}

/// Walks the scene graph from node 0: the models it shows and where, and how many were rotated.
fn place_models(
    nodes: &std::collections::HashMap<i32, Node>,
    hidden_layers: &[i32],
    models: usize,
) -> Result<(Vec<Placed>, u32), String> {
    let mut placed = Vec::new();
    let mut rotated = 0;
    // (node, translation so far, rotated above); depth-bounded by the node count (a cycle is an error).
    let mut stack = vec![(0i32, [0i32; 3], false, 0usize)];
    while let Some((id, at, turned, depth)) = stack.pop() {
        if depth > nodes.len() {
            return Err("the scene graph has a cycle".into());
        }
        let Some(node) = nodes.get(&id) else {
            return Err(format!("the scene graph names node {id}, which the file does not hold"));
        };
        match node {
            Node::Transform { child, layer, translation, rotated: r, hidden } => {
                if *hidden || hidden_layers.contains(layer) {
                    continue;
                }
                let t = [at[0] + translation[0], at[1] + translation[1], at[2] + translation[2]];
                stack.push((*child, t, turned || *r, depth + 1));
            }
            Node::Group { children } => stack.extend(children.iter().map(|&c| (c, at, turned, depth + 1))),
            Node::Shape { model: Some(model) } => {
                if *model >= models {
                    return Err(format!("a shape names model {model}; the file holds {models}"));
                }
                rotated += turned as u32;
                placed.push(Placed { model: *model, translation: at });
            }
            Node::Shape { model: None } => {}
        }
        if placed.len() > MAX_NODES {
            return Err(format!("the scene graph places more than {MAX_NODES} models"));
        }
    }
    Ok((placed, rotated))
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
    let mut nodes = std::collections::HashMap::new();
    let mut hidden_layers = Vec::new();
    let mut emissive = Vec::new();
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
            b"nTRN" | b"nGRP" | b"nSHP" => {
                if nodes.len() >= MAX_NODES {
                    return Err(format!("more than {MAX_NODES} scene-graph nodes"));
                }
                let (node_id, node) = parse_node(id, &mut b)?;
                nodes.insert(node_id, node);
            }
            b"LAYR" => {
                let layer = b.i32("LAYR id")?;
                if lookup(&b.dict("LAYR attributes")?, "_hidden") == Some("1") {
                    hidden_layers.push(layer);
                }
            }
            b"MATL" => {
                let index = b.u32("MATL id")?;
                let properties = b.dict("MATL properties")?;
                let number = |key: &str| lookup(&properties, key).and_then(|v| v.parse::<f32>().ok());
                if lookup(&properties, "_type") == Some("_emit") && (1..=255).contains(&index) {
                    let emit = number("_emit").unwrap_or(0.0);
                    let flux = number("_flux").unwrap_or(0.0);
                    let strength = EMIT_STRENGTH * emit * (1.0 + flux);
                    if !(strength.is_finite() && (0.0..=1.0e6).contains(&strength)) {
                        return Err(format!("material {index}: emission {emit} x flux {flux} is out of range"));
                    }
                    if strength > 0.0 {
                        emissive.push((index as u8, strength));
                    }
                }
            }
            _ => {}
        }
    }
    if models.is_empty() {
        return Err("no models (SIZE + XYZI) in the file".into());
    }
    let (placed, rotated) =
        if nodes.is_empty() { (Vec::new(), 0) } else { place_models(&nodes, &hidden_layers, models.len())? };
    Ok(VoxFile { models, palette, placed, emissive, rotated })
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

/// Where each shown model's voxel (0, 0, 0) lands, in MagicaVoxel axes: by the scene graph (a translation places
/// the model's centre, `size / 2` rounded down), or side by side along x, 2 voxels apart, without one.
fn layout(file: &VoxFile) -> Vec<(usize, [i64; 3])> {
    if file.placed.is_empty() {
        let mut x = 1i64;
        return file
            .models
            .iter()
            .enumerate()
            .map(|(i, m)| {
                let at = (i, [x, 0, 0]);
                x += m.size[0] as i64 + 2;
                at
            })
            .collect();
    }
    file.placed
        .iter()
        .map(|p| {
            let size = file.models[p.model].size;
            (p.model, [0, 1, 2].map(|a| p.translation[a] as i64 - (size[a] / 2) as i64))
        })
        .collect()
}

/// Builds a world holding the file's models as laid out (`layout`), moved so the lowest corner is at the
/// origin (plus a voxel of margin along x without a scene graph, as before).
pub fn vox_world(file: &VoxFile) -> Result<VoxelWorld, String> {
    let placed = layout(file);
    let mut lo = [i64::MAX; 3];
    let mut hi = [i64::MIN; 3];
    for &(model, at) in &placed {
        let size = file.models[model].size;
        for a in 0..3 {
            lo[a] = lo[a].min(at[a]);
            hi[a] = hi[a].max(at[a] + size[a] as i64);
        }
    }
    if file.placed.is_empty() {
        lo = [0; 3];
        hi[0] += 1;
    }
    // MagicaVoxel (x, y, z) is our (x, z, y).
    let extent = |a: usize| (hi[a] - lo[a]).max(1);
    let (sx, sy, sz) = (extent(0), extent(2), extent(1));
    if [sx, sy, sz].iter().any(|&e| e > MAX_WORLD_EDGE as i64) {
        return Err(format!("the models need a {sx}x{sy}x{sz} world, larger than {MAX_WORLD_EDGE} per axis"));
    }
    let size = UVec3::new(sx as u32, sy as u32, sz as u32);
    let mut palette = Palette::default();
    let mut ids = [0u16; 256];
    let mut builder = BrickBuilder::new();
    for &(model, at) in &placed {
        for v in &file.models[model].voxels {
            let index = v[3] as usize;
            if index == 0 {
                continue;
            }
            if ids[index] == 0 {
                let [r, g, b, _] = file.palette[index - 1];
                let albedo = [srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b)];
                let name = format!("vox-{index}");
                let material = match file.emissive.iter().find(|(i, _)| *i as usize == index) {
                    Some(&(_, strength)) => Material::emissive(&name, albedo, albedo, strength),
                    None => Material::solid(&name, albedo),
                };
                ids[index] = palette.push(material);
            }
            let p = [0, 1, 2].map(|a| (at[a] + v[a] as i64 - lo[a]) as i32);
            builder.set(IVec3::new(p[0], p[2], p[1]), ids[index]);
        }
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
