//! Imports point one way (README "Layout"): no source file names a module of a layer above its own, and the
//! CPU-only layers (world, lights, dynamic, reference, colour, image files) use none of Bevy's render crates.

use std::path::{Path, PathBuf};

/// Each top-level module of `src/` and its layer, bottom (0) to top.
const LAYERS: [(&str, u32); 19] = [
    ("alloc_watch", 0),
    ("colour", 0),
    ("progress", 0),
    ("image_io", 0),
    ("world", 1),
    ("lights", 2),
    ("dynamic", 2),
    ("reference", 2),
    ("settings", 3),
    ("render", 3),
    ("core_plugin", 3),
    ("net", 3),
    ("game", 4),
    ("headless", 4),
    ("bench", 5),
    ("stress", 5),
    ("cli", 6),
    ("lib", 7),
    ("main", 8),
];

/// Layers that must not depend on the GPU.
const CPU_ONLY: [&str; 8] =
    ["alloc_watch", "colour", "progress", "image_io", "world", "lights", "dynamic", "reference"];
const RENDER_CRATES: [&str; 4] = ["bevy::render", "bevy::core_pipeline", "bevy::shader", "bevy::camera"];

fn layer(module: &str) -> Option<u32> {
    LAYERS.iter().find(|(m, _)| *m == module).map(|&(_, l)| l)
}

fn rust_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            rust_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs") {
            out.push(path);
        }
    }
}

/// The top-level modules a source file names as `crate::<module>`.
fn crate_imports(source: &str) -> Vec<&str> {
    source
        .match_indices("crate::")
        .map(|(i, _)| {
            let rest = &source[i + "crate::".len()..];
            let end = rest.find(|c: char| !(c.is_ascii_alphanumeric() || c == '_')).unwrap_or(rest.len());
            &rest[..end]
        })
        .collect()
}

#[test]
fn no_source_file_imports_from_a_layer_above_its_own() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let mut files = Vec::new();
    rust_files(&src, &mut files);
    assert!(files.len() > 40, "found only {} source files", files.len());
    let mut violations = Vec::new();
    for file in &files {
        let relative = file.strip_prefix(&src).unwrap();
        let module = relative.components().next().unwrap().as_os_str().to_str().unwrap().trim_end_matches(".rs");
        let own =
            layer(module).unwrap_or_else(|| panic!("{module} (src/{}) has no layer in LAYERS", relative.display()));
        let source = std::fs::read_to_string(file).unwrap();
        for import in crate_imports(&source) {
            match layer(import) {
                Some(l) if l > own => violations.push(format!("src/{} uses crate::{import}", relative.display())),
                None => violations.push(format!("src/{}: crate::{import} has no layer", relative.display())),
                _ => {}
            }
        }
        if CPU_ONLY.contains(&module) {
            for krate in RENDER_CRATES.iter().filter(|k| source.contains(*k)) {
                violations.push(format!("src/{} (CPU only) uses {krate}", relative.display()));
            }
        }
    }
    assert!(violations.is_empty(), "imports that point up:\n{}", violations.join("\n"));
}

#[test]
fn the_checker_sees_an_upward_import() {
    assert_eq!(crate_imports("use crate::render::frame;\nlet x = crate::world::grid::AIR;"), ["render", "world"]);
    assert!(layer("render") > layer("world"));
}
