//! Render settings: one resource, editable in game (F4 panel) and from the command line (`--set KEY=VALUE`,
//! `--config FILE.ron`). Every key is one entry of [`SETTINGS`]: parsing, the error messages, `--help`, the HUD
//! line and the F4 panel all read that table, so adding a setting means adding one entry.

use bevy::prelude::Resource;
use bevy::render::extract_resource::ExtractResource;
use std::fmt::Display;

/// A value with names, as `--set` spells them; the F4 panel cycles through them in this order.
pub trait Named: Copy + PartialEq + Sync + 'static {
    const NAMES: &'static [(&'static str, Self)];

    fn name(self) -> &'static str {
        Self::NAMES.iter().find(|(_, v)| *v == self).map_or("?", |(n, _)| n)
    }

    /// The value called `name`, if any.
    fn named(name: &str) -> Option<Self> {
        Self::NAMES.iter().find(|(n, _)| *n == name).map(|(_, v)| *v)
    }
}

/// On/off switches.
impl Named for bool {
    const NAMES: &'static [(&'static str, bool)] = &[("on", true), ("off", false)];

    /// Also the spellings a RON file or a script may use.
    fn named(name: &str) -> Option<bool> {
        match name {
            "on" | "true" | "1" => Some(true),
            "off" | "false" | "0" => Some(false),
            _ => None,
        }
    }
}

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

impl Named for DebugView {
    const NAMES: &'static [(&'static str, DebugView)] = &[
        ("none", DebugView::None),
        ("albedo", DebugView::Albedo),
        ("normal", DebugView::Normal),
        ("hit", DebugView::Hit),
        ("depth", DebugView::Depth),
        ("reservoir", DebugView::Reservoir),
    ];
}

impl DebugView {
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

impl Named for Lighting {
    const NAMES: &'static [(&'static str, Lighting)] =
        &[("sun", Lighting::Sun), ("nee", Lighting::Nee), ("restir", Lighting::Restir)];
}

/// How NEE and ReSTIR's candidates pick a light from the pool.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightPick {
    /// In proportion to power (alias table).
    #[default]
    Power,
    Uniform,
}

impl Named for LightPick {
    const NAMES: &'static [(&'static str, LightPick)] = &[("power", LightPick::Power), ("uniform", LightPick::Uniform)];
}

/// Where ReSTIR samples a light cube.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum LightSample {
    /// A point on a face: soft shadows.
    #[default]
    Area,
    /// The cube's centre: hard shadows, less noise.
    Point,
}

impl Named for LightSample {
    const NAMES: &'static [(&'static str, LightSample)] = &[("area", LightSample::Area), ("point", LightSample::Point)];
}

/// How ReSTIR normalises reused reservoirs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reuse {
    /// The thesis' 1/M.
    #[default]
    Biased,
    /// 1/Z, with a visibility ray per neighbour.
    Unbiased,
}

impl Named for Reuse {
    const NAMES: &'static [(&'static str, Reuse)] = &[("biased", Reuse::Biased), ("unbiased", Reuse::Unbiased)];
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
    pub sample: LightSample,
    pub reuse: Reuse,
}

impl Default for RestirSettings {
    fn default() -> Self {
        RestirSettings {
            candidates: 32,
            taps: 5,
            radius: 30.0,
            temporal: true,
            spatial: true,
            sample: LightSample::Area,
            reuse: Reuse::Biased,
        }
    }
}

impl RestirSettings {
    /// Brings every field into its valid range (for settings written by code rather than `--set` or the panel).
    pub fn clamped(mut self) -> Self {
        self.candidates = self.candidates.clamp(CANDIDATES_RANGE.0, CANDIDATES_RANGE.1);
        self.taps = self.taps.clamp(TAPS_RANGE.0, TAPS_RANGE.1);
        self.radius = if self.radius.is_finite() { self.radius.clamp(RADIUS_RANGE.0, RADIUS_RANGE.1) } else { 30.0 };
        self
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

/// Most spatial taps a ReSTIR pixel merges (the `taps` range's end; the shaders loop to it).
pub const MAX_TAPS: u32 = 16;

/// Valid ranges, shared by `--set` (which rejects) and the F4 panel (which clamps).
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
    pub pick: LightPick,
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
            pick: LightPick::Power,
            accumulate: false,
            sun: true,
            shadows: true,
            exposure: 1.0,
            restir: RestirSettings::default(),
            gi: GiSettings::default(),
        }
    }
}

/// Which settings belong together: ReSTIR's only matter with `lighting=restir`, the GI cache's with `gi=on`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Section {
    General,
    Restir,
    Gi,
}

impl Section {
    pub const ALL: [Section; 3] = [Section::General, Section::Restir, Section::Gi];

    /// Whether the section's settings change the image now (the HUD shows only those).
    pub fn applies(self, settings: &RenderSettings) -> bool {
        match self {
            Section::General => true,
            Section::Restir => settings.lighting == Lighting::Restir,
            Section::Gi => settings.gi.enabled,
        }
    }

    fn title(self) -> &'static str {
        match self {
            Section::General => "General",
            Section::Restir => "Voxel ReSTIR (used with lighting=restir)",
            Section::Gi => "GI cache (used with gi=on)",
        }
    }
}

/// One setting: its `--set` key, a line for `--help`, and the field it reads and writes.
pub struct Setting {
    pub key: &'static str,
    pub section: Section,
    pub about: &'static str,
    field: &'static dyn Field,
}

/// What a setting's field accepts and how it is read, written and stepped: [`Choice`] or [`Range`].
pub trait Field: Sync {
    /// What `--set` accepts, as the messages and `--help` list it: `on|off`, `<1..64>`.
    fn accepts(&self) -> String;
    /// The current value, spelled as `--set` takes it.
    fn get(&self, settings: &RenderSettings) -> String;
    /// Parses `value` and stores it, or says why not.
    fn set(&self, settings: &mut RenderSettings, value: &str) -> Result<(), String>;
    /// The F4 panel's Left (-1) / Right (+1): the neighbouring choice (wrapping), or a step within the range.
    fn step(&self, settings: &mut RenderSettings, direction: i32);
    /// The value as the panel shows it.
    fn show(&self, settings: &RenderSettings) -> String {
        self.get(settings)
    }
}

/// A field holding one of `T`'s named values.
pub struct Choice<T> {
    pub get: fn(&RenderSettings) -> T,
    pub set: fn(&mut RenderSettings, T),
}

impl<T: Named> Field for Choice<T> {
    fn accepts(&self) -> String {
        T::NAMES.iter().map(|(name, _)| *name).collect::<Vec<_>>().join("|")
    }

    fn get(&self, settings: &RenderSettings) -> String {
        (self.get)(settings).name().to_string()
    }

    fn set(&self, settings: &mut RenderSettings, value: &str) -> Result<(), String> {
        let v = T::named(value).ok_or_else(|| format!("'{value}' is not one of {}", self.accepts()))?;
        (self.set)(settings, v);
        Ok(())
    }

    fn step(&self, settings: &mut RenderSettings, direction: i32) {
        let current = (self.get)(settings);
        let i = T::NAMES.iter().position(|(_, v)| *v == current).unwrap_or(0) as i32;
        (self.set)(settings, T::NAMES[(i + direction).rem_euclid(T::NAMES.len() as i32) as usize].1);
    }
}

/// How the panel steps a number.
#[derive(Clone, Copy, Debug)]
pub enum Step<T> {
    /// Double (Right) or halve (Left): for counts and scales that matter in powers of two.
    Double,
    /// Add or subtract this much.
    Add(T),
}

/// A field holding a number within `range` (inclusive).
pub struct Range<T> {
    pub range: (T, T),
    pub step: Step<T>,
    /// Appended in the panel, e.g. " px".
    pub unit: &'static str,
    pub get: fn(&RenderSettings) -> T,
    pub set: fn(&mut RenderSettings, T),
}

/// The two kinds of number settings hold: whole (`u32`) and real (`f32`).
pub trait Number: Copy + PartialOrd + Display + Sync + 'static {
    /// Parses `value` and checks it against `range`; the message gives the range.
    fn parse_within(value: &str, range: (Self, Self)) -> Result<Self, String>;
    /// `self` moved one `step` up (`direction` 1) or down (-1), not yet clamped to a range.
    fn stepped(self, step: Step<Self>, direction: i32) -> Self;
}

impl Number for u32 {
    fn parse_within(value: &str, (lo, hi): (u32, u32)) -> Result<u32, String> {
        let v: i64 = value.parse().map_err(|_| format!("'{value}' is not a whole number (valid: {lo}..{hi})"))?;
        if v < lo as i64 || v > hi as i64 {
            return Err(format!("{value} is out of range (valid: {lo}..{hi})"));
        }
        Ok(v as u32)
    }

    fn stepped(self, step: Step<u32>, direction: i32) -> u32 {
        match step {
            Step::Double if direction > 0 => self.saturating_mul(2),
            Step::Double => self / 2,
            Step::Add(n) => (self as i64 + n as i64 * direction as i64).clamp(0, u32::MAX as i64) as u32,
        }
    }
}

impl Number for f32 {
    fn parse_within(value: &str, (lo, hi): (f32, f32)) -> Result<f32, String> {
        let v: f32 = value.parse().map_err(|_| format!("'{value}' is not a number (valid: {lo}..{hi})"))?;
        if !(v.is_finite() && (lo..=hi).contains(&v)) {
            return Err(format!("{value} is out of range (valid: {lo}..{hi})"));
        }
        Ok(v)
    }

    fn stepped(self, step: Step<f32>, direction: i32) -> f32 {
        match step {
            Step::Double if direction > 0 => self * 2.0,
            Step::Double => self / 2.0,
            Step::Add(d) => self + d * direction as f32,
        }
    }
}

impl<T: Number> Field for Range<T> {
    fn accepts(&self) -> String {
        format!("<{}..{}>", self.range.0, self.range.1)
    }

    fn get(&self, settings: &RenderSettings) -> String {
        (self.get)(settings).to_string()
    }

    fn set(&self, settings: &mut RenderSettings, value: &str) -> Result<(), String> {
        (self.set)(settings, T::parse_within(value, self.range)?);
        Ok(())
    }

    fn step(&self, settings: &mut RenderSettings, direction: i32) {
        let v = (self.get)(settings).stepped(self.step, direction);
        let (lo, hi) = self.range;
        (self.set)(
            settings,
            if v < lo {
                lo
            } else if v > hi {
                hi
            } else {
                v
            },
        );
    }

    fn show(&self, settings: &RenderSettings) -> String {
        format!("{}{}", self.get(settings), self.unit)
    }
}

/// Every setting, in the order `--set`'s messages list them.
pub static SETTINGS: &[Setting] = &[
    Setting {
        key: "lighting",
        section: Section::General,
        about: "How surfaces are lit: sun and sky; emitters by next-event estimation; emitters by Voxel ReSTIR.",
        field: &Choice { get: |s| s.lighting, set: |s, v| s.lighting = v },
    },
    Setting {
        key: "pick",
        section: Section::General,
        about: "How NEE and ReSTIR pick lights: in proportion to power (alias table) or uniformly.",
        field: &Choice { get: |s| s.pick, set: |s, v| s.pick = v },
    },
    Setting {
        key: "accumulate",
        section: Section::General,
        about: "Average frames while nothing changes (camera, world, lights, settings).",
        field: &Choice { get: |s| s.accumulate, set: |s, v| s.accumulate = v },
    },
    Setting {
        key: "debug",
        section: Section::General,
        about: "What the image shows: the lit image, or one of its inputs (hit and reservoir are raw data for tests).",
        field: &Choice { get: |s| s.debug, set: |s, v| s.debug = v },
    },
    Setting {
        key: "sun",
        section: Section::General,
        about: "Sun light with lighting=sun (off leaves sky light and emission).",
        field: &Choice { get: |s| s.sun, set: |s, v| s.sun = v },
    },
    Setting {
        key: "shadows",
        section: Section::General,
        about: "Shadow rays towards the sun.",
        field: &Choice { get: |s| s.shadows, set: |s, v| s.shadows = v },
    },
    Setting {
        key: "exposure",
        section: Section::General,
        about: "Linear scale applied before tonemapping.",
        field: &Range {
            range: EXPOSURE_RANGE,
            step: Step::Double,
            unit: "",
            get: |s| s.exposure,
            set: |s, v| s.exposure = v,
        },
    },
    Setting {
        key: "candidates",
        section: Section::Restir,
        about: "Initial light candidates per pixel (M_init).",
        field: &Range {
            range: CANDIDATES_RANGE,
            step: Step::Double,
            unit: "",
            get: |s| s.restir.candidates,
            set: |s, v| s.restir.candidates = v,
        },
    },
    Setting {
        key: "taps",
        section: Section::Restir,
        about: "Spatial neighbours merged per pixel (k).",
        field: &Range {
            range: TAPS_RANGE,
            step: Step::Add(1),
            unit: "",
            get: |s| s.restir.taps,
            set: |s, v| s.restir.taps = v,
        },
    },
    Setting {
        key: "radius",
        section: Section::Restir,
        about: "Spatial disk radius in pixels (r).",
        field: &Range {
            range: RADIUS_RANGE,
            step: Step::Add(5.0),
            unit: " px",
            get: |s| s.restir.radius,
            set: |s, v| s.restir.radius = v,
        },
    },
    Setting {
        key: "temporal",
        section: Section::Restir,
        about: "Temporal reuse: merge last frame's reservoir at the reprojected pixel.",
        field: &Choice { get: |s| s.restir.temporal, set: |s, v| s.restir.temporal = v },
    },
    Setting {
        key: "spatial",
        section: Section::Restir,
        about: "Spatial reuse: merge neighbours' reservoirs.",
        field: &Choice { get: |s| s.restir.spatial, set: |s, v| s.restir.spatial = v },
    },
    Setting {
        key: "sample",
        section: Section::Restir,
        about: "Where a light cube is sampled: a point on a face (soft shadows) or its centre (hard, less noise).",
        field: &Choice { get: |s| s.restir.sample, set: |s, v| s.restir.sample = v },
    },
    Setting {
        key: "reuse",
        section: Section::Restir,
        about: "Normalisation of reuse: the thesis' biased 1/M, or 1/Z with a visibility ray per neighbour.",
        field: &Choice { get: |s| s.restir.reuse, set: |s, v| s.restir.reuse = v },
    },
    Setting {
        key: "gi",
        section: Section::General,
        about: "Indirect light from the per-face GI cache (play turns it on); off, no GI memory or pass.",
        field: &Choice { get: |s| s.gi.enabled, set: |s, v| s.gi.enabled = v },
    },
    Setting {
        key: "gi_rays",
        section: Section::Gi,
        about: "Fixed directions per face entry (K), traced against the static world once and cached.",
        field: &Range {
            range: GI_RAYS_RANGE,
            step: Step::Double,
            unit: "",
            get: |s| s.gi.rays,
            set: |s, v| s.gi.rays = v,
        },
    },
    Setting {
        key: "gi_update",
        section: Section::Gi,
        about: "Of those, how many each visible entry re-shades per frame (round robin).",
        field: &Range {
            range: GI_UPDATE_RAYS_RANGE,
            step: Step::Double,
            unit: "",
            get: |s| s.gi.update_rays,
            set: |s, v| s.gi.update_rays = v,
        },
    },
    Setting {
        key: "gi_alpha",
        section: Section::Gi,
        about: "Weight of a new frame in the temporal blend (a fresh entry averages its first 1/alpha frames).",
        field: &Range {
            range: GI_ALPHA_RANGE,
            step: Step::Double,
            unit: "",
            get: |s| s.gi.alpha,
            set: |s, v| s.gi.alpha = v,
        },
    },
    Setting {
        key: "gi_filter",
        section: Section::Gi,
        about: "Average each entry with its same-orientation neighbours in a 3x3x3 block.",
        field: &Choice { get: |s| s.gi.filter, set: |s, v| s.gi.filter = v },
    },
    Setting {
        key: "gi_bounces",
        section: Section::Gi,
        about: "Read last frame's indirect light at ray hits (multiple bounces); off gives one bounce.",
        field: &Choice { get: |s| s.gi.bounces, set: |s, v| s.gi.bounces = v },
    },
    Setting {
        key: "gi_cache",
        section: Section::Gi,
        about: "Keep each entry's static hits until an edit can reach them; off retraces every ray every frame.",
        field: &Choice { get: |s| s.gi.cache, set: |s, v| s.gi.cache = v },
    },
];

/// The setting called `key`.
pub fn setting(key: &str) -> Option<&'static Setting> {
    SETTINGS.iter().find(|s| s.key == key)
}

impl Setting {
    /// What `--set` accepts: `on|off`, `<1..64>`.
    pub fn accepts(&self) -> String {
        self.field.accepts()
    }

    /// The current value, spelled as `--set` takes it.
    pub fn get(&self, settings: &RenderSettings) -> String {
        self.field.get(settings)
    }

    /// Parses `value` into this setting; the error names the key and what is valid.
    pub fn set(&self, settings: &mut RenderSettings, value: &str) -> Result<(), String> {
        self.field.set(settings, value).map_err(|why| format!("setting {}: {why}", self.key))
    }

    /// The F4 panel's Left (-1) / Right (+1).
    pub fn step(&self, settings: &mut RenderSettings, direction: i32) {
        self.field.step(settings, direction)
    }

    /// The value as the panel shows it (with its unit).
    pub fn show(&self, settings: &RenderSettings) -> String {
        self.field.show(settings)
    }

    /// The value `RenderSettings::default()` holds.
    pub fn default_value(&self) -> String {
        self.field.get(&RenderSettings::default())
    }
}

/// Every key with what it accepts, on one line: `lighting=sun|nee|restir, ..., exposure=<0.001..1000>, ...`.
/// The error messages end with it.
pub fn valid_pairs() -> String {
    SETTINGS.iter().map(|s| format!("{}={}", s.key, s.accepts())).collect::<Vec<_>>().join(", ")
}

/// The settings section of `--help`: every key by section, with what it accepts, its default and what it does.
pub fn help_text() -> String {
    let mut text = String::from(
        "Render settings, for --set KEY=VALUE (repeatable) or a --config FILE.ron map such as \
         {\"lighting\": \"restir\", \"candidates\": 16}:\n",
    );
    for section in Section::ALL {
        text += &format!("\n{}:\n", section.title());
        for s in SETTINGS.iter().filter(|s| s.section == section) {
            text += &format!("  {}={}  [default: {}]\n      {}\n", s.key, s.accepts(), s.default_value(), s.about);
        }
    }
    text
}

impl RenderSettings {
    /// Applies one `KEY=VALUE` pair; unknown keys or values give an error listing the valid ones.
    pub fn set(&mut self, pair: &str) -> Result<(), String> {
        let Some((key, value)) = pair.split_once('=') else {
            return Err(format!("setting '{pair}' is not KEY=VALUE (valid: {})", valid_pairs()));
        };
        let (key, value) = (key.trim(), value.trim());
        let setting = setting(key).ok_or_else(|| format!("unknown setting '{key}' (valid: {})", valid_pairs()))?;
        setting.set(self, value)
    }

    /// Applies several pairs in order.
    pub fn with_pairs<'a>(mut self, pairs: impl IntoIterator<Item = &'a String>) -> Result<Self, String> {
        for pair in pairs {
            self.set(pair)?;
        }
        Ok(self)
    }

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
                ron::Value::Bool(b) => b.name().to_string(),
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

    /// The settings that change the image now, as `--set` pairs, one line per section: the HUD's and the log's
    /// words are the command line's.
    pub fn summary(&self) -> String {
        let line = |section| {
            SETTINGS
                .iter()
                .filter(|s| s.section == section)
                .map(|s| format!("{}={}", s.key, s.get(self)))
                .collect::<Vec<_>>()
                .join(" ")
        };
        Section::ALL.into_iter().filter(|s| s.applies(self)).map(line).collect::<Vec<_>>().join("\n")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// What `--set` accepts, split into the values to try: every name, or both ends of a range.
    fn valid_values(setting: &Setting) -> Vec<String> {
        let accepts = setting.accepts();
        match accepts.strip_prefix('<').and_then(|r| r.strip_suffix('>')) {
            Some(range) => range.split("..").map(String::from).collect(),
            None => accepts.split('|').map(String::from).collect(),
        }
    }

    #[test]
    fn the_messages_list_the_keys_and_values_as_before_the_table() {
        assert_eq!(
            valid_pairs(),
            "lighting=sun|nee|restir, pick=power|uniform, accumulate=on|off, \
             debug=none|albedo|normal|hit|depth|reservoir, sun=on|off, shadows=on|off, exposure=<0.001..1000>, \
             candidates=<1..64>, taps=<0..16>, radius=<0..100>, temporal=on|off, spatial=on|off, \
             sample=area|point, reuse=biased|unbiased, gi=on|off, gi_rays=<4..128>, gi_update=<1..64>, \
             gi_alpha=<0.001..1>, gi_filter=on|off, gi_bounces=on|off, gi_cache=on|off"
        );
    }

    #[test]
    fn every_value_a_key_advertises_round_trips() {
        for setting in SETTINGS {
            assert_eq!(SETTINGS.iter().filter(|s| s.key == setting.key).count(), 1, "{} twice", setting.key);
            let values = valid_values(setting);
            assert!(values.len() >= 2, "{}", setting.key);
            for value in values {
                let mut s = RenderSettings::default();
                s.set(&format!("{}={value}", setting.key)).unwrap();
                assert_eq!(setting.get(&s), value, "{}", setting.key);
                // Setting what get reads back changes nothing.
                let read = s.clone();
                s.set(&format!("{}={}", setting.key, setting.get(&read))).unwrap();
                assert_eq!(s, read, "{}", setting.key);
            }
            let mut s = RenderSettings::default();
            s.set(&format!("{}={}", setting.key, setting.default_value())).unwrap();
            assert_eq!(s, RenderSettings::default(), "{}", setting.key);
        }
    }

    #[test]
    fn switches_take_the_usual_spellings() {
        for (value, on) in [("on", true), ("true", true), ("1", true), ("off", false), ("false", false), ("0", false)] {
            let s = RenderSettings::default().with_pairs(&[format!("temporal={value}")]).unwrap();
            assert_eq!(s.restir.temporal, on, "{value}");
        }
    }

    #[test]
    fn an_unknown_key_or_a_missing_value_lists_every_key() {
        for pair in ["colour=blue", "colour"] {
            let error = RenderSettings::default().set(pair).unwrap_err();
            for setting in SETTINGS {
                assert!(error.contains(&format!("{}={}", setting.key, setting.accepts())), "{error}");
            }
        }
        assert!(RenderSettings::default().set("colour=blue").unwrap_err().starts_with("unknown setting 'colour'"));
        assert!(RenderSettings::default().set("colour").unwrap_err().starts_with("setting 'colour' is not KEY=VALUE"));
    }

    #[test]
    fn bad_values_are_refused_with_what_is_valid() {
        for setting in SETTINGS {
            let accepts = setting.accepts();
            let error = RenderSettings::default().set(&format!("{}=sideways", setting.key)).unwrap_err();
            if let Some(range) = accepts.strip_prefix('<').and_then(|r| r.strip_suffix('>')) {
                assert!(error.contains(&format!("(valid: {range})")), "{error}");
                let (lo, hi) = range.split_once("..").unwrap();
                let (lo, hi): (f64, f64) = (lo.parse().unwrap(), hi.parse().unwrap());
                for outside in [lo - 1.0, hi + 1.0] {
                    let error = RenderSettings::default().set(&format!("{}={outside}", setting.key)).unwrap_err();
                    let expected = format!("setting {}: {outside} is out of range (valid: {range})", setting.key);
                    assert_eq!(error, expected);
                }
            } else {
                assert_eq!(error, format!("setting {}: 'sideways' is not one of {accepts}", setting.key));
            }
        }
        assert_eq!(
            RenderSettings::default().set("candidates=lots").unwrap_err(),
            "setting candidates: 'lots' is not a whole number (valid: 1..64)"
        );
        assert_eq!(
            RenderSettings::default().set("radius=NaN").unwrap_err(),
            "setting radius: NaN is out of range (valid: 0..100)"
        );
    }

    #[test]
    fn panel_steps_stay_within_what_set_accepts() {
        for setting in SETTINGS {
            for direction in [1, -1] {
                let mut s = RenderSettings::default();
                for _ in 0..40 {
                    setting.step(&mut s, direction);
                    let value = setting.get(&s);
                    RenderSettings::default().set(&format!("{}={value}", setting.key)).unwrap();
                }
            }
        }
        // Choices cycle; numbers stop at the ends.
        let lighting = setting("lighting").unwrap();
        let mut s = RenderSettings::default();
        let mut cycle = vec![];
        for _ in 0..3 {
            lighting.step(&mut s, 1);
            cycle.push(lighting.get(&s));
        }
        assert_eq!(cycle, ["nee", "restir", "sun"]);
        lighting.step(&mut s, -1);
        assert_eq!(s.lighting, Lighting::Restir);
        let mut s = RenderSettings::default();
        (0..20).for_each(|_| setting("gi_rays").unwrap().step(&mut s, 1));
        assert_eq!(s.gi.rays, GI_RAYS_RANGE.1);
    }

    #[test]
    fn help_text_gives_every_key_its_values_and_default() {
        let help = help_text();
        for setting in SETTINGS {
            let line = format!("  {}={}  [default: {}]", setting.key, setting.accepts(), setting.default_value());
            assert!(help.contains(&line), "{line}\n{help}");
        }
        assert!(help.contains("  candidates=<1..64>  [default: 32]") && help.contains("  lighting=sun|nee|restir"));
    }

    #[test]
    fn the_summary_shows_the_sections_that_apply() {
        let s = RenderSettings::default();
        assert_eq!(s.summary().lines().count(), 1);
        assert!(s.summary().starts_with("lighting=sun pick=power"), "{}", s.summary());
        let s = s.with_pairs(&["lighting=restir".to_string(), "gi=on".to_string(), "sample=point".to_string()]);
        let summary = s.unwrap().summary();
        assert_eq!(summary.lines().count(), 3, "{summary}");
        assert!(summary.contains("candidates=32 taps=5 radius=30 temporal=on spatial=on sample=point reuse=biased"));
        assert!(summary.contains("gi_rays=64 gi_update=8 gi_alpha=0.03 gi_filter=on"), "{summary}");
    }

    #[test]
    fn a_ron_settings_file_sets_what_set_sets_and_rejects_the_same() {
        let text = r#"{"lighting": "restir", "candidates": 16, "temporal": false, "radius": 12.5, "sample": "point"}"#;
        let s = RenderSettings::default().with_ron(text, "t.ron").unwrap();
        assert_eq!(s.lighting, Lighting::Restir);
        assert_eq!((s.restir.candidates, s.restir.temporal, s.restir.radius), (16, false, 12.5));
        assert_eq!(s.restir.sample, LightSample::Point);
        let bad = RenderSettings::default().with_ron(r#"{"candidates": 0}"#, "t.ron").unwrap_err();
        assert!(bad.contains("t.ron: setting candidates: 0 is out of range (valid: 1..64)"), "{bad}");
        let broken = RenderSettings::default().with_ron("{\"lighting\": ", "t.ron").unwrap_err();
        assert!(broken.starts_with("t.ron:1:"), "{broken}");
        let nested = RenderSettings::default().with_ron(r#"{"lighting": ["restir"]}"#, "t.ron").unwrap_err();
        assert!(nested.contains("is not a string, number or bool"), "{nested}");
    }
}
