//! Every WGSL file composes (its imports resolved, the shared constants defined) and validates with naga, the
//! composer and validator Bevy uses: a shader error fails `cargo test` on a machine without a GPU too, and names
//! the two globals when bindings collide.

use bevy::shader::ShaderDefVal;
use glowbrick::render::gpu_types::shader_defs;
use glowbrick::render::shaders::SOURCES;
use naga::valid::{Capabilities, ValidationFlags, Validator};
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

fn defs() -> HashMap<String, ShaderDefValue> {
    shader_defs()
        .into_iter()
        .map(|d| match d {
            ShaderDefVal::Bool(k, v) => (k, ShaderDefValue::Bool(v)),
            ShaderDefVal::Int(k, v) => (k, ShaderDefValue::Int(v)),
            ShaderDefVal::UInt(k, v) => (k, ShaderDefValue::UInt(v)),
        })
        .collect()
}

fn library(composer: &mut Composer, path: &str, source: &str) {
    let added = composer
        .add_composable_module(ComposableModuleDescriptor {
            source,
            file_path: path,
            language: ShaderLanguage::Wgsl,
            as_name: None,
            additional_imports: &[],
            shader_defs: defs(),
        })
        .map(|_| ());
    if let Err(e) = added {
        panic!("{path}: {}", e.emit_to_string(composer));
    }
}

#[test]
fn every_shader_composes_and_validates() {
    let mut composer = Composer::default().with_capabilities(Capabilities::all());
    library(&mut composer, "bevy_render/view.wgsl", VIEW);
    let (libraries, passes): (Vec<_>, Vec<_>) = SOURCES.iter().partition(|(_, s)| s.contains("#define_import_path"));
    for (path, source) in libraries {
        library(&mut composer, path, source);
    }
    assert!(passes.len() >= 8, "every pass shader is checked");
    for (path, source) in passes {
        let module = composer
            .make_naga_module(NagaModuleDescriptor {
                source,
                file_path: path,
                shader_type: ShaderType::Wgsl,
                shader_defs: defs(),
                additional_imports: &[],
            })
            .unwrap_or_else(|e| panic!("{path}: {}", e.emit_to_string(&composer)));
        if let Err(e) = Validator::new(ValidationFlags::all(), Capabilities::all()).validate(&module) {
            let globals: Vec<String> = module
                .global_variables
                .iter()
                .map(|(h, g)| format!("{h:?} {:?} {:?}", g.name, g.binding.as_ref().map(|b| (b.group, b.binding))))
                .collect();
            panic!("{path}: {e:?}\nglobals:\n{}", globals.join("\n"));
        }
    }
}
