//! The settings every voxel pipeline is compiled for. A frame's passes branch on a handful of settings that stay
//! the same for many frames (the lighting mode, the debug view, ReSTIR's and the GI cache's switches, the walk,
//! whether the world holds moving objects);
//! compiling each pipeline for the frame's values leaves the other values' code out of it. On a GPU that saves
//! registers; on this project's software Vulkan (Mesa 22.3's lavapipe, which runs both sides of every branch under
//! a mask) it saves the time of every pass that holds code the frame does not run (`docs/bench/frame.md`).
//!
//! The shaders read these values through accessors (`lighting_mode()`, `debug_view()`, `restir_flag()`,
//! `gi_on()`, `gi_setting()`, ...), which read the uniform instead when a value is `KEY_GENERIC`: the tests that
//! compose one library function alone compile it that way. The uniforms keep carrying the same values.

use super::gi;
use super::restir::RestirParams;
use super::scene::lights::scene_lighting;
use crate::settings::{RenderSettings, Traversal};
use bevy::shader::ShaderDefVal;

/// What a setting compiles to when a pipeline is not specialised: the accessor reads the uniform.
pub const KEY_GENERIC: u32 = u32::MAX;

/// The values a set of voxel pipelines is compiled for; one set per key met so far.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct PassKey {
    /// The walk (never `Auto`: resolved for the adapter).
    pub traversal: Traversal,
    /// `SceneLighting`'s `mode`, `shadows` and `power_pick`.
    lighting: u32,
    shadows: u32,
    power_pick: u32,
    /// `FrameParams`' `debug_view` and `restir_flags`.
    debug_view: u32,
    restir_flags: u32,
    /// `GiParams`' `enabled` and the setting bits of its `flags`.
    gi: u32,
    gi_flags: u32,
    /// 1 when the world holds moving objects this frame (`WorldInfo.object_count` above 0): without them every
    /// shadow and GI ray is the static walk alone.
    objects: u32,
    /// 1 when the world's brick pool is split into parts (`render::scene::world::POOL_PARTS`): without parts a
    /// voxel read is one load, without the part's choice (which costs software Vulkan a sixth of a frame).
    pool_parts: u32,
}

impl PassKey {
    /// The key of a frame under `settings`, with `auto` already resolved to `traversal`, in a world with or
    /// without moving objects, whose pool is or is not in parts. Each value is computed by the function that fills
    /// its uniform, so the two cannot disagree.
    pub fn of(settings: &RenderSettings, traversal: Traversal, objects: bool, pool_parts: bool) -> Self {
        let scene = scene_lighting(settings, 0);
        PassKey {
            traversal,
            lighting: scene.mode,
            shadows: scene.shadows,
            power_pick: scene.power_pick,
            debug_view: settings.debug.shader_index(),
            restir_flags: RestirParams::of(settings).flags,
            gi: settings.gi.enabled as u32,
            gi_flags: gi::setting_flags(&settings.gi),
            objects: objects as u32,
            pool_parts: pool_parts as u32,
        }
    }

    /// A key that specialises nothing but the walk: every accessor reads its uniform, so its pipelines are right
    /// for any settings (the game's fallback while a new key's set compiles).
    pub fn generic(traversal: Traversal) -> Self {
        let g = KEY_GENERIC;
        PassKey {
            traversal,
            lighting: g,
            shadows: g,
            power_pick: g,
            debug_view: g,
            restir_flags: g,
            gi: g,
            gi_flags: g,
            objects: g,
            pool_parts: g,
        }
    }

    /// The key's shader defs (added to the shared constants').
    pub fn shader_defs(&self) -> Vec<ShaderDefVal> {
        let mut defs = key_defs([
            self.lighting,
            self.shadows,
            self.power_pick,
            self.debug_view,
            self.restir_flags,
            self.gi,
            self.gi_flags,
            self.objects,
            self.pool_parts,
        ]);
        if self.traversal == Traversal::Occupancy {
            defs.push(ShaderDefVal::Bool("TRAVERSAL_OCCUPANCY".into(), true));
        }
        defs
    }
}

/// The defs' names, in `key_defs`' order (constants.wgsl declares each once).
pub const KEY_NAMES: [&str; 9] = [
    "KEY_LIGHTING",
    "KEY_SHADOWS",
    "KEY_POWER_PICK",
    "KEY_DEBUG_VIEW",
    "KEY_RESTIR_FLAGS",
    "KEY_GI",
    "KEY_GI_FLAGS",
    "KEY_OBJECTS",
    "KEY_POOL_PARTS",
];

fn key_defs(values: [u32; 9]) -> Vec<ShaderDefVal> {
    let mut defs = vec![ShaderDefVal::UInt("KEY_GENERIC".into(), KEY_GENERIC)];
    defs.extend(KEY_NAMES.iter().zip(values).map(|(name, value)| ShaderDefVal::UInt((*name).into(), value)));
    defs
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu_types::GI_CACHE;
    use crate::settings::{DebugView, Lighting};

    fn value(defs: &[ShaderDefVal], name: &str) -> Option<u32> {
        defs.iter().find_map(|d| match d {
            ShaderDefVal::UInt(n, v) if n == name => Some(*v),
            _ => None,
        })
    }

    /// Each setting the shaders branch on reaches its def, and a change of any of them is a new key (a pipeline
    /// compiled for one value must never run a frame of another).
    #[test]
    fn every_specialised_setting_is_in_the_key() {
        let base = RenderSettings::default();
        let key = |s: &RenderSettings| PassKey::of(s, Traversal::Dda, false, false);
        let defs = key(&base).shader_defs();
        assert_eq!(value(&defs, "KEY_LIGHTING"), Some(base.lighting as u32));
        assert_eq!(value(&defs, "KEY_DEBUG_VIEW"), Some(0));
        assert_eq!(value(&defs, "KEY_GI"), Some(base.gi.enabled as u32));
        assert_eq!(value(&defs, "KEY_RESTIR_FLAGS"), Some(RestirParams::of(&base).flags));
        assert!(!defs.iter().any(|d| matches!(d, ShaderDefVal::Bool(n, _) if n == "TRAVERSAL_OCCUPANCY")));
        let changes: [fn(&mut RenderSettings); 7] = [
            |s| s.lighting = Lighting::Sun,
            |s| s.shadows = !s.shadows,
            |s| s.debug = DebugView::Normal,
            |s| s.restir.spatial = !s.restir.spatial,
            |s| s.restir.light_tiles = !s.restir.light_tiles,
            |s| s.gi.enabled = !s.gi.enabled,
            |s| s.gi.cache = !s.gi.cache,
        ];
        for change in changes {
            let mut changed = base.clone();
            change(&mut changed);
            assert_ne!(key(&changed), key(&base), "{changed:?}");
        }
        let mut cached = base.clone();
        cached.gi.cache = true;
        assert_eq!(value(&key(&cached).shader_defs(), "KEY_GI_FLAGS").map(|f| f & GI_CACHE), Some(GI_CACHE));
        // Settings no shader branches on at compile time share the key (no recompiling as the player tunes them).
        let mut tuned = base.clone();
        tuned.exposure *= 2.0;
        tuned.time = 20.0;
        assert_eq!(key(&tuned), key(&base));
        assert_ne!(PassKey::of(&base, Traversal::Dda, true, false), key(&base));
        assert_eq!(value(&PassKey::of(&base, Traversal::Dda, true, false).shader_defs(), "KEY_OBJECTS"), Some(1));
        let parts = PassKey::of(&base, Traversal::Dda, false, true);
        assert_ne!(parts, key(&base));
        assert_eq!(value(&parts.shader_defs(), "KEY_POOL_PARTS"), Some(1));
        assert_eq!(value(&key(&base).shader_defs(), "KEY_POOL_PARTS"), Some(0));
        let walk = PassKey::of(&base, Traversal::Occupancy, false, false).shader_defs();
        assert!(walk.iter().any(|d| matches!(d, ShaderDefVal::Bool(n, true) if n == "TRAVERSAL_OCCUPANCY")));
    }

    #[test]
    fn generic_defs_specialise_nothing() {
        let defs = PassKey::generic(Traversal::Dda).shader_defs();
        assert_eq!(defs.len(), KEY_NAMES.len() + 1);
        assert!(KEY_NAMES.iter().all(|name| value(&defs, name) == Some(KEY_GENERIC)));
        assert_ne!(
            PassKey::generic(Traversal::Dda),
            PassKey::of(&RenderSettings::default(), Traversal::Dda, false, false)
        );
    }
}
