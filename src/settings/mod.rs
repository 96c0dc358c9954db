//! Render settings: one resource, editable in game (F4 panel) and from the command line (`--set KEY=VALUE`,
//! `--config FILE.ron`). This module holds the values (the resource, its parts and the named choices); every key
//! is one entry of the table [`SETTINGS`] (`table.rs`): parsing, the error messages, `--help`, the HUD line and
//! the F4 panel all read it, so adding a setting means adding one entry.

mod scale;
mod table;

pub use scale::{FRAME_TARGET_RANGE, PANEL_SCALES, RENDER_SCALE_RANGE, RenderScale};
pub use table::{Choice, Field, Range, SETTINGS, Section, Setting, Step, help_text, setting, valid_pairs};

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
    /// The denoiser's luminance variance estimate (its square root, grey), where it filters.
    Variance,
    /// The denoiser's history length per pixel, over its cap (1 = white: a full history).
    History,
    /// The GI cache's share of the lit image alone (each surface's albedo times the cache's incoming light), in
    /// the image's units: what `reference --indirect` renders, pixel for pixel. Needs `gi=on` (black without).
    Indirect,
}

impl Named for DebugView {
    const NAMES: &'static [(&'static str, DebugView)] = &[
        ("none", DebugView::None),
        ("albedo", DebugView::Albedo),
        ("normal", DebugView::Normal),
        ("hit", DebugView::Hit),
        ("depth", DebugView::Depth),
        ("reservoir", DebugView::Reservoir),
        ("variance", DebugView::Variance),
        ("history", DebugView::History),
        ("indirect", DebugView::Indirect),
    ];
}

impl DebugView {
    /// The value the shader switches on.
    pub fn shader_index(self) -> u32 {
        self as u32
    }

    /// Whether the view shows the lit image (or the denoiser's view of it), so every lighting pass runs.
    pub fn is_lit(self) -> bool {
        matches!(self, DebugView::None | DebugView::Variance | DebugView::History | DebugView::Indirect)
    }
}

/// How surfaces are lit.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Lighting {
    /// The game's frame: the sun (or moon) disk with soft shadows, the sky, and every emitter at once. Emitters
    /// by Voxel ReSTIR, the disk by one shadow ray to a point of it, the sky through the GI cache (or, with
    /// `gi=off`, one cosine-sampled ray). The CPU reference renders the same (`reference --set lighting=full`).
    #[default]
    Full,
    /// Emitters only by Voxel ReSTIR (the thesis' protocol, no sky): candidates, temporal and spatial reuse,
    /// then one shadow ray per pixel. Also spelled `restir`, its name before the sun and sky joined it.
    Emitters,
    /// Emitters only: one next-event-estimation light sample per pixel with a shadow ray. The baseline ReSTIR
    /// is measured against.
    Nee,
    /// Debug view: the old quick look, a sun without a disk, a crude sky ambient (or the GI cache), emission;
    /// no ReSTIR.
    Sun,
}

impl Named for Lighting {
    const NAMES: &'static [(&'static str, Lighting)] =
        &[("full", Lighting::Full), ("emitters", Lighting::Emitters), ("nee", Lighting::Nee), ("sun", Lighting::Sun)];

    /// `restir` is still read (settings files and scripts from before `full` existed).
    fn named(name: &str) -> Option<Lighting> {
        match name {
            "restir" => Some(Lighting::Emitters),
            _ => Self::NAMES.iter().find(|(n, _)| *n == name).map(|(_, v)| *v),
        }
    }
}

impl Lighting {
    /// Whether Voxel ReSTIR samples the emitters (its settings apply).
    pub fn uses_restir(self) -> bool {
        matches!(self, Lighting::Full | Lighting::Emitters)
    }

    /// Whether the sun (or moon) disk and the sky light the scene (the CPU reference's `Daylight`).
    pub fn has_daylight(self) -> bool {
        matches!(self, Lighting::Full | Lighting::Sun)
    }
}

/// How rays walk the brick grid (`world::traversal`); both find the same voxels.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Traversal {
    /// The walk that suits the adapter: the plain DDA on a CPU adapter (software Vulkan, whose SIMD lanes pay for
    /// every branch any of them takes), the occupancy masks on a GPU (whose rays wait on their memory loads).
    #[default]
    Auto,
    /// The plain two-level DDA: brick by brick, then voxel by voxel in stored bricks, one load per step.
    Dda,
    /// Through the occupancy hierarchy (`world::occupancy`): one step per empty cell of 128 down to 2 voxels,
    /// 2.2-5.2x fewer steps and 1.4-5.6x fewer loads per ray than the DDA, but slower on lavapipe
    /// (`docs/bench/traversal.md`).
    Occupancy,
}

impl Traversal {
    /// The walk this setting means on an adapter that is (`true`) or is not a CPU.
    pub fn resolve(self, cpu_adapter: bool) -> Traversal {
        match self {
            Traversal::Auto if cpu_adapter => Traversal::Dda,
            Traversal::Auto => Traversal::Occupancy,
            walk => walk,
        }
    }
}

impl Named for Traversal {
    const NAMES: &'static [(&'static str, Traversal)] =
        &[("auto", Traversal::Auto), ("dda", Traversal::Dda), ("occupancy", Traversal::Occupancy)];
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

/// How ReSTIR weighs reused reservoirs (pairwise MIS, `shaders/restir/common.wgsl`): which visibility rays the
/// MIS weights pay for.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Reuse {
    /// No rays: a neighbour's weight for this pixel's sample ignores whether the neighbour sees it (darker near
    /// shadow edges, docs/bench/why.md). The thesis' protocol (`assets/settings/thesis.ron`).
    Biased,
    /// One ray per neighbour: whether the neighbour sees this pixel's sample. Unbiased for a static view, and
    /// a little dearer than `Biased` (docs/bench/restir.md).
    #[default]
    OneRay,
    /// Two rays per neighbour: also whether this pixel sees the neighbour's sample, so an occluded one is never
    /// picked (less noise than `OneRay`).
    Unbiased,
}

impl Named for Reuse {
    const NAMES: &'static [(&'static str, Reuse)] =
        &[("biased", Reuse::Biased), ("one-ray", Reuse::OneRay), ("unbiased", Reuse::Unbiased)];
}

/// Voxel ReSTIR's knobs (seed 000's, with one spatial tap instead of five: `assets/settings/thesis.ron` has the
/// thesis').
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
    /// A share of the candidates is drawn among the lights beside the shaded face (a lamp lying on a floor is
    /// otherwise a 1-in-N find for the power pick, and a firefly when found).
    pub local_lights: bool,
    /// A visibility ray for each pixel's chosen candidate before reuse (the thesis' visibility reuse, §4.4). Off,
    /// the final shadow ray's verdict is the one next frame's temporal reuse inherits (W = 0 when occluded), as
    /// in RTXDI's final visibility reuse: one ray fewer per pixel.
    pub initial_visibility: bool,
    /// Candidates drawn from presampled light tiles (RTXDI's): each frame a pass draws `LIGHT_TILES` x
    /// `LIGHT_TILE_SIZE` lights by power into a buffer, copies of the lights beside them, and every 4x4 block of
    /// pixels draws its candidates from one tile: one load a candidate, from a few kilobytes every lane of the
    /// block shares, instead of two or three dependent loads scattered over the alias table and the light pool.
    pub light_tiles: bool,
}

impl Default for RestirSettings {
    fn default() -> Self {
        RestirSettings {
            // One tap: per frame more accurate than the thesis' 5 on every scene measured, and 4 rays per hit pixel
            // at most on average (the ray budget test). 16 candidates were cheaper still at equal time in the
            // rooms but too noisy among 10^5 lamps (docs/bench/why.md).
            candidates: 32,
            taps: 1,
            radius: 30.0,
            temporal: true,
            spatial: true,
            sample: LightSample::Area,
            reuse: Reuse::OneRay,
            local_lights: true,
            initial_visibility: true,
            light_tiles: true,
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
    /// Fixed directions per face entry (K) with the static visibility cache (`cache`), traced against the static
    /// world once and cached; without it each frame draws `update_rays` fresh ones.
    pub rays: u32,
    /// Rays each entry traces per frame: fresh directions, or with `cache` the next of its K (round robin).
    pub update_rays: u32,
    /// Weight of a new frame in the temporal blend (a fresh entry averages its first 1/alpha frames evenly).
    pub alpha: f32,
    /// Average each entry with its same-orientation neighbours in a 3x3x3 block.
    pub filter: bool,
    /// Read last frame's indirect light at ray hits (multiple bounces); off gives one bounce.
    pub bounces: bool,
    /// Keep each entry's static hits along K fixed directions until an edit can reach them. Off (the default),
    /// every frame traces fresh stratified directions from faces across the entry's cell: at 320x180 the GI passes
    /// cost up to 0.16 of the direct frame more, but a fixed set of 64 directions leaves every entry an error of its
    /// own that no blend averages (the window room's denoised frame against 8-bounce references: relMSE 0.0031 with
    /// it, 0.0020 without; docs/bench/gi.md "Fresh directions", "Rays from across the cell").
    pub cache: bool,
    /// Draw each entry's fresh rays (direction and start point) and its direct light's points on the cell from
    /// the entry's own low-discrepancy sequence, frame after frame; off, independent random ones. A blend over
    /// frames then covers the hemisphere and the cell evenly: the slow swing a few half-lit cells gave a whole
    /// room's bounce light falls (docs/bench/gi.md, "Low-discrepancy rays").
    pub qmc: bool,
    /// Draw an entry's light-pool light through a reservoir it keeps from frame to frame (seed 002): 32 lights by
    /// power a sample, resampled by their unshadowed light, merged with the entry's reservoir of the frames
    /// before, one shadow ray, plus a resampled sample of the lights the cell's centre cannot see; off, one light by
    /// power a sample (docs/bench/gi.md, "Reservoirs per entry": 6-38x less noise in the cache's light among
    /// thousands of lamps).
    pub reservoirs: bool,
    /// Draw an entry's fresh rays from a mixture of the cosine lobe and a histogram of where its light came
    /// from, learnt from its own rays (seed 004's guiding toward the voxels that carry light), each weighted by
    /// the cosine lobe's density over the mixture's; off, the cosine lobe alone (docs/bench/gi.md, "Guided
    /// rays"). Unused with `cache` (cached hits keep fixed directions).
    pub guiding: bool,
    /// Run four update iterations a frame in a fresh cache's first 64 frames (and after a reset): a room lit
    /// over many bounces is then bright within a second instead of brightening for hundreds of frames
    /// (docs/bench/gi.md, "A fresh cache warms up"); off, one a frame from the start.
    pub warm_up: bool,
    /// Slots in the static world's table (rounded up to a power of two). A full table fails inserts, which the
    /// `GiFull` counter, the bench and the HUD report.
    pub table: u32,
    /// How wide, at least, a camera's cells of the cache are on screen, in pixels: a surface is read at the
    /// finest level of detail whose cell (2^k voxels) spans this many pixels. 1 keeps one entry per voxel face
    /// while a voxel spans a pixel or more; the default 4 keeps about one per 16-64 pixels (seed 002's adaptive
    /// cells), 3-9x fewer entries and GI passes 2.5-4x cheaper at 320x180 for about the same error.
    pub cell_pixels: u32,
    /// Frames between two updates of a settled entry (blended for 2 / alpha frames, no moving object among its
    /// hits): at one update every `period` frames it keeps the same noise (the blend weight per update is
    /// unchanged) for 1 / period of the GI rays, but follows every slow change `period` times slower. Young
    /// entries, entries a moving object's light reaches, and every entry in the frames after a change of light
    /// or an edit update every frame. 1 (every frame) by default: a large open scene's bounce light still
    /// converges for hundreds of frames after its blends settle, and 2 doubled that (docs/bench/why.md).
    pub period: u32,
}

impl Default for GiSettings {
    fn default() -> Self {
        GiSettings {
            enabled: false,
            rays: 64,
            update_rays: 8,
            alpha: 0.03,
            filter: true,
            bounces: true,
            cache: false,
            qmc: true,
            reservoirs: true,
            guiding: false,
            warm_up: true,
            table: GI_TABLE_DEFAULT,
            cell_pixels: 4,
            period: 1,
        }
    }
}

/// Most spatial taps a ReSTIR pixel merges (the `taps` range's end; the shaders loop to it).
pub const MAX_TAPS: u32 = 16;

/// Valid ranges, shared by `--set` (which rejects) and the F4 panel (which clamps).
pub const GI_RAYS_RANGE: (u32, u32) = (4, 128);
pub const GI_PERIOD_RANGE: (u32, u32) = (1, 8);
pub const GI_UPDATE_RAYS_RANGE: (u32, u32) = (1, 64);
pub const GI_ALPHA_RANGE: (f32, f32) = (0.001, 1.0);
pub const GI_TABLE_RANGE: (u32, u32) = (1 << 12, 1 << 22);
pub const GI_TABLE_DEFAULT: u32 = 1 << 18;
pub const GI_CELL_RANGE: (u32, u32) = (1, 16);
/// `seed`'s range, and the frames one seed moves the passes' frame counters by (their random numbers hash the
/// frame): a thousand seeds of 2^16 frames each stay clear of the counters' wrap for 4 billion frames.
pub const SEED_RANGE: (u32, u32) = (0, 1000);
pub const SEED_FRAMES: u32 = 1 << 16;
pub const CANDIDATES_RANGE: (u32, u32) = (1, 64);
pub const TAPS_RANGE: (u32, u32) = (0, MAX_TAPS);
pub const RADIUS_RANGE: (f32, f32) = (0.0, 100.0);
pub const EXPOSURE_RANGE: (f32, f32) = (0.001, 1000.0);
pub const TIME_RANGE: (f32, f32) = (0.0, 24.0);

/// Settings every pass reads.
#[derive(Resource, ExtractResource, Clone, Debug, PartialEq)]
pub struct RenderSettings {
    pub debug: DebugView,
    pub lighting: Lighting,
    pub pick: LightPick,
    /// Average frames while nothing changes (camera, world, lights, settings).
    pub accumulate: bool,
    /// Sun (or moon) light on or off (off leaves only sky light and emission).
    pub sun: bool,
    /// Time of day in hours (0-24): where the sun or moon stands and the colours of it and the sky
    /// (`lights::daylight`).
    pub time: f32,
    /// Shadow rays towards the sun.
    pub shadows: bool,
    /// Linear scale applied before tonemapping.
    pub exposure: f32,
    /// The spatiotemporal denoiser (`render::denoise`): on in `play`, off by default so `render`, the bench and
    /// the thesis protocol measure raw frames.
    pub denoise: bool,
    /// Where the random sequences start (0 by default): renders with different seeds are independent
    /// realisations of the same image, for measuring the spread of a result (the GI cache's slow noise moves a
    /// room's mean by a percent or two between them).
    pub seed: u32,
    /// How the GPU's rays walk the grid (the CPU reference walks it with the DDA; the hits are the same).
    pub traversal: Traversal,
    /// The game renders each frame in the update that reads its input (no pipelined rendering, decided at start)
    /// and keeps at most one frame of GPU work in flight, so input shows within a frame or two
    /// (`game::frame_pacing`); off lets Bevy pipeline and the driver queue frames ahead. Only the game reads it.
    pub pacing: bool,
    /// The lighting passes' share of the output's pixels per axis (`render::upscale` brings their light to the
    /// output): fixed (1 by default, so `render` and the benches measure native frames), or `auto` in the game.
    pub render_scale: RenderScale,
    /// The GPU time per frame in milliseconds that `render_scale=auto` steers toward.
    pub frame_target: f32,
    pub restir: RestirSettings,
    pub gi: GiSettings,
}

impl Default for RenderSettings {
    fn default() -> Self {
        RenderSettings {
            debug: DebugView::None,
            lighting: Lighting::Full,
            pick: LightPick::Power,
            accumulate: false,
            sun: true,
            time: crate::lights::daylight::DEFAULT_HOURS,
            shadows: true,
            exposure: 1.0,
            denoise: false,
            seed: 0,
            traversal: Traversal::Auto,
            pacing: true,
            render_scale: RenderScale::Fixed(1.0),
            frame_target: 16.7,
            restir: RestirSettings::default(),
            gi: GiSettings::default(),
        }
    }
}

impl RenderSettings {
    /// The settings `play` starts from: the defaults with the GI cache, the denoiser and dynamic resolution on (the
    /// defaults leave them off so `render`, the bench and the thesis protocol measure raw direct light).
    pub fn game() -> Self {
        let mut settings = RenderSettings::default();
        settings.gi.enabled = true;
        settings.denoise = true;
        settings.render_scale = RenderScale::Auto;
        settings
    }

    /// These settings at the time of day `world` was saved at, if it was.
    pub fn with_world_time(mut self, world: &crate::world::VoxelWorld) -> Self {
        if let Some(hours) = world.time_of_day {
            self.time = hours;
        }
        self
    }

    /// The sun or moon and the sky these settings light with, or `None` for emitters-only lighting.
    pub fn daylight(&self) -> Option<crate::lights::daylight::Daylight> {
        self.lighting.has_daylight().then(|| crate::lights::daylight::Daylight::at(self.time, self.sun))
    }

    /// Applies one `KEY=VALUE` pair; unknown keys or values give an error listing the valid ones, in one line
    /// even when the pair quotes a newline (found by the fuzzer: a settings file's string spanning lines).
    pub fn set(&mut self, pair: &str) -> Result<(), String> {
        self.set_pair(pair).map_err(|e| crate::world::format::one_line(&e))
    }

    fn set_pair(&mut self, pair: &str) -> Result<(), String> {
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
                other => {
                    let error = format!("{origin}: setting {key}: {other:?} is not a string, number or bool");
                    return Err(crate::world::format::one_line(&error));
                }
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
mod tests;
