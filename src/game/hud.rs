//! The HUD (Bevy UI). By default the screen stays clean: a crosshair, the hotbar, the selected block's name, the
//! frame time in a corner and a status line for saves and errors. F3 shows the debug panel (frame rate, lights,
//! the render settings that apply as `--set` pairs, movement mode, brush, target), F1 the help. Every panel wraps
//! its text to the window, so nothing is cut off from 960x540 up.

use super::interaction::{Brush, Hotbar, Target, TargetObject};
use super::player::Player;
use crate::lights::LightPool;
use crate::world::VoxelWorld;
use bevy::prelude::*;

/// A message shown for a few seconds at the top of the screen (saves, loads, errors).
#[derive(Resource, Default, Debug)]
pub struct StatusLine {
    pub text: String,
    /// Seconds left to show it.
    pub remaining: f32,
}

impl StatusLine {
    pub fn show(&mut self, text: String) {
        info!("{text}");
        self.text = text;
        self.remaining = 5.0;
    }
}

#[derive(Component)]
struct HotbarSlot(usize);
#[derive(Component)]
struct StatsText;
#[derive(Component)]
struct MaterialText;
#[derive(Component)]
struct StatusText;
#[derive(Component)]
struct HelpPanel;
#[derive(Component)]
struct DebugPanel;
#[derive(Component)]
struct FrameTimeText;

/// Shown on the status line when the game starts, so a new player finds the help.
pub const START_HINT: &str = "F1 help  |  F3 debug";

const HELP: &str = "glowbrick controls\n\n\
    click          capture the mouse (Esc releases it)\n\
    W A S D        move            mouse          look\n\
    Space / Shift  up / down (flying), Space jumps (walking)\n\
    Ctrl           move faster     F              toggle walking / flying\n\
    left click     break the targeted block\n\
    right click    place the selected block on the targeted face\n\
    middle click   pick the targeted block into the hotbar slot\n\
    wheel, 1-9     choose a hotbar slot\n\
    B              box brush: click two corners to fill (right) or clear (left)\n\
    Ctrl+Z, Ctrl+Y undo, redo\n\
    V              drop the --model .vox model in front of you\n\
    F3             debug panel: frame rate, lights, render settings, target\n\
    F6             debug views (lit, albedo, normal, depth, denoiser variance, history)\n\
    L              lighting: full (sun, sky, lamps) / emitters only (ReSTIR) / NEE / sun debug look\n\
    T, Shift+T     time of day: an hour on / back (noon 12, dusk 18, night 0)\n\
    G              indirect light (the GI cache) on / off\n\
    N              denoiser on / off\n\
    O              spawn a drifting lantern in front of you\n\
    F4             render settings panel (arrows choose and change)\n\
    F5, F9         save, load\n\
    F1             this help";

pub struct HudPlugin;

impl Plugin for HudPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<StatusLine>()
            .add_systems(Startup, (spawn_hud, |mut status: ResMut<StatusLine>| status.show(START_HINT.into())))
            .add_systems(Update, (update_hotbar, update_texts, toggle_panels));
    }
}

fn text(value: &str, size: f32) -> (Text, TextFont, TextColor) {
    (Text::new(value), TextFont::from_font_size(size), TextColor(Color::WHITE))
}

fn spawn_hud(mut commands: Commands) {
    // Crosshair: two thin bars at the centre, white with a dark rim so it shows on bright blocks too.
    for (w, h) in [(16.0, 4.0), (4.0, 16.0)] {
        commands.spawn((
            Node {
                position_type: PositionType::Absolute,
                left: Val::Percent(50.0),
                top: Val::Percent(50.0),
                width: Val::Px(w),
                height: Val::Px(h),
                margin: UiRect { left: Val::Px(-w / 2.0), top: Val::Px(-h / 2.0), ..default() },
                border: UiRect::all(Val::Px(1.0)),
                ..default()
            },
            BackgroundColor(Color::srgba(1.0, 1.0, 1.0, 0.9)),
            BorderColor::all(Color::srgba(0.0, 0.0, 0.0, 0.8)),
        ));
    }
    // Debug panel (F3): frame rate, lights, settings, mode; top left, wrapped to half the window.
    commands.spawn((
        Node {
            position_type: PositionType::Absolute,
            left: Val::Px(6.0),
            top: Val::Px(6.0),
            max_width: Val::Percent(55.0),
            padding: UiRect::all(Val::Px(4.0)),
            display: Display::None,
            ..default()
        },
        BackgroundColor(Color::srgba(0.0, 0.0, 0.0, 0.45)),
        DebugPanel,
        children![(text("", 14.0), StatsText)],
    ));
    // Frame time: a small corner at the top right.
    commands.spawn((
        Node { position_type: PositionType::Absolute, right: Val::Px(6.0), top: Val::Px(6.0), ..default() },
        Text::new(""),
        TextFont::from_font_size(13.0),
        TextColor(Color::srgba(1.0, 1.0, 1.0, 0.8)),
        FrameTimeText,
    ));
    // Status: top centre.
    commands.spawn((
        Node {
            position_type: PositionType::Absolute,
            top: Val::Px(8.0),
            width: Val::Percent(100.0),
            justify_content: JustifyContent::Center,
            ..default()
        },
        children![(text("", 18.0), BackgroundColor(Color::srgba(0.0, 0.0, 0.0, 0.45)), StatusText)],
    ));
    // Hotbar and material name: bottom centre.
    commands
        .spawn(Node {
            position_type: PositionType::Absolute,
            bottom: Val::Px(8.0),
            width: Val::Percent(100.0),
            flex_direction: FlexDirection::Column,
            align_items: AlignItems::Center,
            row_gap: Val::Px(4.0),
            ..default()
        })
        .with_children(|bottom| {
            bottom.spawn((text("", 16.0), BackgroundColor(Color::srgba(0.0, 0.0, 0.0, 0.45)), MaterialText));
            bottom.spawn(Node { column_gap: Val::Px(4.0), ..default() }).with_children(|row| {
                for i in 0..9 {
                    row.spawn((
                        Node {
                            width: Val::Px(40.0),
                            height: Val::Px(40.0),
                            border: UiRect::all(Val::Px(3.0)),
                            ..default()
                        },
                        BackgroundColor(Color::BLACK),
                        BorderColor::all(Color::srgb(0.2, 0.2, 0.2)),
                        HotbarSlot(i),
                    ));
                }
            });
        });
    // Help panel, hidden until F1: centred, wrapped to the window.
    commands.spawn((
        Node {
            position_type: PositionType::Absolute,
            width: Val::Percent(100.0),
            height: Val::Percent(100.0),
            justify_content: JustifyContent::Center,
            align_items: AlignItems::Center,
            display: Display::None,
            ..default()
        },
        HelpPanel,
        children![(
            Node { max_width: Val::Percent(90.0), padding: UiRect::all(Val::Px(12.0)), ..default() },
            BackgroundColor(Color::srgba(0.0, 0.0, 0.0, 0.8)),
            children![text(HELP, 14.0)],
        )],
    ));
}

fn update_hotbar(
    hotbar: Res<Hotbar>,
    world: Res<VoxelWorld>,
    mut slots: Query<(&HotbarSlot, &mut BackgroundColor, &mut BorderColor)>,
) {
    if !hotbar.is_changed() && !world.is_changed() {
        return;
    }
    for (slot, mut background, mut border) in &mut slots {
        let material = world.palette.get(hotbar.slots[slot.0]);
        let [r, g, b] = match material {
            Some(m) if m.is_emissive() => m.emission,
            Some(m) => m.albedo,
            None => [0.0; 3],
        };
        background.0 = Color::linear_rgb(r, g, b);
        let selected = slot.0 == hotbar.selected;
        *border = BorderColor::all(if selected { Color::WHITE } else { Color::srgb(0.2, 0.2, 0.2) });
    }
}

#[allow(clippy::too_many_arguments, clippy::type_complexity)]
fn update_texts(
    // The real clock: the virtual one clamps each frame's delta (Bevy's `Time<Virtual>::max_delta`), so on a slow
    // adapter the frame time read that clamp while frames took seconds.
    time: Res<Time<Real>>,
    mut smoothed_dt: Local<f32>,
    hotbar: Res<Hotbar>,
    brush: Res<Brush>,
    target: Res<Target>,
    target_object: Res<TargetObject>,
    objects: Query<&crate::dynamic::DynamicObject>,
    world: Res<VoxelWorld>,
    pool: Res<LightPool>,
    settings: Res<crate::settings::RenderSettings>,
    scale: Option<Res<super::dynamic_resolution::DynamicResolution>>,
    player: Query<&Player>,
    mut status: ResMut<StatusLine>,
    mut texts: ParamSet<(
        Query<&mut Text, With<StatsText>>,
        Query<&mut Text, With<MaterialText>>,
        Query<&mut Text, With<StatusText>>,
        Query<&mut Text, With<FrameTimeText>>,
    )>,
) {
    let dt = time.delta_secs();
    *smoothed_dt = if *smoothed_dt == 0.0 { dt } else { *smoothed_dt * 0.9 + dt * 0.1 };
    let mode = if player.single().is_ok_and(|p| p.walking) { "walking" } else { "flying" };
    let brush = match *brush {
        Brush::Single => "single".to_string(),
        Brush::Box { first_corner: None } => "box (click first corner)".to_string(),
        Brush::Box { first_corner: Some(c) } => format!("box from {} {} {} (click second corner)", c.x, c.y, c.z),
    };
    let target = match (target.0, target_object.0.and_then(|(e, d)| Some((objects.get(e).ok()?, d)))) {
        (_, Some((object, distance))) => format!("a moving {} at {distance:.1}", object.model.name),
        (Some(h), None) => format!("{} {} {}", h.voxel.x, h.voxel.y, h.voxel.z),
        (None, None) => "-".to_string(),
    };
    let (voxel_lights, brick_lights) = pool.counts();
    if let Ok(mut t) = texts.p0().single_mut() {
        t.0 = format!(
            "{:.0} fps  {:.1} ms\n{}\nlights {} (voxel {voxel_lights}, brick {brick_lights})\n{}\n{mode} | brush {brush}\ntarget {target}",
            1.0 / smoothed_dt.max(1e-6),
            *smoothed_dt * 1000.0,
            scale_line(&settings, scale.as_deref()),
            pool.len(),
            settings.summary(),
        );
    }
    if let Ok(mut t) = texts.p1().single_mut() {
        t.0 = match world.palette.get(hotbar.material()) {
            Some(m) if m.is_emissive() => {
                let [r, g, b] = m.emission;
                format!("{}  (emits {r:.2} {g:.2} {b:.2} x {})", m.name, m.strength)
            }
            Some(m) => m.name.clone(),
            None => "(empty slot)".to_string(),
        };
    }
    if let Ok(mut t) = texts.p3().single_mut() {
        t.0 = format!("{:.1} ms", *smoothed_dt * 1000.0);
    }
    status.remaining -= dt;
    if let Ok(mut t) = texts.p2().single_mut() {
        let shown = if status.remaining > 0.0 { status.text.as_str() } else { "" };
        if t.0 != shown {
            t.0 = shown.to_string();
        }
    }
}

/// The render scale in force, and with `render_scale=auto` the GPU time it was chosen from and the target.
pub fn scale_line(
    settings: &crate::settings::RenderSettings,
    dynamic: Option<&super::dynamic_resolution::DynamicResolution>,
) -> String {
    use crate::settings::RenderScale;
    match (settings.render_scale, dynamic) {
        (RenderScale::Auto, Some(d)) if d.gpu_ms > 0.0 => {
            format!("render scale {:.2} (auto: GPU {:.1} ms, target {} ms)", d.scale, d.gpu_ms, settings.frame_target)
        }
        (RenderScale::Auto, Some(d)) => format!("render scale {:.2} (auto: measuring)", d.scale),
        (RenderScale::Auto, None) => "render scale 1 (auto)".to_string(),
        (RenderScale::Fixed(scale), _) => format!("render scale {scale}"),
    }
}

/// F1 shows or hides the help, F3 the debug panel.
fn toggle_panels(
    keys: Res<ButtonInput<KeyCode>>,
    mut help: Query<&mut Node, (With<HelpPanel>, Without<DebugPanel>)>,
    mut debug: Query<&mut Node, (With<DebugPanel>, Without<HelpPanel>)>,
) {
    let flip = |node: &mut Node| {
        node.display = if node.display == Display::None { Display::Flex } else { Display::None };
    };
    if keys.just_pressed(KeyCode::F1) {
        help.iter_mut().for_each(|mut n| flip(&mut n));
    }
    if keys.just_pressed(KeyCode::F3) {
        debug.iter_mut().for_each(|mut n| flip(&mut n));
    }
}
