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
    /// Voxel ReSTIR's final reservoir per pixel, raw: (W, M, w_sum, 1 if a field was non-finite and was reset).
    /// For the stress run; only meaningful with `lighting=restir`.
    Reservoir,
}

impl DebugView {
    pub const NAMES: [(&'static str, DebugView); 6] = [
        ("none", DebugView::None),
        ("albedo", DebugView::Albedo),
        ("normal", DebugView::Normal),
        ("hit", DebugView::Hit),
        ("depth", DebugView::Depth),
        ("reservoir", DebugView::Reservoir),
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
    /// Emitters only, by Voxel ReSTIR: candidates, temporal and spatial reuse, then one shadow ray per pixel.
    Restir,
}

impl Lighting {
    pub const NAMES: [(&'static str, Lighting); 3] =
        [("sun", Lighting::Sun), ("nee", Lighting::Nee), ("restir", Lighting::Restir)];

    pub fn name(self) -> &'static str {
        Lighting::NAMES.iter().find(|(_, l)| *l == self).map_or("?", |(n, _)| n)
    }
}

/// Voxel ReSTIR's knobs (seed 000's defaults).
#[derive(Clone, Debug, PartialEq)]
pub struct RestirSettings {
    /// Initial candidates per pixel (M_init).
    pub candidates: u32,
    /// Spatial neighbours merged per pixel (k).
    pub taps: u32,
    /// Spatial disk radius in pixels (r).
    pub radius: f32,
    pub temporal: bool,
    pub spatial: bool,
    /// Sample the centre of each light cube instead of a point on a face (hard shadows, less noise).
    pub point_lights: bool,
    /// 1/Z normalisation with a visibility ray per neighbour instead of the thesis' biased 1/M.
    pub unbiased: bool,
}

impl Default for RestirSettings {
    fn default() -> Self {
        RestirSettings {
            candidates: 32,
            taps: 5,
            radius: 30.0,
            temporal: true,
            spatial: true,
            point_lights: false,
            unbiased: false,
        }
    }
}

/// The per-voxel-face GI cache's knobs (seed 001 adapted, DESIGN.md "GI cache").
#[derive(Clone, Debug, PartialEq)]
pub struct GiSettings {
    /// Indirect light from the cache; off, the cache holds no memory and no GI pass runs.
    pub enabled: bool,
    /// Fixed directions per face entry (K), traced against the static world once and cached.
    pub rays: u32,
    /// Of those, how many each visible entry re-shades per frame (round robin).
    pub update_rays: u32,
    /// Weight of a new frame in the temporal blend (a fresh entry averages its first 1/alpha frames evenly).
    pub alpha: f32,
    /// Average each entry with its same-orientation neighbours in a 3x3x3 block.
    pub filter: bool,
    /// Read last frame's indirect light at ray hits (multiple bounces); off gives one bounce.
    pub bounces: bool,
    /// Keep each entry's static hits until an edit can reach them; off retraces every ray every frame.
    pub cache: bool,
}

impl Default for GiSettings {
    fn default() -> Self {
        GiSettings { enabled: false, rays: 64, update_rays: 8, alpha: 0.03, filter: true, bounces: true, cache: true }
    }
}

impl GiSettings {
    /// One line for the HUD.
    pub fn summary(&self) -> String {
        if !self.enabled {
            return "GI off".into();
        }
        format!(
            "GI K={} {}/frame a={} {}{}{}",
            self.rays,
            self.update_rays,
            self.alpha,
            if self.filter { "F" } else { "-" },
            if self.bounces { "B" } else { "-" },
            if self.cache { "C" } else { "-" }
        )
    }
}

/// Most spatial taps a ReSTIR pixel merges (the `taps` range's end; the shaders loop to it).
pub const MAX_TAPS: u32 = 16;

/// Valid ranges, shared by `--set` (which rejects) and the in-game keys (which clamp).
pub const GI_RAYS_RANGE: (u32, u32) = (4, 128);
pub const GI_UPDATE_RAYS_RANGE: (u32, u32) = (1, 64);
pub const GI_ALPHA_RANGE: (f32, f32) = (0.001, 1.0);
pub const CANDIDATES_RANGE: (u32, u32) = (1, 64);
pub const TAPS_RANGE: (u32, u32) = (0, MAX_TAPS);
pub const RADIUS_RANGE: (f32, f32) = (0.0, 100.0);
pub const EXPOSURE_RANGE: (f32, f32) = (0.001, 1000.0);

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
    pub restir: RestirSettings,
    pub gi: GiSettings,
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
            restir: RestirSettings::default(),
            gi: GiSettings::default(),
        }
    }
}

/// The keys `--set` accepts, with their values, for error messages and `--help`.
pub const SETTING_KEYS: &str = "lighting=sun|nee|restir, pick=power|uniform, accumulate=on|off, \
     debug=none|albedo|normal|hit|depth|reservoir, sun=on|off, shadows=on|off, exposure=<0.001..1000>, \
     candidates=<1..64>, taps=<0..16>, radius=<0..100>, temporal=on|off, spatial=on|off, \
     sample=area|point, reuse=biased|unbiased, gi=on|off, gi_rays=<4..128>, gi_update=<1..64>, \
     gi_alpha=<0.001..1>, gi_filter=on|off, gi_bounces=on|off, gi_cache=on|off";

fn parse_switch(key: &str, value: &str) -> Result<bool, String> {
    match value {
        "on" | "true" | "1" => Ok(true),
        "off" | "false" | "0" => Ok(false),
        _ => Err(format!("setting {key}: '{value}' is not one of on|off")),
    }
}

fn parse_number(key: &str, value: &str, (lo, hi): (f32, f32)) -> Result<f32, String> {
    let v: f32 = value.parse().map_err(|_| format!("setting {key}: '{value}' is not a number (valid: {lo}..{hi})"))?;
    if !(v.is_finite() && (lo..=hi).contains(&v)) {
        return Err(format!("setting {key}: {value} is out of range (valid: {lo}..{hi})"));
    }
    Ok(v)
}

fn parse_count(key: &str, value: &str, (lo, hi): (u32, u32)) -> Result<u32, String> {
    let v: i64 =
        value.parse().map_err(|_| format!("setting {key}: '{value}' is not a whole number (valid: {lo}..{hi})"))?;
    if v < lo as i64 || v > hi as i64 {
        return Err(format!("setting {key}: {value} is out of range (valid: {lo}..{hi})"));
    }
    Ok(v as u32)
}

impl RestirSettings {
    /// Brings every field into its valid range (the in-game keys step past the ends).
    pub fn clamped(mut self) -> Self {
        self.candidates = self.candidates.clamp(CANDIDATES_RANGE.0, CANDIDATES_RANGE.1);
        self.taps = self.taps.clamp(TAPS_RANGE.0, TAPS_RANGE.1);
        self.radius = if self.radius.is_finite() { self.radius.clamp(RADIUS_RANGE.0, RADIUS_RANGE.1) } else { 30.0 };
        self
    }

    /// One line for the HUD.
    pub fn summary(&self) -> String {
        format!(
            "M={} taps={} r={} {}{} {} {}",
            self.candidates,
            self.taps,
            self.radius,
            if self.temporal { "T" } else { "-" },
            if self.spatial { "S" } else { "-" },
            if self.point_lights { "point" } else { "area" },
            if self.unbiased { "unbiased" } else { "biased" }
        )
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
                self.debug = DebugView::NAMES.iter().find(|(n, _)| *n == value).map(|(_, v)| *v).ok_or_else(|| {
                    format!("setting debug: '{value}' is not one of none|albedo|normal|hit|depth|reservoir")
                })?;
            }
            "lighting" => {
                self.lighting = Lighting::NAMES
                    .iter()
                    .find(|(n, _)| *n == value)
                    .map(|(_, l)| *l)
                    .ok_or_else(|| format!("setting lighting: '{value}' is not one of sun|nee|restir"))?;
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
            "exposure" => self.exposure = parse_number(key, value, EXPOSURE_RANGE)?,
            "candidates" => self.restir.candidates = parse_count(key, value, CANDIDATES_RANGE)?,
            "taps" => self.restir.taps = parse_count(key, value, TAPS_RANGE)?,
            "radius" => self.restir.radius = parse_number(key, value, RADIUS_RANGE)?,
            "temporal" => self.restir.temporal = parse_switch(key, value)?,
            "spatial" => self.restir.spatial = parse_switch(key, value)?,
            "sample" => {
                self.restir.point_lights = match value {
                    "area" => false,
                    "point" => true,
                    _ => return Err(format!("setting sample: '{value}' is not one of area|point")),
                }
            }
            "reuse" => {
                self.restir.unbiased = match value {
                    "biased" => false,
                    "unbiased" => true,
                    _ => return Err(format!("setting reuse: '{value}' is not one of biased|unbiased")),
                }
            }
            "gi" => self.gi.enabled = parse_switch(key, value)?,
            "gi_rays" => self.gi.rays = parse_count(key, value, GI_RAYS_RANGE)?,
            "gi_update" => self.gi.update_rays = parse_count(key, value, GI_UPDATE_RAYS_RANGE)?,
            "gi_alpha" => self.gi.alpha = parse_number(key, value, GI_ALPHA_RANGE)?,
            "gi_filter" => self.gi.filter = parse_switch(key, value)?,
            "gi_bounces" => self.gi.bounces = parse_switch(key, value)?,
            "gi_cache" => self.gi.cache = parse_switch(key, value)?,
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

impl RenderSettings {
    /// Applies a RON settings file: a map of the `--set` keys to values, e.g.
    /// `{"lighting": "restir", "candidates": 16, "temporal": true, "sample": "point"}`. Numbers, strings and
    /// booleans are accepted; each pair goes through `set`, so the ranges and messages are the same.
    pub fn with_ron(mut self, text: &str, origin: &str) -> Result<Self, String> {
        let map: std::collections::BTreeMap<String, ron::Value> = ron::from_str(text).map_err(|e| {
            format!(
                "{origin}:{}:{}: {} (expected a map such as {{\"lighting\": \"restir\"}})",
                e.span.start.line, e.span.start.col, e.code
            )
        })?;
        for (key, value) in map {
            let value = match value {
                ron::Value::String(s) => s,
                ron::Value::Bool(b) => (if b { "on" } else { "off" }).to_string(),
                ron::Value::Number(n) => match n {
                    ron::value::Number::F32(f) => f.get().to_string(),
                    ron::value::Number::F64(f) => f.get().to_string(),
                    other => format!("{}", other.into_f64()),
                },
                other => return Err(format!("{origin}: setting {key}: {other:?} is not a string, number or bool")),
            };
            self.set(&format!("{key}={value}")).map_err(|e| format!("{origin}: {e}"))?;
        }
        Ok(self)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_ron_settings_file_sets_what_set_sets_and_rejects_the_same() {
        let text = r#"{"lighting": "restir", "candidates": 16, "temporal": false, "radius": 12.5, "sample": "point"}"#;
        let s = RenderSettings::default().with_ron(text, "t.ron").unwrap();
        assert_eq!(s.lighting, Lighting::Restir);
        assert_eq!((s.restir.candidates, s.restir.temporal, s.restir.radius), (16, false, 12.5));
        assert!(s.restir.point_lights);
        let bad = RenderSettings::default().with_ron(r#"{"candidates": 0}"#, "t.ron").unwrap_err();
        assert!(bad.contains("t.ron: setting candidates: 0 is out of range (valid: 1..64)"), "{bad}");
        let broken = RenderSettings::default().with_ron("{\"lighting\": ", "t.ron").unwrap_err();
        assert!(broken.starts_with("t.ron:1:"), "{broken}");
        let nested = RenderSettings::default().with_ron(r#"{"lighting": ["restir"]}"#, "t.ron").unwrap_err();
        assert!(nested.contains("is not a string, number or bool"), "{nested}");
    }
}
