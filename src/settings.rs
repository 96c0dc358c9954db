//! Render settings: one resource, editable in game and from the command line as `--set KEY=VALUE` pairs.

use bevy::prelude::Resource;
use bevy::render::extract_resource::ExtractResource;

/// What the primary pass writes: the lit image or one of its inputs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum DebugView {
    /// Albedo lit by the sun and sky, plus emission.
    #[default]
    None,
    /// Material albedo only.
    Albedo,
    /// Face normal mapped to colour (`n * 0.5 + 0.5`).
    Normal,
    /// Exact hit ids for tests: `(voxel.x, voxel.y, voxel.z, face + 1)`, zero on a miss.
    Hit,
    /// Hit distance in voxels.
    Depth,
}

impl DebugView {
    pub const NAMES: [(&'static str, DebugView); 5] = [
        ("none", DebugView::None),
        ("albedo", DebugView::Albedo),
        ("normal", DebugView::Normal),
        ("hit", DebugView::Hit),
        ("depth", DebugView::Depth),
    ];

    /// The value the shader switches on.
    pub fn shader_index(self) -> u32 {
        self as u32
    }
}

/// How surfaces are lit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Lighting {
    /// A sun with shadows and sky light, plus emission: the game's look before the ReSTIR passes exist.
    #[default]
    Sun,
    /// Emitters only (the thesis' convention, no sky): one next-event-estimation light sample per pixel with a
    /// shadow ray. The baseline ReSTIR is measured against, and what the CPU reference converges to.
    Nee,
}

/// Settings every pass reads.
#[derive(Resource, ExtractResource, Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub debug: DebugView,
    pub lighting: Lighting,
    /// Pick lights in proportion to power (alias table) or uniformly.
    pub power_pick: bool,
    /// Average frames while nothing changes (camera, world, lights, settings).
    pub accumulate: bool,
    /// Sun light on or off (off leaves only sky light and emission).
    pub sun: bool,
    /// Shadow rays towards the sun.
    pub shadows: bool,
    /// Linear scale applied before tonemapping.
    pub exposure: f32,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            debug: DebugView::None,
            lighting: Lighting::Sun,
            power_pick: true,
            accumulate: false,
            sun: true,
            shadows: true,
            exposure: 1.0,
        }
    }
}

/// The keys `--set` accepts, with their values, for error messages and `--help`.
pub const SETTING_KEYS: &str = "lighting=sun|nee, pick=power|uniform, accumulate=on|off, \
                                 debug=none|albedo|normal|hit|depth, sun=on|off, shadows=on|off, exposure=<0.001..1000>";

fn parse_switch(key: &str, value: &str) -> Result<bool, String> {
    match value {
        "on" | "true" | "1" => Ok(true),
        "off" | "false" | "0" => Ok(false),
        _ => Err(format!("setting {key}: '{value}' is not one of on|off")),
    }
}

impl RenderSettings {
    /// Applies one `KEY=VALUE` pair; unknown keys or values give an error listing the valid ones.
    pub fn set(&mut self, pair: &str) -> Result<(), String> {
        let Some((key, value)) = pair.split_once('=') else {
            return Err(format!("setting '{pair}' is not KEY=VALUE (valid: {SETTING_KEYS})"));
        };
        let (key, value) = (key.trim(), value.trim());
        match key {
            "debug" => {
                self.debug =
                    DebugView::NAMES.iter().find(|(n, _)| *n == value).map(|(_, v)| *v).ok_or_else(|| {
                        format!("setting debug: '{value}' is not one of none|albedo|normal|hit|depth")
                    })?;
            }
            "lighting" => {
                self.lighting = match value {
                    "sun" => Lighting::Sun,
                    "nee" => Lighting::Nee,
                    _ => return Err(format!("setting lighting: '{value}' is not one of sun|nee")),
                }
            }
            "pick" => {
                self.power_pick = match value {
                    "power" => true,
                    "uniform" => false,
                    _ => return Err(format!("setting pick: '{value}' is not one of power|uniform")),
                }
            }
            "accumulate" => self.accumulate = parse_switch(key, value)?,
            "sun" => self.sun = parse_switch(key, value)?,
            "shadows" => self.shadows = parse_switch(key, value)?,
            "exposure" => {
                let v: f32 = value.parse().map_err(|_| format!("setting exposure: '{value}' is not a number"))?;
                if !(v.is_finite() && (0.001..=1000.0).contains(&v)) {
                    return Err(format!("setting exposure: {v} must be within 0.001..1000"));
                }
                self.exposure = v;
            }
            _ => return Err(format!("unknown setting '{key}' (valid: {SETTING_KEYS})")),
        }
        Ok(())
    }

    /// Applies several pairs in order.
    pub fn with_pairs<'a>(mut self, pairs: impl IntoIterator<Item = &'a String>) -> Result<Self, String> {
        for pair in pairs {
            self.set(pair)?;
        }
        Ok(self)
    }
}
