//! The fuzzer's seeds: real files from the source tree (`saves/`, `assets/`, `tests/data/`), one list per
//! loader. A seed that takes longer than `SLOW_SEED` to load is left out (and named in the report): the
//! fuzzer's throughput is what lets a run reach a million inputs, and the scene it would build is the same
//! code path as the smaller seeds'.

use super::Target;
use crate::settings::SETTINGS;
use crate::world::format::{FORMAT_TAG, world_to_string};
use crate::world::import::vx;
use crate::world::recipe::generated_world;
use bevy::math::UVec3;
use std::io::{Read, Write};
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

/// Seeds slower than this to load are left out.
pub const SLOW_SEED: Duration = Duration::from_millis(50);
/// Entries a `.vx` seed keeps from the head of a thesis scene.
const VX_SEED_ENTRIES: u32 = 1024;

/// One corpus file, as the loader reads it (a `.vx` seed is its decompressed payload).
#[derive(Clone, Debug)]
pub struct Seed {
    pub name: String,
    pub bytes: Vec<u8>,
}

/// The source tree the corpus comes from.
fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// Files under `dir` (recursively) whose name ends in `.ext`, sorted.
fn files(dir: &Path, ext: &str, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else { return };
    let mut paths: Vec<PathBuf> = entries.filter_map(|e| e.ok().map(|e| e.path())).collect();
    paths.sort();
    for path in paths {
        if path.is_dir() {
            files(&path, ext, out);
        } else if path.extension().is_some_and(|e| e == ext) {
            out.push(path);
        }
    }
}

fn named(path: &Path, bytes: Vec<u8>) -> Seed {
    let name = path.strip_prefix(root()).unwrap_or(path).display().to_string();
    Seed { name, bytes }
}

/// gzip at the fastest level (the `.vx` inputs are compressed once each).
pub fn gzip(bytes: &[u8]) -> Vec<u8> {
    let mut encoder = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::fast());
    // Writing into a Vec cannot fail.
    let _ = encoder.write_all(bytes);
    encoder.finish().unwrap_or_default()
}

/// The head of a thesis `.vx` scene, decompressed: its header with the entry count cut to `VX_SEED_ENTRIES`,
/// those entries' positions and their values.
fn vx_head(path: &Path) -> Result<Vec<u8>, String> {
    let mut stream = vx::open(path)?;
    let mut header = [0u8; 24];
    stream.read_exact(&mut header).map_err(|e| format!("{}: {e}", path.display()))?;
    let n = u32::from_le_bytes([header[20], header[21], header[22], header[23]]);
    let k = n.min(VX_SEED_ENTRIES);
    let mut positions = vec![0u8; 4 * k as usize];
    stream.read_exact(&mut positions).map_err(|e| format!("{}: {e}", path.display()))?;
    let rest = 4 * (n - k) as u64;
    std::io::copy(&mut (&mut stream).take(rest), &mut std::io::sink()).map_err(|e| e.to_string())?;
    let mut values = vec![0u8; 2 * k as usize];
    stream.read_exact(&mut values).map_err(|e| format!("{}: {e}", path.display()))?;
    header[20..24].copy_from_slice(&k.to_le_bytes());
    Ok([header.as_slice(), &positions, &values].concat())
}

/// Every key at its default, as a settings file.
fn all_settings() -> String {
    let pairs: Vec<String> = SETTINGS.iter().map(|s| format!("{:?}: {:?}", s.key, s.default_value())).collect();
    format!("{{{}}}", pairs.join(", "))
}

/// A `world.ron` of an endless world with every field: a player a million voxels out and a time of day.
fn endless_world_file() -> Vec<u8> {
    let text = "(format: \"glowbrick-endless-world\", version: 1, seed: 7, height: 192, player: Some((region: \
                (15625, -3), view: (name: \"player\", origin: (10.25, 80.5, 3.125), direction: (0.0, -0.5, 1.0), \
                fov_deg: 70.0))), time_of_day: Some(18.5))";
    text.as_bytes().to_vec()
}

/// The seeds of `target` and the files left out (with why).
pub fn seeds(target: Target) -> Result<(Vec<Seed>, Vec<String>), String> {
    let root = root();
    let mut paths = Vec::new();
    let mut seeds = Vec::new();
    match target {
        Target::World => {
            files(&root.join("saves"), "ron", &mut paths);
            files(&root.join("tests/data"), "ron", &mut paths);
            let small = generated_world(4, UVec3::new(24, 16, 24)).map_err(|e| e.to_string())?;
            seeds.push(Seed { name: "a generated 24x16x24 world".into(), bytes: world_to_string(&small).into_bytes() });
        }
        Target::Recipe => files(&root.join("assets/scenes"), "ron", &mut paths),
        Target::Vx => {
            let mut thesis = Vec::new();
            files(&root.join("tests/data"), "vx", &mut thesis);
            for path in thesis {
                let name = format!("{} (first {VX_SEED_ENTRIES} entries)", named(&path, Vec::new()).name);
                seeds.push(Seed { name, bytes: vx_head(&path)? });
            }
        }
        Target::Vox => files(&root.join("tests/data"), "vox", &mut paths),
        Target::Settings => {
            files(&root.join("assets/settings"), "ron", &mut paths);
            seeds.push(Seed { name: "every key at its default".into(), bytes: all_settings().into_bytes() });
        }
        Target::Endless => {
            seeds.push(Seed { name: "an endless world's world.ron".into(), bytes: endless_world_file() })
        }
    }
    for path in paths {
        let bytes = std::fs::read(&path).map_err(|e| format!("{}: {e}", path.display()))?;
        let is_world = String::from_utf8_lossy(&bytes).contains(FORMAT_TAG);
        if matches!(target, Target::World | Target::Recipe) && is_world != (target == Target::World) {
            continue; // a world file in a recipe folder or the other way round
        }
        seeds.push(named(&path, bytes));
    }
    // Every seed must load (a corpus of broken files would fuzz only the first check); slow ones are left out.
    let mut left_out = Vec::new();
    let mut kept = Vec::new();
    for seed in seeds {
        let file = if target == Target::Vx { gzip(&seed.bytes) } else { seed.bytes.clone() };
        let start = Instant::now();
        let loaded = target.load(&file);
        let took = start.elapsed();
        match loaded {
            Err(e) => return Err(format!("fuzz corpus: {} does not load: {e}", seed.name)),
            Ok(_) if took > SLOW_SEED => {
                left_out.push(format!("{} (loads in {:.0} ms)", seed.name, took.as_secs_f64() * 1e3))
            }
            Ok(_) => kept.push(seed),
        }
    }
    if kept.is_empty() {
        return Err(format!(
            "fuzz corpus for {}: no seeds under {} (run from a source checkout)",
            target.name(),
            root.display()
        ));
    }
    Ok((kept, left_out))
}
