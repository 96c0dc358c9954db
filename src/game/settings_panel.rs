//! The in-game render settings panel (F4): Up/Down choose a row, Left/Right change it. Values step within the
//! same ranges `--set` accepts (`crate::settings`), clamped at the ends. L cycles the lighting mode at any time.

use crate::settings::{CANDIDATES_RANGE, Lighting, RADIUS_RANGE, RenderSettings, TAPS_RANGE};
use bevy::prelude::*;

/// The rows of the panel, top to bottom.
pub const ROWS: [&str; 10] =
    ["lighting", "candidates", "taps", "radius", "temporal", "spatial", "sample", "reuse", "pick", "accumulate"];

#[derive(Resource, Default, Debug)]
pub struct SettingsPanel {
    pub open: bool,
    pub row: usize,
}

#[derive(Component)]
struct PanelText;

/// Changes row `row` of `settings` by `step` (+1 / -1): numbers double or halve (radius in steps of 5), switches
/// flip, the lighting mode cycles. Results stay inside the valid ranges.
pub fn adjust(settings: &mut RenderSettings, row: usize, step: i32) {
    let r = &mut settings.restir;
    match ROWS.get(row).copied() {
        Some("lighting") => {
            let names = Lighting::NAMES;
            let i = names.iter().position(|(_, l)| *l == settings.lighting).unwrap_or(0) as i32;
            settings.lighting = names[(i + step).rem_euclid(names.len() as i32) as usize].1;
        }
        Some("candidates") => {
            let v = if step > 0 { r.candidates.saturating_mul(2) } else { r.candidates / 2 };
            r.candidates = v.clamp(CANDIDATES_RANGE.0, CANDIDATES_RANGE.1);
        }
        Some("taps") => r.taps = (r.taps as i32 + step).clamp(TAPS_RANGE.0 as i32, TAPS_RANGE.1 as i32) as u32,
        Some("radius") => r.radius = (r.radius + 5.0 * step as f32).clamp(RADIUS_RANGE.0, RADIUS_RANGE.1),
        Some("temporal") => r.temporal = !r.temporal,
        Some("spatial") => r.spatial = !r.spatial,
        Some("sample") => r.point_lights = !r.point_lights,
        Some("reuse") => r.unbiased = !r.unbiased,
        Some("pick") => settings.power_pick = !settings.power_pick,
        Some("accumulate") => settings.accumulate = !settings.accumulate,
        _ => {}
    }
}

fn value(settings: &RenderSettings, row: &str) -> String {
    let r = &settings.restir;
    let on = |b: bool| if b { "on" } else { "off" }.to_string();
    match row {
        "lighting" => settings.lighting.name().to_string(),
        "candidates" => r.candidates.to_string(),
        "taps" => r.taps.to_string(),
        "radius" => format!("{} px", r.radius),
        "temporal" => on(r.temporal),
        "spatial" => on(r.spatial),
        "sample" => if r.point_lights { "point" } else { "area" }.to_string(),
        "reuse" => if r.unbiased { "unbiased" } else { "biased" }.to_string(),
        "pick" => if settings.power_pick { "power" } else { "uniform" }.to_string(),
        "accumulate" => on(settings.accumulate),
        _ => String::new(),
    }
}

/// The panel's text, the chosen row marked.
pub fn panel_text(settings: &RenderSettings, panel: &SettingsPanel) -> String {
    let mut text = String::from("render settings (F4 closes)\nUp/Down choose, Left/Right change\n\n");
    for (i, row) in ROWS.iter().enumerate() {
        let mark = if i == panel.row { ">" } else { " " };
        text += &format!("{mark} {row:<11} {}\n", value(settings, row));
    }
    text
}

pub struct SettingsPanelPlugin;

impl Plugin for SettingsPanelPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<SettingsPanel>().add_systems(Startup, spawn_panel).add_systems(Update, panel_keys);
    }
}

fn spawn_panel(mut commands: Commands) {
    commands.spawn((
        Node {
            position_type: PositionType::Absolute,
            right: Val::Px(6.0),
            top: Val::Px(6.0),
            padding: UiRect::all(Val::Px(6.0)),
            display: Display::None,
            ..default()
        },
        BackgroundColor(Color::srgba(0.0, 0.0, 0.0, 0.6)),
        Text::new(""),
        TextFont::from_font_size(16.0),
        TextColor(Color::WHITE),
        PanelText,
    ));
}

fn panel_keys(
    keys: Res<ButtonInput<KeyCode>>,
    mut panel: ResMut<SettingsPanel>,
    mut settings: ResMut<RenderSettings>,
    mut node: Query<(&mut Node, &mut Text), With<PanelText>>,
) {
    if keys.just_pressed(KeyCode::F4) {
        panel.open = !panel.open;
    }
    if keys.just_pressed(KeyCode::KeyL) {
        adjust(&mut settings, 0, 1);
    }
    if panel.open {
        if keys.just_pressed(KeyCode::ArrowDown) {
            panel.row = (panel.row + 1) % ROWS.len();
        }
        if keys.just_pressed(KeyCode::ArrowUp) {
            panel.row = (panel.row + ROWS.len() - 1) % ROWS.len();
        }
        for (key, step) in [(KeyCode::ArrowRight, 1), (KeyCode::ArrowLeft, -1)] {
            if keys.just_pressed(key) {
                let row = panel.row;
                adjust(&mut settings, row, step);
            }
        }
    }
    if let Ok((mut node, mut text)) = node.single_mut() {
        node.display = if panel.open { Display::Flex } else { Display::None };
        if panel.open && (panel.is_changed() || settings.is_changed()) {
            text.0 = panel_text(&settings, &panel);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn keys_step_within_the_command_line_ranges() {
        let mut s = RenderSettings::default();
        let row = |name: &str| ROWS.iter().position(|r| *r == name).unwrap();
        for _ in 0..10 {
            adjust(&mut s, row("candidates"), 1);
            adjust(&mut s, row("taps"), 1);
            adjust(&mut s, row("radius"), 1);
        }
        assert_eq!((s.restir.candidates, s.restir.taps, s.restir.radius), (64, 15, 80.0));
        for _ in 0..40 {
            adjust(&mut s, row("candidates"), -1);
            adjust(&mut s, row("taps"), -1);
            adjust(&mut s, row("radius"), -1);
        }
        assert_eq!((s.restir.candidates, s.restir.taps, s.restir.radius), (1, 0, 0.0));
        // Every value the panel reaches is one `--set` accepts.
        for pair in [format!("candidates={}", s.restir.candidates), format!("radius={}", s.restir.radius)] {
            RenderSettings::default().set(&pair).unwrap();
        }
        adjust(&mut s, row("lighting"), 1);
        assert_eq!(s.lighting, Lighting::Nee);
        adjust(&mut s, row("lighting"), 1);
        assert_eq!(s.lighting, Lighting::Restir);
        adjust(&mut s, row("lighting"), 1);
        assert_eq!(s.lighting, Lighting::Sun);
        assert!(panel_text(&s, &SettingsPanel { open: true, row: 1 }).contains("> candidates  1"));
    }
}
