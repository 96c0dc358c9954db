//! The code's shape, checked on every file: no function over 100 lines (but the two traversal twins, which
//! mirror each other line for line), no comment holding a date or a measured time (the numbers live in
//! `docs/bench/why.md`), every path of the README's layout table exists, and the README, `src/lib.rs` and
//! `layers.rs` state the same layers.

use std::path::{Path, PathBuf};

const LONGEST_FUNCTION: usize = 100;

/// The CPU and WGSL occupancy walks: one loop each, kept whole so the two read side by side.
const LONG_ON_PURPOSE: [&str; 2] = ["trace_occupancy", "trace_occupancy_counted"];

fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

fn source_files(dir: &Path, out: &mut Vec<PathBuf>) {
    for entry in std::fs::read_dir(dir).unwrap() {
        let path = entry.unwrap().path();
        if path.is_dir() {
            source_files(&path, out);
        } else if path.extension().is_some_and(|e| e == "rs" || e == "wgsl") {
            out.push(path);
        }
    }
}

fn all_sources() -> Vec<(String, String)> {
    let mut files = Vec::new();
    source_files(&root().join("src"), &mut files);
    source_files(&root().join("shaders"), &mut files);
    files.sort();
    files
        .into_iter()
        .map(|f| (f.strip_prefix(root()).unwrap().display().to_string(), std::fs::read_to_string(&f).unwrap()))
        .collect()
}

/// A line's code without its comment and with string and character literals emptied, for counting braces.
fn code_of(line: &str) -> String {
    let mut out = String::new();
    let mut chars = line.chars().peekable();
    while let Some(c) = chars.next() {
        match c {
            '/' if chars.peek() == Some(&'/') => break,
            '"' => {
                while let Some(d) = chars.next() {
                    match d {
                        '\\' => {
                            chars.next();
                        }
                        '"' => break,
                        _ => {}
                    }
                }
            }
            '\'' if line.contains("'{'") || line.contains("'}'") => {
                // A character literal of a brace: skip it whole.
                let rest: String = chars.clone().take(2).collect();
                if rest == "{'" || rest == "}'" {
                    chars.next();
                    chars.next();
                }
            }
            _ => out.push(c),
        }
    }
    out
}

/// The name a line declares a function by (Rust or WGSL), if it does.
fn declared_function(line: &str) -> Option<&str> {
    let trimmed = line.trim_start();
    let words: Vec<&str> = trimmed.split_whitespace().collect();
    let at = words.iter().position(|w| *w == "fn")?;
    if !words[..at].iter().all(|w| ["pub", "pub(crate)", "const", "async", "unsafe", "pub(super)"].contains(w)) {
        return None;
    }
    let name = words.get(at + 1)?;
    Some(&name[..name.find(['(', '<']).unwrap_or(name.len())])
}

/// Every function with its length in lines (from its `fn` line to its closing brace).
fn function_lengths(source: &str) -> Vec<(String, usize)> {
    let lines: Vec<&str> = source.lines().collect();
    let mut out = Vec::new();
    for (start, line) in lines.iter().enumerate() {
        let Some(name) = declared_function(line) else { continue };
        let mut depth = 0i32;
        let mut opened = false;
        for (end, body) in lines.iter().enumerate().skip(start) {
            let code = code_of(body);
            if !opened && code.contains(';') && !code.contains('{') {
                break;
            }
            depth += code.matches('{').count() as i32 - code.matches('}').count() as i32;
            opened |= code.contains('{');
            if opened && depth <= 0 {
                out.push((name.to_string(), end - start + 1));
                break;
            }
        }
    }
    out
}

#[test]
fn no_function_is_over_100_lines_but_the_traversal_twins() {
    let mut long = Vec::new();
    let mut seen = 0;
    for (path, source) in all_sources() {
        for (name, lines) in function_lengths(&source) {
            seen += 1;
            if lines > LONGEST_FUNCTION && !LONG_ON_PURPOSE.contains(&name.as_str()) {
                long.push(format!("{path}: {name} is {lines} lines"));
            }
        }
    }
    assert!(seen > 1000, "found only {seen} functions");
    assert!(long.is_empty(), "split these into their phases:\n{}", long.join("\n"));
}

#[test]
fn the_length_check_counts_a_function_to_its_closing_brace() {
    let source = "/// Doc.\npub fn a(x: u32) -> u32 {\n    let s = \"}\";\n    if x > 0 {\n        1\n    } else { 2 }\n}\nfn b();\n";
    assert_eq!(function_lengths(source), [("a".to_string(), 6)]);
    assert_eq!(declared_function("@compute @workgroup_size(8, 8, 1)"), None);
    assert_eq!(declared_function("fn trace_occupancy(origin: vec3<f32>) -> Hit {"), Some("trace_occupancy"));
}

/// A comment's dates (`2026-11-28`) and measured times (`26 ms`, `3.0 s` after a digit), or H200 results: the
/// numbers belong in `docs/bench/`.
fn dated_or_timed(comment: &str) -> Option<String> {
    let chars: Vec<char> = comment.chars().collect();
    let digits_at = |i: usize, n: usize| i + n <= chars.len() && chars[i..i + n].iter().all(|c| c.is_ascii_digit());
    for i in 0..chars.len() {
        if digits_at(i, 4) && chars.get(i + 4) == Some(&'-') && digits_at(i + 5, 2) && chars.get(i + 7) == Some(&'-') {
            return Some("a date".into());
        }
        if chars[i].is_ascii_digit() {
            let rest: String = chars[i + 1..].iter().collect();
            let unit = rest.trim_start_matches(' ');
            let word_end = |u: &str, n: usize| !u[n..].starts_with(|c: char| c.is_alphanumeric());
            if (unit.starts_with("ms") && word_end(unit, 2)) || (unit.starts_with("µs") && word_end(unit, "µs".len()))
            {
                return Some("a time in milliseconds".into());
            }
        }
    }
    comment.contains("H200").then(|| "an H200 result".into())
}

#[test]
fn no_comment_holds_a_date_or_a_measured_time() {
    let mut found = Vec::new();
    for (path, source) in all_sources() {
        for (n, line) in source.lines().enumerate() {
            if let Some(at) = line.find("//")
                && let Some(what) = dated_or_timed(&line[at..])
            {
                found.push(format!("{path}:{}: {what}: {}", n + 1, line.trim()));
            }
        }
    }
    assert!(found.is_empty(), "move these to docs/bench/why.md:\n{}", found.join("\n"));
}

#[test]
fn the_comment_check_sees_dates_and_times() {
    assert!(dated_or_timed("// fixed 2026-11-28").is_some());
    assert!(dated_or_timed("// the refresh pass 26-35 ms").is_some());
    assert!(dated_or_timed("// 4ms a frame").is_some());
    assert!(dated_or_timed("// on the H200 it ran").is_some());
    assert_eq!(dated_or_timed("// depth within 10%, 8x8 workgroups, msaa off"), None);
}

/// The README's section `## Layout`.
fn readme_layout() -> String {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let start = readme.find("## Layout").expect("the README has a Layout section");
    let end = readme[start + 3..].find("\n## ").map_or(readme.len(), |e| start + 3 + e);
    readme[start..end].to_string()
}

/// The paths in a layout row's first cell: a name without a folder is beside the cell's first path.
fn row_paths(cell: &str) -> Vec<String> {
    let names: Vec<&str> = cell.split('`').skip(1).step_by(2).collect();
    let folder = names.first().map_or("", |first| {
        let first = first.trim_end_matches('/');
        first.rfind('/').map_or("", |i| &first[..i + 1])
    });
    names
        .iter()
        .map(
            |n| if n.contains('/') && n.find('/') < Some(n.len() - 1) { n.to_string() } else { format!("{folder}{n}") },
        )
        .collect()
}

#[test]
fn every_path_in_the_readmes_layout_table_exists() {
    let mut missing = Vec::new();
    let mut checked = 0;
    for row in readme_layout().lines().filter(|l| l.starts_with("| `")) {
        let cell = row.split('|').nth(1).unwrap();
        for path in row_paths(cell) {
            checked += 1;
            if !root().join(&path).exists() {
                missing.push(path);
            }
        }
    }
    assert!(checked > 30, "checked only {checked} paths");
    assert!(missing.is_empty(), "the README's layout names paths that do not exist: {missing:?}");
    assert_eq!(
        row_paths("`src/render/primary.rs`, `restir.rs`, `gi/`"),
        ["src/render/primary.rs", "src/render/restir.rs", "src/render/gi/"]
    );
}

/// The layers a statement names, bottom up: the groups between `->`, each the names in backticks.
fn stated_layers(text: &str) -> Vec<Vec<String>> {
    let start = text.find("`colour`").expect("the statement starts at `colour`");
    let end = start + text[start..].find("`cli`").expect("and ends at `cli`") + "`cli`".len();
    let mut layers: Vec<Vec<String>> = text[start..end]
        .split("->")
        .map(|group| {
            let mut names: Vec<String> = group.split('`').skip(1).step_by(2).map(String::from).collect();
            names.sort();
            names
        })
        .collect();
    layers.iter_mut().for_each(|l| l.dedup());
    layers
}

#[test]
fn the_readme_lib_rs_and_the_layer_table_state_the_same_layers() {
    let table = crate::layers::layers_bottom_up();
    let lib = std::fs::read_to_string(root().join("src/lib.rs")).unwrap();
    assert_eq!(stated_layers(&readme_layout()), table, "the README's Layout line");
    assert_eq!(stated_layers(&lib), table, "src/lib.rs's doc comment");
}
