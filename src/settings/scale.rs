//! The render scale: the share of the output's pixels per axis that the lighting passes shade (`render::upscale`
//! brings their light back to the output), fixed or chosen each frame by the game's dynamic resolution.

use super::RenderSettings;
use super::table::Field;

/// `render_scale`'s range: below a quarter a render pixel spans 16 output pixels and more, and the voxel faces
/// a render pixel misses outnumber those it sees.
pub const RENDER_SCALE_RANGE: (f32, f32) = (0.25, 1.0);
/// `frame_target`'s range in milliseconds of GPU time.
pub const FRAME_TARGET_RANGE: (f32, f32) = (1.0, 10_000.0);
/// The fixed scales the F4 panel steps through (beside `auto`).
pub const PANEL_SCALES: [f32; 5] = [1.0, 0.75, 0.5, 0.33, 0.25];

/// The lighting passes' share of the output's pixels per axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RenderScale {
    /// This scale, every frame (`render` and the benches: reproducible measurements).
    Fixed(f32),
    /// The game's dynamic resolution picks it from the measured GPU time and `frame_target`
    /// (`game::dynamic_resolution`); elsewhere it means 1.
    Auto,
}

impl Default for RenderScale {
    fn default() -> Self {
        RenderScale::Fixed(1.0)
    }
}

impl RenderScale {
    /// The scale in force where no dynamic resolution chooses one (`auto` without the game's: 1).
    pub fn fixed_or_native(self) -> f32 {
        match self {
            RenderScale::Fixed(scale) => scale,
            RenderScale::Auto => 1.0,
        }
    }
}

/// The field of `render_scale`: `auto` or a number within `RENDER_SCALE_RANGE`.
pub struct ScaleField;

impl Field for ScaleField {
    fn accepts(&self) -> String {
        format!("auto|<{}..{}>", RENDER_SCALE_RANGE.0, RENDER_SCALE_RANGE.1)
    }

    fn get(&self, settings: &RenderSettings) -> String {
        match settings.render_scale {
            RenderScale::Auto => "auto".to_string(),
            RenderScale::Fixed(scale) => scale.to_string(),
        }
    }

    fn set(&self, settings: &mut RenderSettings, value: &str) -> Result<(), String> {
        if value == "auto" {
            settings.render_scale = RenderScale::Auto;
            return Ok(());
        }
        let (lo, hi) = RENDER_SCALE_RANGE;
        let scale: f32 = value.parse().map_err(|_| format!("'{value}' is not one of {}", self.accepts()))?;
        if !(scale.is_finite() && (lo..=hi).contains(&scale)) {
            return Err(format!("{value} is out of range (valid: {})", self.accepts()));
        }
        settings.render_scale = RenderScale::Fixed(scale);
        Ok(())
    }

    /// Steps through `auto` and `PANEL_SCALES` (Right: smaller, then `auto`, then 1 again); a scale between two
    /// listed ones steps to the neighbour on that side.
    fn step(&self, settings: &mut RenderSettings, direction: i32) {
        let choices: Vec<RenderScale> =
            std::iter::once(RenderScale::Auto).chain(PANEL_SCALES.iter().map(|&s| RenderScale::Fixed(s))).collect();
        let next = match settings.render_scale {
            RenderScale::Fixed(scale) if !PANEL_SCALES.iter().any(|&s| (s - scale).abs() < 1e-3) => {
                let mut listed = PANEL_SCALES.iter().copied();
                let neighbour =
                    if direction > 0 { listed.find(|&s| s < scale) } else { listed.rev().find(|&s| s > scale) };
                neighbour.map_or(RenderScale::Auto, RenderScale::Fixed)
            }
            current => {
                let at = choices.iter().position(|c| match (c, current) {
                    (RenderScale::Fixed(a), RenderScale::Fixed(b)) => (a - b).abs() < 1e-3,
                    (a, b) => *a == b,
                });
                let at = at.unwrap_or(0) as i32;
                choices[(at + direction).rem_euclid(choices.len() as i32) as usize]
            }
        };
        settings.render_scale = next;
    }

    fn show(&self, settings: &RenderSettings) -> String {
        match settings.render_scale {
            RenderScale::Auto => format!("auto (target {} ms)", settings.frame_target),
            RenderScale::Fixed(scale) => format!("{scale}"),
        }
    }
}
