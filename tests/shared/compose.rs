//! Composing the WGSL outside Bevy, as Bevy does (naga_oil, the shared constants as shader defs): for the CPU
//! test that validates every shader and for the GPU tests that run a library function on their own inputs.

use bevy::shader::ShaderDefVal;
use glowbrick::render::gpu_types::shader_defs;
use glowbrick::render::pass_key::PassKey;
use glowbrick::render::shaders::{SOURCES, read_sources};
use glowbrick::settings::Traversal;
use naga::valid::Capabilities;
use naga_oil::compose::{
    ComposableModuleDescriptor, Composer, NagaModuleDescriptor, ShaderDefValue, ShaderLanguage, ShaderType,
};
use std::collections::HashMap;

/// Bevy's `View` as far as our shaders read it (the real one lives in bevy_render's view.wgsl).
const VIEW: &str = "#define_import_path bevy_render::view
struct View {
    clip_from_world: mat4x4<f32>,
    world_from_clip: mat4x4<f32>,
    clip_from_view: mat4x4<f32>,
    world_position: vec3<f32>,
    viewport: vec4<f32>,
}
";

/// The shared constants and a generic pass key, with `extra` (a pipeline's key) on top.
fn defs_with(extra: &[ShaderDefVal]) -> HashMap<String, ShaderDefValue> {
    shader_defs()
        .into_iter()
        .chain(PassKey::generic(Traversal::Dda).shader_defs())
        .chain(extra.iter().cloned())
        .map(|d| match d {
            ShaderDefVal::Bool(k, v) => (k, ShaderDefValue::Bool(v)),
            ShaderDefVal::Int(k, v) => (k, ShaderDefValue::Int(v)),
            ShaderDefVal::UInt(k, v) => (k, ShaderDefValue::UInt(v)),
        })
        .collect()
}

fn defs() -> HashMap<String, ShaderDefValue> {
    defs_with(&[])
}

fn library(composer: &mut Composer, path: &str, source: &str, defs: &HashMap<String, ShaderDefValue>) {
    let added = composer
        .add_composable_module(ComposableModuleDescriptor {
            source,
            file_path: path,
            language: ShaderLanguage::Wgsl,
            as_name: None,
            additional_imports: &[],
            shader_defs: defs.clone(),
        })
        .map(|_| ());
    if let Err(e) = added {
        panic!("{path}: {}", e.emit_to_string(composer));
    }
}

/// A composer holding every library shader (the files with a `#define_import_path`).
pub fn composer() -> Composer {
    composer_with(&[])
}

/// `composer` with `extra` defs (a pipeline's `PassKey`) on top.
pub fn composer_with(extra: &[ShaderDefVal]) -> Composer {
    let defs = defs_with(extra);
    let mut composer = Composer::default().with_capabilities(Capabilities::all());
    library(&mut composer, "bevy_render/view.wgsl", VIEW, &defs);
    for (path, source) in sources().iter().filter(|(_, s)| s.contains("#define_import_path")) {
        library(&mut composer, path, source, &defs);
    }
    composer
}

/// The shaders built in, or those of the folder `GLOWBRICK_SHADERS` names (as the game reads them): a shader
/// experiment runs in a bench without rebuilding it.
fn sources() -> Vec<(&'static str, String)> {
    match std::env::var_os("GLOWBRICK_SHADERS") {
        Some(dir) => read_sources(std::path::Path::new(&dir)).unwrap_or_else(|e| panic!("GLOWBRICK_SHADERS: {e}")),
        None => SOURCES.iter().map(|&(path, source)| (path, source.to_string())).collect(),
    }
}

/// A pass composed as a pipeline of `key` compiles it (`composer` from `composer_with` the same defs).
#[allow(dead_code)]
pub fn compose_keyed(composer: &mut Composer, path: &str, source: &str, key: &[ShaderDefVal]) -> naga::Module {
    composer
        .make_naga_module(NagaModuleDescriptor {
            source,
            file_path: path,
            shader_type: ShaderType::Wgsl,
            shader_defs: defs_with(key),
            additional_imports: &[],
        })
        .unwrap_or_else(|e| panic!("{path}: {}", e.emit_to_string(composer)))
}

/// `source` (a pass, or a test's own shader importing the libraries) composed into one naga module.
#[allow(dead_code)]
pub fn compose(composer: &mut Composer, path: &str, source: &str) -> naga::Module {
    compose_with(composer, path, source, &[])
}

/// `compose` with boolean shader defs on top of the shared constants (a pipeline variant, e.g.
/// `TRAVERSAL_OCCUPANCY`).
#[allow(dead_code)]
pub fn compose_with(composer: &mut Composer, path: &str, source: &str, flags: &[&str]) -> naga::Module {
    let mut shader_defs = defs();
    shader_defs.extend(flags.iter().map(|f| (f.to_string(), ShaderDefValue::Bool(true))));
    composer
        .make_naga_module(NagaModuleDescriptor {
            source,
            file_path: path,
            shader_type: ShaderType::Wgsl,
            shader_defs,
            additional_imports: &[],
        })
        .unwrap_or_else(|e| panic!("{path}: {}", e.emit_to_string(composer)))
}
