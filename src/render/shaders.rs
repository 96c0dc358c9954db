//! The WGSL, embedded at compile time so the binary runs from any directory. `shaders/lib/` holds the libraries
//! every pass imports (`glowbrick::world`, `::traversal`, `::random`, `::guards`, `::lights`, `::frame`,
//! `::constants`, `::counters`); `shaders/restir/`, `shaders/gi/` and `shaders/denoise/` one technique each.
//!
//! `GLOWBRICK_SHADERS=DIR` reads every file from `DIR` (laid out as `shaders/`) instead, when the process starts:
//! a shader change is tried, or two variants timed against each other, with one binary and no rebuild.

use bevy::prelude::*;
use bevy::shader::Shader;

/// Every shader file: its path under `shaders/` and its source. Libraries first (they only define imports).
pub const SOURCES: [(&str, &str); 27] = [
    ("lib/constants.wgsl", include_str!("../../shaders/lib/constants.wgsl")),
    ("lib/random.wgsl", include_str!("../../shaders/lib/random.wgsl")),
    ("lib/guards.wgsl", include_str!("../../shaders/lib/guards.wgsl")),
    ("lib/counters.wgsl", include_str!("../../shaders/lib/counters.wgsl")),
    ("lib/world.wgsl", include_str!("../../shaders/lib/world.wgsl")),
    ("lib/traversal.wgsl", include_str!("../../shaders/lib/traversal.wgsl")),
    ("lib/lights.wgsl", include_str!("../../shaders/lib/lights.wgsl")),
    ("lib/frame.wgsl", include_str!("../../shaders/lib/frame.wgsl")),
    ("gi/cache.wgsl", include_str!("../../shaders/gi/cache.wgsl")),
    ("gi/reservoir.wgsl", include_str!("../../shaders/gi/reservoir.wgsl")),
    ("gi/guide.wgsl", include_str!("../../shaders/gi/guide.wgsl")),
    ("gi/direct.wgsl", include_str!("../../shaders/gi/direct.wgsl")),
    ("restir/common.wgsl", include_str!("../../shaders/restir/common.wgsl")),
    ("denoise/common.wgsl", include_str!("../../shaders/denoise/common.wgsl")),
    ("primary.wgsl", include_str!("../../shaders/primary.wgsl")),
    ("restir/tiles.wgsl", include_str!("../../shaders/restir/tiles.wgsl")),
    ("restir/initial.wgsl", include_str!("../../shaders/restir/initial.wgsl")),
    ("restir/temporal.wgsl", include_str!("../../shaders/restir/temporal.wgsl")),
    ("restir/spatial.wgsl", include_str!("../../shaders/restir/spatial.wgsl")),
    ("restir/shade.wgsl", include_str!("../../shaders/restir/shade.wgsl")),
    ("gi/compact.wgsl", include_str!("../../shaders/gi/compact.wgsl")),
    ("gi/refresh.wgsl", include_str!("../../shaders/gi/refresh.wgsl")),
    ("gi/update.wgsl", include_str!("../../shaders/gi/update.wgsl")),
    ("gi/filter.wgsl", include_str!("../../shaders/gi/filter.wgsl")),
    ("denoise/temporal.wgsl", include_str!("../../shaders/denoise/temporal.wgsl")),
    ("denoise/wavelet.wgsl", include_str!("../../shaders/denoise/wavelet.wgsl")),
    ("upscale/upscale.wgsl", include_str!("../../shaders/upscale/upscale.wgsl")),
];

/// Handles of every embedded shader, by its path under `shaders/`. Holding them keeps the libraries loaded.
#[derive(Resource, Clone)]
pub struct GlowbrickShaders(pub Vec<(&'static str, Handle<Shader>)>);

impl GlowbrickShaders {
    /// Adds every shader to the asset store: the embedded sources, or those of `$GLOWBRICK_SHADERS`.
    pub fn load(shaders: &mut Assets<Shader>) -> Self {
        let sources = match std::env::var_os("GLOWBRICK_SHADERS") {
            Some(dir) => read_sources(std::path::Path::new(&dir)).unwrap_or_else(|error| {
                // Read before any window or device exists: one line and out, like any other bad input.
                eprintln!("error: GLOWBRICK_SHADERS: {error}");
                std::process::exit(2);
            }),
            None => SOURCES.iter().map(|&(path, source)| (path, source.to_string())).collect(),
        };
        GlowbrickShaders(
            sources
                .into_iter()
                .map(|(path, source)| (path, shaders.add(Shader::from_wgsl(source, format!("glowbrick/{path}")))))
                .collect(),
        )
    }

    /// The handle of the shader at `path` (one of `SOURCES`; a typo is a programming error caught by every test).
    pub fn get(&self, path: &str) -> Handle<Shader> {
        self.0.iter().find(|(p, _)| *p == path).map(|(_, h)| h.clone()).unwrap_or_else(|| panic!("no shader {path}"))
    }
}

/// Every file of `SOURCES` read from `dir`; the first missing or unreadable one is the error.
pub fn read_sources(dir: &std::path::Path) -> Result<Vec<(&'static str, String)>, String> {
    SOURCES
        .iter()
        .map(|&(path, _)| {
            let file = dir.join(path);
            std::fs::read_to_string(&file).map(|source| (path, source)).map_err(|e| format!("{}: {e}", file.display()))
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_override_folder_reads_every_shader_and_names_a_missing_one() {
        let shipped = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("shaders");
        let read = read_sources(&shipped).unwrap();
        assert_eq!(read.len(), SOURCES.len());
        for ((path, source), (embedded_path, embedded)) in read.iter().zip(SOURCES) {
            assert_eq!((*path, source.as_str()), (embedded_path, embedded));
        }
        let error = read_sources(&shipped.join("restir")).unwrap_err();
        assert!(error.contains("lib/constants.wgsl"), "{error}");
    }
}
