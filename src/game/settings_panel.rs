//! The in-game render settings panel (F4): Up/Down choose a row, Left/Right change it. Each row is a setting of
//! `crate::settings::SETTINGS`, which says how it steps: choices cycle, numbers step within the range `--set`
//! accepts. L cycles the lighting mode at any time. What changes is kept for the next game
//! (`super::settings_file`).

use crate::settings::{RenderSettings, setting};
use bevy::prelude::*;

/// The settings the panel shows, top to bottom (keys of `crate::settings::SETTINGS`).
pub const ROWS: [&str; 14] = [
    "lighting",
    "candidates",
    "taps",
    "radius",
    "temporal",
    "spatial",
    "sample",
    "reuse",
    "pick",
    "accumulate",
    "time",
    "denoise",
    "render_scale",
    "frame_target",
];

#[derive(Resource, Default, Debug)]
pub struct SettingsPanel {
    pub open: bool,
    pub row: usize,
}

#[derive(Component)]
struct PanelText;

/// Changes row `row` of `settings` by `step` (+1 / -1), as its setting steps.
pub fn adjust(settings: &mut RenderSettings, row: usize, step: i32) {
    if let Some(setting) = ROWS.get(row).and_then(|key| setting(key)) {
        setting.step(settings, step);
    }
}

/// The panel's text, the chosen row marked.
pub fn panel_text(settings: &RenderSettings, panel: &SettingsPanel) -> String {
    let mut text = String::from("render settings (F4 closes)\nUp/Down choose, Left/Right change\n\n");
    for (i, row) in ROWS.iter().enumerate() {
        let mark = if i == panel.row { ">" } else { " " };
        let value = setting(row).map_or(String::new(), |s| s.show(settings));
        text += &format!("{mark} {row:<11} {value}\n");
    }
    text
}

pub struct SettingsPanelPlugin;

impl Plugin for SettingsPanelPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<SettingsPanel>()
            .add_systems(Startup, spawn_panel)
            .add_systems(Update, (panel_keys, super::settings_file::keep_settings).chain());
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
    use crate::settings::Lighting;

    #[test]
    fn every_row_is_a_setting() {
        for row in ROWS {
            assert!(setting(row).is_some(), "{row}");
        }
    }

    #[test]
    fn keys_step_within_the_command_line_ranges() {
        let mut s = RenderSettings::default();
        let row = |name: &str| ROWS.iter().position(|r| *r == name).unwrap();
        for _ in 0..10 {
            adjust(&mut s, row("candidates"), 1);
            adjust(&mut s, row("taps"), 1);
            adjust(&mut s, row("radius"), 1);
        }
        assert_eq!((s.restir.candidates, s.restir.taps, s.restir.radius), (64, 11, 80.0));
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
        assert_eq!(s.lighting, Lighting::Emitters);
        adjust(&mut s, row("lighting"), 1);
        assert_eq!(s.lighting, Lighting::Nee);
        adjust(&mut s, row("lighting"), 1);
        assert_eq!(s.lighting, Lighting::Sun);
        adjust(&mut s, row("lighting"), 1);
        assert_eq!(s.lighting, Lighting::Full);
        let text = panel_text(&s, &SettingsPanel { open: true, row: 1 });
        assert!(text.contains("> candidates  1") && text.contains("  radius      0 px"), "{text}");
    }
}
