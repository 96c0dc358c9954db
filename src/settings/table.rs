//! The settings table: one entry per `--set` key (its section, a line of help, and the field it reads and
//! writes, a named choice or a numeric range), and what is derived from it: parsing with its messages, the
//! settings section of `--help`, the panel's stepping.

use super::*;

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
            Section::Restir => settings.lighting.uses_restir(),
            Section::Gi => settings.gi.enabled,
        }
    }

    fn title(self) -> &'static str {
        match self {
            Section::General => "General",
            Section::Restir => "Voxel ReSTIR (used with lighting=full and lighting=emitters)",
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
        about: "How surfaces are lit: sun or moon, sky and emitters (ReSTIR); emitters only by Voxel ReSTIR \
                (the thesis' protocol; also `restir`); emitters only by next-event estimation; the old sun-only look.",
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
        about: "Sun (or moon) light with lighting=full or sun (off leaves sky light and emission).",
        field: &Choice { get: |s| s.sun, set: |s, v| s.sun = v },
    },
    Setting {
        key: "time",
        section: Section::General,
        about: "Time of day in hours: noon 12, sunset 18, night 0; moves the sun and colours it and the sky.",
        field: &Range { range: TIME_RANGE, step: Step::Add(1.0), unit: " h", get: |s| s.time, set: |s, v| s.time = v },
    },
    Setting {
        key: "shadows",
        section: Section::General,
        about: "Shadow rays towards the sun or moon.",
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
        key: "seed",
        section: Section::General,
        about: "Where the random sequences start: renders with different seeds are independent, to measure a result's \
                spread. A change starts the GI cache over.",
        field: &Range { range: SEED_RANGE, step: Step::Add(1), unit: "", get: |s| s.seed, set: |s, v| s.seed = v },
    },
    Setting {
        key: "traversal",
        section: Section::General,
        about: "How the GPU's rays walk the grid: the plain DDA, or the occupancy masks that jump empty space (fewer \
                steps and memory loads, more arithmetic per step); auto: the DDA on a CPU adapter (software Vulkan), \
                the masks on a GPU. Both find the same voxels.",
        field: &Choice { get: |s| s.traversal, set: |s, v| s.traversal = v },
    },
    Setting {
        key: "pacing",
        section: Section::General,
        about: "The game renders a frame in the update that reads its input (no pipelined rendering; read at start) and \
                keeps at most one frame of GPU work in flight, so input shows within a frame or two; off: Bevy's \
                pipelined rendering and the driver's own queue (a frame or more of extra latency).",
        field: &Choice { get: |s| s.pacing, set: |s, v| s.pacing = v },
    },
    Setting {
        key: "denoise",
        section: Section::General,
        about: "Spatiotemporal denoiser (SVGF family) on the lit image; play turns it on (debug=variance|history \
                show its inputs).",
        field: &Choice { get: |s| s.denoise, set: |s, v| s.denoise = v },
    },
    Setting {
        key: "render_scale",
        section: Section::General,
        about: "The lighting passes' share of the output's pixels per axis (ReSTIR, the GI resolve, the denoiser), \
                upscaled by voxel-face plane with temporal accumulation at the output; auto: the game's dynamic \
                resolution follows the GPU time toward frame_target (elsewhere auto is 1). Lit views with ReSTIR only.",
        field: &super::scale::ScaleField,
    },
    Setting {
        key: "frame_target",
        section: Section::General,
        about: "GPU milliseconds per frame that render_scale=auto steers toward.",
        field: &Range {
            range: FRAME_TARGET_RANGE,
            step: Step::Double,
            unit: " ms",
            get: |s| s.frame_target,
            set: |s, v| s.frame_target = v,
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
        about: "Visibility in the reuse weights: none (biased, darker at shadow edges), one ray per neighbour \
                (unbiased for a still view) or two (unbiased, less noise).",
        field: &Choice { get: |s| s.restir.reuse, set: |s, v| s.restir.reuse = v },
    },
    Setting {
        key: "local_lights",
        section: Section::Restir,
        about: "Draw a quarter of the candidates among the lights touching the air in front of the shaded face.",
        field: &Choice { get: |s| s.restir.local_lights, set: |s, v| s.restir.local_lights = v },
    },
    Setting {
        key: "initial_visibility",
        section: Section::Restir,
        about: "A visibility ray for each pixel's chosen candidate before reuse; off, the final shadow ray's \
                verdict is what next frame reuses (one ray fewer).",
        field: &Choice { get: |s| s.restir.initial_visibility, set: |s, v| s.restir.initial_visibility = v },
    },
    Setting {
        key: "light_tiles",
        section: Section::Restir,
        about: "Draw the candidates from tiles of lights presampled by power each frame (one coherent load a \
                candidate); off, each candidate reads the alias table and the light pool itself.",
        field: &Choice { get: |s| s.restir.light_tiles, set: |s, v| s.restir.light_tiles = v },
    },
    Setting {
        key: "gi",
        section: Section::General,
        about: "Indirect light from the per-face GI cache (play turns it on); off, no GI memory or pass.",
        field: &Choice { get: |s| s.gi.enabled, set: |s, v| s.gi.enabled = v },
    },
    Setting {
        key: "gi_cached_rays",
        section: Section::Gi,
        about: "Fixed directions per face entry (K) with gi_cached_hits=on (unused otherwise), traced against the \
                static world once and cached. Was `gi_rays`, still read.",
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
        about: "Rays each entry traces per frame: fresh directions, or with gi_cached_hits=on the next of its K (round robin).",
        field: &Range {
            range: GI_UPDATE_RAYS_RANGE,
            step: Step::Double,
            unit: "",
            get: |s| s.gi.update_rays,
            set: |s, v| s.gi.update_rays = v,
        },
    },
    Setting {
        key: "gi_period",
        section: Section::Gi,
        about: "Frames between updates of a settled entry (blended 2/alpha frames, no moving object in its rays): \
                the same noise for 1/period of the rays, slow changes followed period times slower.",
        field: &Range {
            range: GI_PERIOD_RANGE,
            step: Step::Double,
            unit: "",
            get: |s| s.gi.period,
            set: |s, v| s.gi.period = v,
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
        key: "gi_table",
        section: Section::Gi,
        about: "Slots in the GI cache's table (rounded up to a power of two; 156 bytes each, 408 with gi_cached_hits=on at gi_cached_rays=64). A full \
                table leaves new faces without indirect light, counted as gi_full.",
        field: &Range {
            range: GI_TABLE_RANGE,
            step: Step::Double,
            unit: "",
            get: |s| s.gi.table,
            set: |s, v| s.gi.table = v,
        },
    },
    Setting {
        key: "gi_cell",
        section: Section::Gi,
        about: "Width in pixels the cache's cells have at least on screen (a cell is 2^k voxels, k from the pixel \
                footprint): 1 keeps one entry per voxel face up close, larger values fewer, cheaper, blurrier entries.",
        field: &Range {
            range: GI_CELL_RANGE,
            step: Step::Double,
            unit: "",
            get: |s| s.gi.cell_pixels,
            set: |s, v| s.gi.cell_pixels = v,
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
        key: "gi_cached_hits",
        section: Section::Gi,
        about: "Cache each entry's static hits along K fixed directions until an edit reaches them (cheaper, but \
                each entry keeps the error of its fixed set); off traces fresh directions every frame. Was \
                `gi_cache`, still read.",
        field: &Choice { get: |s| s.gi.cache, set: |s, v| s.gi.cache = v },
    },
    Setting {
        key: "gi_qmc",
        section: Section::Gi,
        about: "Draw each entry's fresh rays and direct-light points from its own low-discrepancy sequence, frame \
                after frame (off: independent random ones, which leave a slow swing in the bounce light).",
        field: &Choice { get: |s| s.gi.qmc, set: |s, v| s.gi.qmc = v },
    },
    Setting {
        key: "gi_reservoirs",
        section: Section::Gi,
        about: "Each entry draws its light-pool light through a reservoir kept from frame to frame (32 lights by \
                power a sample, resampled, merged with its past ones; seed 002); off, one light by power a sample.",
        field: &Choice { get: |s| s.gi.reservoirs, set: |s, v| s.gi.reservoirs = v },
    },
    Setting {
        key: "gi_guiding",
        section: Section::Gi,
        about: "Each entry's fresh rays lean toward where its light came from (a 16-bin histogram of its own rays, \
                mixed half and half with the cosine lobe, weighted so the estimate stays unbiased; seed 004); off, \
                the cosine lobe alone. No effect with gi_cached_hits=on.",
        field: &Choice { get: |s| s.gi.guiding, set: |s, v| s.gi.guiding = v },
    },
    Setting {
        key: "gi_warm_up",
        section: Section::Gi,
        about: "Four update iterations a frame in a fresh cache's first 64 frames, so a room lit over many bounces \
                is bright within a second (off: one a frame from the start; frames then cost less but the room \
                brightens slowly).",
        field: &Choice { get: |s| s.gi.warm_up, set: |s, v| s.gi.warm_up = v },
    },
];

/// Keys renamed since settings files and scripts were written with them: (old, new). The old key is still read.
pub const RENAMED: [(&str, &str); 2] = [("gi_cache", "gi_cached_hits"), ("gi_rays", "gi_cached_rays")];

/// The setting called `key` (or once called `key`).
pub fn setting(key: &str) -> Option<&'static Setting> {
    let key = RENAMED.iter().find(|(old, _)| *old == key).map_or(key, |(_, new)| *new);
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
