//! Every WGSL file composes (its imports resolved, the shared constants defined) and validates with naga, the
//! composer and validator Bevy uses: a shader error fails `cargo test` on a machine without a GPU too, and names
//! the two globals when bindings collide. And every buffer the shaders bind has the layout of the Rust type
//! that fills it, as naga lays the WGSL out.

use crate::compose;
use glowbrick::lights::AliasEntry;
use glowbrick::render::frame::{all_passes, bind_groups};
use glowbrick::render::gpu_types::*;
use glowbrick::render::interface::{Access, GroupInterface};
use glowbrick::render::pass::{Dispatch, LINEAR_WORKGROUP, PIXEL_WORKGROUP_EDGE};
use glowbrick::render::shaders::SOURCES;
use naga::valid::{Capabilities, ValidationFlags, Validator};
use std::mem::offset_of;

/// Every pass shader composed with its imports, by path (with `flags` as boolean shader defs).
fn composed_passes_with(flags: &[&str]) -> Vec<(&'static str, naga::Module)> {
    let mut composer = compose::composer();
    let passes: Vec<_> = SOURCES.iter().filter(|(_, s)| !s.contains("#define_import_path")).collect();
    assert!(passes.len() >= 8, "every pass shader is checked");
    passes
        .into_iter()
        .map(|&(path, source)| (path, compose::compose_with(&mut composer, path, source, flags)))
        .collect()
}

fn composed_passes() -> Vec<(&'static str, naga::Module)> {
    composed_passes_with(&[])
}

#[test]
fn every_shader_composes_and_validates() {
    for (path, module) in composed_passes() {
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

/// The pipelines of `traversal=occupancy` (every pass with the `TRAVERSAL_OCCUPANCY` def) validate too.
#[test]
fn every_shader_validates_with_the_occupancy_traversal() {
    for (path, module) in composed_passes_with(&["TRAVERSAL_OCCUPANCY"]) {
        let source = SOURCES.iter().find(|(p, _)| *p == path).map_or("", |(_, s)| *s);
        let traced =
            module.functions.iter().any(|(_, f)| f.name.as_deref().is_some_and(|n| n.contains("trace_occupancy")));
        let plain = module.functions.iter().any(|(_, f)| f.name.as_deref().is_some_and(|n| n.contains("trace_dda")));
        assert!(!plain, "{path}: the plain DDA is compiled into the occupancy variant");
        if let Err(e) = Validator::new(ValidationFlags::all(), Capabilities::all()).validate(&module) {
            panic!("{path} with TRAVERSAL_OCCUPANCY: {e:?}");
        }
        if source.contains("trace") && path.contains("primary") {
            assert!(traced, "{path}: the occupancy variant traces through trace_occupancy");
        }
    }
}

/// Every pass validates as the pipelines compile it: specialised for a frame's settings (`PassKey`), each
/// accessor folded to a constant, for the default frame and for settings that take the other side of each branch.
#[test]
fn every_shader_validates_specialised_for_the_settings() {
    use glowbrick::render::pass_key::PassKey;
    use glowbrick::settings::{DebugView, Lighting, RenderSettings, Traversal};
    let default = RenderSettings::default();
    let mut others = vec![];
    for change in [
        (|s: &mut RenderSettings| s.lighting = Lighting::Nee) as fn(&mut RenderSettings),
        |s| s.lighting = Lighting::Sun,
        |s| s.debug = DebugView::Reservoir,
        |s| s.debug = DebugView::Albedo,
        |s| {
            s.gi.enabled = false;
            s.shadows = false;
        },
        |s| {
            s.gi.cache = true;
            s.restir.light_tiles = false;
            s.restir.local_lights = false;
        },
    ] {
        let mut settings = default.clone();
        change(&mut settings);
        others.push(settings);
    }
    for (settings, traversal) in std::iter::once((&default, Traversal::Occupancy))
        .chain(std::iter::once(&default).chain(&others).map(|s| (s, Traversal::Dda)))
    {
        // Objects with the DDA, a pool in parts with the occupancy walk: every variant of the world's code.
        let occupancy = traversal == Traversal::Occupancy;
        let key = PassKey::of(settings, traversal, !occupancy, occupancy).shader_defs();
        let mut composer = compose::composer_with(&key);
        for &(path, source) in SOURCES.iter().filter(|(_, s)| !s.contains("#define_import_path")) {
            let module = compose::compose_keyed(&mut composer, path, source, &key);
            if let Err(e) = Validator::new(ValidationFlags::all(), Capabilities::all()).validate(&module) {
                panic!("{path} for {settings:?}, {traversal:?}: {e:?}");
            }
        }
    }
}

/// A buffer binding and the Rust side that fills it.
struct Twin {
    /// The WGSL global, as declared (before naga_oil decorates it with its module).
    global: &'static str,
    /// The WGSL type of one element (a uniform's whole type), when it is a struct.
    wgsl_struct: Option<&'static str>,
    /// Bytes of one Rust element: the whole buffer for a uniform, one element of a storage array.
    bytes: usize,
    /// WGSL elements per Rust element (an edit-log record is two `vec4<i32>`).
    per: usize,
    /// The Rust struct's fields (padding left out) in the order the WGSL struct declares its members (padding,
    /// named `_pad*`, left out): the WGSL member's name and the Rust field's offset. Empty where the Rust side is
    /// only a size.
    fields: Vec<(&'static str, usize)>,
}

/// A twin whose Rust side is a `repr(C)` struct: its size and the offsets of the listed fields, each named as in
/// the WGSL (`field => "wgsl_name"` where the names differ).
macro_rules! twin {
    ($global:literal, $wgsl:literal, $rust:ty { $($field:ident $(=> $name:literal)?),* $(,)? }) => {
        Twin {
            global: $global,
            wgsl_struct: Some($wgsl),
            bytes: size_of::<$rust>(),
            per: 1,
            fields: vec![$(([$($name,)? stringify!($field)][0], offset_of!($rust, $field))),*],
        }
    };
}

/// A twin whose Rust side is only a size per element (`per` WGSL elements to it).
fn sized(global: &'static str, wgsl_struct: Option<&'static str>, bytes: u64, per: usize) -> Twin {
    Twin { global, wgsl_struct, bytes: bytes as usize, per, fields: Vec::new() }
}

/// Every buffer the shaders bind, with its Rust twin.
fn twins() -> Vec<Twin> {
    let word = size_of::<u32>() as u64;
    vec![
        // Group 0: the world.
        twin!(
            "world_info",
            "WorldInfo",
            WorldInfo {
                size,
                object_count,
                bricks,
                voxel_mask_base,
                sectors,
                sector_base,
                regions,
                region_base,
                occupied_lo,
                pool_part_shift,
                occupied_hi,
                detail_origin,
                window_lo,
                window_hi,
                wrap_base
            }
        ),
        sized("top_cells", None, word, 1),
        sized("brick_pool", None, word, 1),
        sized("brick_pool_1", None, word, 1),
        sized("brick_pool_2", None, word, 1),
        sized("brick_pool_3", None, word, 1),
        twin!("materials", "Material", GpuMaterial { albedo, radiance }),
        twin!("objects", "Object", GpuObject { min, id, size, offset, previous_min }),
        sized("object_voxels", None, word, 1),
        sized("counters", None, word, 1),
        // One occupancy mask (`world::occupancy`): a u64 on the CPU, a vec2<u32> on the GPU.
        sized("occupancy", None, size_of::<u64>() as u64, 1),
        // Group 1: one view.
        twin!(
            "frame",
            "FrameParams",
            FrameParams {
                prev_clip_from_world,
                prev_camera,
                debug_view,
                exposure,
                frame,
                accumulated,
                highlight_target,
                selection_min,
                selection_max,
                candidates,
                taps,
                radius,
                restir_flags,
                denoise,
                upscale,
                render_size,
                jitter,
            }
        ),
        sized("accumulation", None, ACCUMULATION_TEXEL_BYTES, 1),
        sized("gbuffer", None, GBUFFER_TEXEL_BYTES, 1),
        sized("prev_gbuffer", None, GBUFFER_TEXEL_BYTES, 1),
        sized("reservoirs_temporal", Some("Reservoir"), RESERVOIR_BYTES, 1),
        sized("reservoirs_final", Some("Reservoir"), RESERVOIR_BYTES, 1),
        sized("noisy", None, DENOISE_TEXEL_BYTES, 1),
        sized("history", None, DENOISE_TEXEL_BYTES, 1),
        sized("prev_history", None, DENOISE_TEXEL_BYTES, 1),
        sized("wavelet", None, DENOISE_TEXEL_BYTES, 1),
        twin!("light_tiles", "TileLight", GpuTileLight { light, slot, pdf }),
        // Group 2: the lights.
        twin!("lights", "Light", GpuLight { min, size_faces, radiance, generation }),
        twin!("alias_table", "AliasEntry", AliasEntry { threshold, alias => "alias_column", slot, pdf }),
        twin!(
            "scene",
            "SceneLighting",
            SceneLighting { sun, sun_radiance, sky_zenith, sky_horizon, mode, power_pick, light_count, shadows }
        ),
        sized("light_index", None, word, 1),
        // Group 3: the GI cache.
        twin!(
            "gi",
            "GiParams",
            GiParams {
                enabled,
                flags,
                rays,
                update_rays,
                alpha,
                epoch,
                lost_epoch,
                edit_count,
                static_capacity,
                dynamic_capacity,
                frame,
                iteration,
                cell_pixels,
                update_run,
                period,
            }
        ),
        sized("gi_keys", None, GI_KEY_BYTES, 1),
        twin!(
            "gi_entries",
            "GiEntry",
            GiEntry { voxel, face, last_used, traced_epoch, samples, object, lo, last_seen, hi, level }
        ),
        sized("gi_irradiance", None, GI_RADIANCE_BYTES, 1),
        sized("gi_filtered", None, GI_RADIANCE_BYTES, 1),
        sized("gi_rays", None, GI_RAY_BYTES, 1),
        sized("gi_edits", None, size_of::<GiEdit>() as u64, 2),
        twin!("gi_direct", "GiDirect", GiDirect { light, reservoir, guide }),
        sized("gi_work", None, word, 1),
        sized("gi_list", None, word, 1),
    ]
}

/// Bindings whose other side is not ours: Bevy's view uniform.
const NOT_OURS: [&str; 1] = ["view"];

/// A name without naga_oil's module decoration.
fn undecorated(name: &str) -> &str {
    name.split("X_naga_oil_mod_X").next().unwrap_or(name)
}

/// Where a buffer binding's WGSL layout differs from its Rust twin's, in words; `None` when they agree.
fn layout_mismatch(module: &naga::Module, global: &naga::GlobalVariable, twin: &Twin) -> Option<String> {
    use naga::TypeInner;
    let ty = &module.types[global.ty];
    // A storage array: its elements; a uniform: the whole type.
    let (element, bytes) = match ty.inner {
        TypeInner::Array { base, stride, .. } => (base, stride as usize * twin.per),
        TypeInner::Struct { span, .. } => (global.ty, span as usize * twin.per),
        ref other => return Some(format!("an unexpected type {other:?}")),
    };
    if bytes != twin.bytes {
        return Some(format!("{bytes} bytes in WGSL, {} in Rust", twin.bytes));
    }
    let element = &module.types[element];
    let name = element.name.as_deref().map(undecorated);
    if name != twin.wgsl_struct {
        return Some(format!("WGSL type {name:?}, expected {:?}", twin.wgsl_struct));
    }
    if let TypeInner::Struct { members, .. } = &element.inner
        && !twin.fields.is_empty()
    {
        let wgsl: Vec<(&str, usize)> = members
            .iter()
            .map(|m| (m.name.as_deref().unwrap_or("?"), m.offset as usize))
            .filter(|(name, _)| !name.starts_with("_pad"))
            .collect();
        if wgsl != twin.fields {
            return Some(format!("members (name, offset) {wgsl:?} in WGSL, {:?} in Rust", twin.fields));
        }
    }
    None
}

/// Every buffer binding in every pass has the layout of its Rust twin: its size (a uniform's, or a storage
/// array's element stride) and, for a struct, every member's offset. A field added, moved or retyped on one side
/// only fails here, and so does a new binding without a twin. Both traversals' variants (the occupancy masks are
/// bound by the occupancy one only).
#[test]
fn every_buffer_has_the_layout_of_its_rust_twin() {
    let twins = twins();
    let mut seen = vec![false; twins.len()];
    let mut errors = Vec::new();
    let variants = composed_passes().into_iter().chain(composed_passes_with(&["TRAVERSAL_OCCUPANCY"]));
    for (path, module) in variants {
        for (_, global) in module.global_variables.iter() {
            if !matches!(global.space, naga::AddressSpace::Uniform | naga::AddressSpace::Storage { .. }) {
                continue;
            }
            let name = undecorated(global.name.as_deref().unwrap_or(""));
            if NOT_OURS.contains(&name) {
                continue;
            }
            let Some(i) = twins.iter().position(|t| t.global == name) else {
                errors.push(format!("{path}: `{name}` has no Rust twin in this test's table"));
                continue;
            };
            seen[i] = true;
            if let Some(why) = layout_mismatch(&module, global, &twins[i]) {
                errors.push(format!("{path}: `{name}`: {why}"));
            }
        }
    }
    for (twin, seen) in twins.iter().zip(seen) {
        if !seen {
            errors.push(format!("`{}` is in the table but no shader binds it", twin.global));
        }
    }
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// How a naga global is accessed, in the terms of the Rust declarations (`interface::Access`); `None` for a
/// global the check does not cover (a sampler, a workgroup variable).
fn wgsl_access(module: &naga::Module, global: &naga::GlobalVariable) -> Option<Access> {
    use naga::{AddressSpace, ImageClass, StorageAccess, TypeInner};
    Some(match global.space {
        AddressSpace::Uniform if undecorated(global.name.as_deref().unwrap_or("")) == "view" => Access::ViewUniform,
        AddressSpace::Uniform => match module.types[global.ty].inner {
            TypeInner::Struct { span, .. } => Access::Uniform(span as u64),
            _ => return None,
        },
        AddressSpace::Storage { access } if access.contains(StorageAccess::STORE) => Access::ReadWrite,
        AddressSpace::Storage { .. } => Access::Read,
        AddressSpace::Handle => match module.types[global.ty].inner {
            TypeInner::Image { class: ImageClass::Storage { access, .. }, .. } if access == StorageAccess::STORE => {
                Access::OutputTexture
            }
            _ => return None,
        },
        _ => return None,
    })
}

/// Every way the shaders' globals disagree with the Rust declarations: a global at a binding declared with
/// another name or access, at a binding nobody declared, or a declared binding no shader uses. Bevy's view
/// uniform is compared by access only (its size is Bevy's).
fn interface_mismatches(modules: &[(&str, naga::Module)], groups: &[GroupInterface]) -> Vec<String> {
    let mut errors = Vec::new();
    let mut used = std::collections::HashSet::new();
    for (path, module) in modules {
        for (_, global) in module.global_variables.iter() {
            let (Some(binding), Some(access)) = (&global.binding, wgsl_access(module, global)) else { continue };
            let name = undecorated(global.name.as_deref().unwrap_or(""));
            let declared =
                groups.iter().find(|g| g.group == binding.group).and_then(|g| g.bindings.get(binding.binding as usize));
            let at = format!("{path}: @group({}) @binding({}) `{name}`", binding.group, binding.binding);
            match declared {
                None => errors.push(format!("{at}: no Rust declaration at this binding")),
                Some(d) if d.name != name => errors.push(format!("{at}: declared as `{}`", d.name)),
                Some(d) if d.access != access => {
                    errors.push(format!("{at}: {access:?} in WGSL, {:?} in its Rust declaration", d.access))
                }
                Some(_) => {
                    used.insert((binding.group, binding.binding));
                }
            }
        }
    }
    for group in groups {
        for (i, declared) in group.bindings.iter().enumerate() {
            if !used.contains(&(group.group, i as u32)) {
                errors.push(format!(
                    "{} binding {i} `{}` is declared but no shader binds it",
                    group.label, declared.name
                ));
            }
        }
    }
    errors.sort();
    errors.dedup();
    errors
}

/// Every pass, in both traversals' variants (the occupancy masks are bound by the occupancy one only), but the
/// one-off test shaders' bindings past 100.
fn pass_modules() -> Vec<(&'static str, naga::Module)> {
    composed_passes().into_iter().chain(composed_passes_with(&["TRAVERSAL_OCCUPANCY"])).collect()
}

/// Every `@group/@binding var<..>` in `shaders/` has the name and access its group's Rust declaration gives it,
/// and every declaration is bound by some shader: the layouts and bind groups are built from those declarations.
#[test]
fn every_shader_binding_matches_its_rust_declaration() {
    let errors = interface_mismatches(&pass_modules(), &bind_groups());
    assert!(errors.is_empty(), "{}", errors.join("\n"));
}

/// The check fails on a declaration that disagrees with the WGSL: an access mode changed, two bindings swapped,
/// one left out.
#[test]
fn the_binding_check_sees_a_wrong_access_a_wrong_number_and_a_missing_declaration() {
    let modules = pass_modules();
    let mut groups = bind_groups();
    let world = groups.iter_mut().find(|g| g.group == 0).unwrap();
    let occupancy = world.bindings.iter().position(|b| b.name == "occupancy").unwrap();
    world.bindings[occupancy].access = Access::ReadWrite;
    let errors = interface_mismatches(&modules, &groups);
    assert!(errors.iter().any(|e| e.contains("`occupancy`") && e.contains("Read in WGSL")), "{errors:?}");

    let mut groups = bind_groups();
    let gi = groups.iter_mut().find(|g| g.group == 3).unwrap();
    gi.bindings.swap(1, 2);
    let errors = interface_mismatches(&modules, &groups);
    assert!(errors.iter().any(|e| e.contains("`gi_keys`: declared as `gi_entries`")), "{errors:?}");

    let mut groups = bind_groups();
    groups.iter_mut().find(|g| g.group == 1).unwrap().bindings.pop();
    let errors = interface_mismatches(&modules, &groups);
    assert!(errors.iter().any(|e| e.contains("`wavelet`: no Rust declaration")), "{errors:?}");
}

/// Every `@workgroup_size` is the one `frame` dispatches with: a square of `PIXEL_WORKGROUP_EDGE` for the
/// per-pixel passes, `LINEAR_WORKGROUP` for the others.
#[test]
fn every_workgroup_size_is_the_one_the_frame_dispatches() {
    let pixels = format!("@workgroup_size({PIXEL_WORKGROUP_EDGE}, {PIXEL_WORKGROUP_EDGE}, 1)");
    let linear = format!("@workgroup_size({LINEAR_WORKGROUP}, 1, 1)");
    let mut seen = 0;
    for (path, source) in SOURCES {
        for (i, _) in source.match_indices("@workgroup_size") {
            let size = &source[i..i + source[i..].find(')').unwrap() + 1];
            assert!(size == pixels || size == linear, "{path}: {size} is neither {pixels} nor {linear}");
            seen += 1;
        }
    }
    assert!(seen >= 10, "only {seen} entry points found");
    for pass in all_passes() {
        let source = SOURCES.iter().find(|(p, _)| *p == pass.shader).map(|(_, s)| *s).unwrap();
        let entry = source.find(&format!("fn {}(", pass.entry_point)).expect(pass.entry_point);
        let size_at = source[..entry].rfind("@workgroup_size").unwrap();
        let expected =
            if matches!(pass.dispatch, Dispatch::Pixels | Dispatch::OutputPixels) { &pixels } else { &linear };
        assert!(source[size_at..].starts_with(expected.as_str()), "{}: {} is not {expected}", pass.shader, pass.name);
    }
}

/// The shaders' luminance weights are Rust's (`colour::LUMINANCE_WEIGHTS`), wherever they are written.
#[test]
fn every_luminance_in_wgsl_weighs_as_the_cpu_does() {
    let [r, g, b] = glowbrick::colour::LUMINANCE_WEIGHTS;
    let weights = format!("vec3({r}, {g}, {b})");
    let mut found = 0;
    for (path, source) in SOURCES {
        let written = source.matches(&format!("{g}")).count();
        let as_rust = source.matches(&weights).count();
        assert_eq!(written, as_rust, "{path}: a green weight of {g} outside `{weights}`");
        found += as_rust;
    }
    assert!(found >= 2, "the luminance weights are written {found} times in WGSL");
}

/// Lavapipe (`maxPerStageDescriptorStorageBuffers`) lets one compute stage bind 32 storage buffers, and every pass
/// binds all four groups: one more, and creating the pipeline layout fails on that adapter, whose frames then never
/// come (a render waits out its timeout).
const STORAGE_BUFFERS_PER_STAGE: usize = 32;

#[test]
fn the_bind_groups_stay_within_lavapipes_storage_buffers_per_stage() {
    let storage = bind_groups()
        .iter()
        .flat_map(|group| group.bindings.iter())
        .filter(|b| matches!(b.access, Access::Read | Access::ReadWrite))
        .count();
    assert!(storage <= STORAGE_BUFFERS_PER_STAGE, "{storage} storage buffers in groups 0-3");
}
