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

/// The table's layers below `lib`, bottom up, each its modules by name.
pub fn layers_bottom_up() -> Vec<Vec<String>> {
    let top = layer("cli").unwrap();
    (0..=top)
        .map(|l| {
            let mut names: Vec<String> = LAYERS.iter().filter(|(_, at)| *at == l).map(|(m, _)| m.to_string()).collect();
            names.sort();
            names
        })
        .collect()
}

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

/// The module paths a source names through `crate::` or `super::` (groups in braces expanded), comments and the
/// test module left out: `super::{gi::{self, GiCache}, pass}` names `super::gi`, `super::gi::GiCache` and `super::pass`.
fn named_paths(source: &str) -> Vec<Vec<String>> {
    let code: String = source
        .split("#[cfg(test)]")
        .next()
        .unwrap_or("")
        .lines()
        .map(|line| line.split("//").next().unwrap_or(""))
        .collect::<Vec<_>>()
        .join("\n");
    let bytes: Vec<char> = code.chars().collect();
    let mut paths = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        let starts_word = i == 0 || !(bytes[i - 1].is_alphanumeric() || bytes[i - 1] == '_' || bytes[i - 1] == ':');
        let rest: String = bytes[i..bytes.len().min(i + 7)].iter().collect();
        if starts_word && (rest.starts_with("crate::") || rest.starts_with("super::")) {
            let mut end = i;
            paths.extend(path_tree(&bytes, &mut end, Vec::new()));
            i = end.max(i + 1);
        } else {
            i += 1;
        }
    }
    paths
}

/// Reads one path from `chars[*at..]` (segments joined by `::`, a braced group expanding to several), each
/// prefixed with `prefix`.
fn path_tree(chars: &[char], at: &mut usize, prefix: Vec<String>) -> Vec<Vec<String>> {
    let mut path = prefix;
    loop {
        let skip_space = |at: &mut usize| {
            while *at < chars.len() && chars[*at].is_whitespace() {
                *at += 1;
            }
        };
        skip_space(at);
        if *at < chars.len() && chars[*at] == '{' {
            *at += 1;
            let mut out = Vec::new();
            loop {
                skip_space(at);
                if *at >= chars.len() || chars[*at] == '}' {
                    *at += 1;
                    return out;
                }
                out.extend(path_tree(chars, at, path.clone()));
                skip_space(at);
                if *at < chars.len() && chars[*at] == ',' {
                    *at += 1;
                }
            }
        }
        let start = *at;
        while *at < chars.len() && (chars[*at].is_alphanumeric() || chars[*at] == '_') {
            *at += 1;
        }
        let segment: String = chars[start..*at].iter().collect();
        if !segment.is_empty() && segment != "self" {
            path.push(segment);
        }
        if chars.get(*at) == Some(&':') && chars.get(*at + 1) == Some(&':') {
            *at += 2;
        } else {
            return vec![path];
        }
    }
}

/// A source file's module path from `src/` (`render/gi/mod.rs` is `render::gi`).
fn module_of(relative: &Path) -> Vec<String> {
    let mut parts: Vec<String> =
        relative.iter().map(|c| c.to_str().unwrap().trim_end_matches(".rs").to_string()).collect();
    if parts.last().is_some_and(|p| p == "mod") {
        parts.pop();
    }
    parts
}

/// `path` as named in module `module`, made absolute from the crate root.
fn resolve(module: &[String], path: &[String]) -> Vec<String> {
    let mut base: Vec<String> = Vec::new();
    let mut rest = path;
    if rest.first().is_some_and(|s| s == "crate") {
        rest = &rest[1..];
    } else {
        base = module.to_vec();
        while rest.first().is_some_and(|s| s == "super") {
            base.pop();
            rest = &rest[1..];
        }
    }
    base.extend(rest.iter().cloned());
    base
}

/// For every folder of `render/`, the edges between its children (`a` names something of `b`): a module's
/// references to its siblings and their descendants, as seen from the folder both live in.
fn render_module_edges(src: &Path) -> Vec<(Vec<String>, String, String)> {
    let mut files = Vec::new();
    rust_files(&src.join("render"), &mut files);
    let modules: Vec<Vec<String>> = files.iter().map(|f| module_of(f.strip_prefix(src).unwrap())).collect();
    let is_module = |path: &[String]| modules.iter().any(|m| m.as_slice() == path);
    let mut edges = Vec::new();
    for (file, module) in files.iter().zip(&modules) {
        let source = std::fs::read_to_string(file).unwrap();
        for named in named_paths(&source) {
            let target = resolve(module, &named);
            let common = module.iter().zip(&target).take_while(|(a, b)| a == b).count();
            if common == 0 || common >= module.len() || common >= target.len() {
                continue;
            }
            let folder = module[..common].to_vec();
            let (from, to) = (&module[common], &target[common]);
            let child = |name: &String| [folder.clone(), vec![name.clone()]].concat();
            if is_module(&child(from)) && is_module(&child(to)) {
                edges.push((folder, from.clone(), to.clone()));
            }
        }
    }
    edges.sort();
    edges.dedup();
    edges
}

/// A circle in `edges` (from, to), as the modules along it, if there is one.
fn find_circle(edges: &[(String, String)]) -> Option<Vec<String>> {
    fn visit(
        node: &str,
        edges: &[(String, String)],
        path: &mut Vec<String>,
        done: &mut std::collections::HashSet<String>,
    ) -> Option<Vec<String>> {
        if let Some(at) = path.iter().position(|n| n == node) {
            let mut circle = path[at..].to_vec();
            circle.push(node.to_string());
            return Some(circle);
        }
        if done.contains(node) {
            return None;
        }
        path.push(node.to_string());
        for (_, to) in edges.iter().filter(|(from, _)| from == node) {
            if let Some(circle) = visit(to, edges, path, done) {
                return Some(circle);
            }
        }
        path.pop();
        done.insert(node.to_string());
        None
    }
    let mut done = std::collections::HashSet::new();
    edges.iter().find_map(|(from, _)| visit(from, edges, &mut Vec::new(), &mut done))
}

/// Inside `render/` imports point one way too: no circle of modules naming each other within any of its folders
/// (the contract `gpu_types` and the data `plan`, `pass` and `interface` name no technique; techniques name no
/// `frame`).
#[test]
fn no_circle_of_imports_inside_render() {
    let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("src");
    let edges = render_module_edges(&src);
    assert!(edges.len() > 20, "found only {} edges: {edges:?}", edges.len());
    let mut folders: Vec<&Vec<String>> = edges.iter().map(|(f, _, _)| f).collect();
    folders.dedup();
    for folder in folders {
        let local: Vec<(String, String)> =
            edges.iter().filter(|(f, _, _)| f == folder).map(|(_, a, b)| (a.clone(), b.clone())).collect();
        assert_eq!(find_circle(&local), None, "a circle of imports in src/{}", folder.join("/"));
    }
}

/// The checker reads grouped and relative paths and finds a circle.
#[test]
fn the_circle_checker_sees_grouped_paths_and_a_circle() {
    let named =
        named_paths("use super::{gi::{self, GiCache}, pass};\n// super::ignored\nlet x = crate::render::frame::f;");
    let strings: Vec<String> = named.iter().map(|p| p.join("::")).collect();
    assert_eq!(strings, ["super::gi", "super::gi::GiCache", "super::pass", "crate::render::frame::f"]);
    let module = module_of(Path::new("render/gi/mod.rs"));
    assert_eq!(resolve(&module, &named[1]), ["render", "gi", "GiCache"]);
    let edge = |a: &str, b: &str| (a.to_string(), b.to_string());
    assert_eq!(find_circle(&[edge("a", "b"), edge("b", "c")]), None);
    assert_eq!(find_circle(&[edge("a", "b"), edge("b", "c"), edge("c", "a")]).map(|c| c.len()), Some(4));
}
