//! Building: the targeted voxel (a CPU ray through the crosshair), the hotbar, brushes, and turning the player's
//! clicks into edits on the one edit path (`EditRequest`).
//!
//! Left click breaks, right click places on the targeted face, middle click picks the targeted material into the
//! current hotbar slot. With the box brush (B), the first click marks a corner and the second fills (right) or
//! clears (left) the box between the two corners.

use super::player::{Player, body_box};
use crate::dynamic::{DynamicObject, PlacedModel};
use crate::render::Highlight;
use crate::world::events::{ApplyEdits, EditRequest};
use crate::world::{Edit, Hit, Palette, Ray, Voxel, VoxelWorld, trace};
use bevy::input::mouse::AccumulatedMouseScroll;
use bevy::prelude::*;
use bevy::window::{CursorGrabMode, CursorOptions, PrimaryWindow};

/// How far the player reaches, in voxels.
pub const REACH: f32 = 64.0;

/// The voxel under the crosshair, if any within reach.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct Target(pub Option<Hit>);

/// Something the player does to the targeted voxel.
#[derive(Message, Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlayerAction {
    Break,
    Place,
    Pick,
}

/// The active brush.
#[derive(Resource, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Brush {
    #[default]
    Single,
    /// Box fill; holds the first corner once clicked.
    Box { first_corner: Option<IVec3> },
}

/// Nine material slots; `selected` is what right click places.
#[derive(Resource, Clone, Debug, PartialEq, Eq)]
pub struct Hotbar {
    pub slots: [Voxel; 9],
    pub selected: usize,
}

impl Hotbar {
    /// A hotbar drawn from the palette: building blocks first, then emitters (so several light colours and
    /// strengths are always at hand), then whatever else the palette holds.
    pub fn from_palette(palette: &Palette) -> Self {
        let ids = 1..palette.id_count() as Voxel;
        let solid: Vec<Voxel> = ids.clone().filter(|&id| !palette.is_emissive(id)).collect();
        let emissive: Vec<Voxel> = ids.filter(|&id| palette.is_emissive(id)).collect();
        // Up to four lights, more when there are fewer than five building blocks.
        let lights = emissive.len().min(4.max(9usize.saturating_sub(solid.len())));
        let mut chosen: Vec<Voxel> = solid.iter().copied().take(9 - lights).collect();
        chosen.extend(emissive.iter().copied().take(lights));
        for &id in solid.iter().chain(&emissive) {
            if chosen.len() < 9 && !chosen.contains(&id) {
                chosen.push(id);
            }
        }
        let mut slots = [0; 9];
        for (i, id) in chosen.into_iter().enumerate() {
            slots[i] = id;
        }
        Hotbar { slots, selected: 0 }
    }

    pub fn material(&self) -> Voxel {
        self.slots[self.selected]
    }
}

/// Which world the hotbar was drawn for.
#[derive(Resource, Default)]
struct HotbarWorld(Option<u64>);

pub struct InteractionPlugin;

impl Plugin for InteractionPlugin {
    fn build(&self, app: &mut App) {
        app.init_resource::<Target>()
            .init_resource::<TargetObject>()
            .init_resource::<Brush>()
            .init_resource::<Highlight>()
            .init_resource::<HotbarWorld>()
            .insert_resource(Hotbar { slots: [0; 9], selected: 0 })
            .add_message::<PlayerAction>()
            .add_systems(
                Update,
                (refresh_hotbar, update_target, perform_actions, update_highlight).chain().before(ApplyEdits),
            );
    }
}

/// Input mapping: mouse buttons to actions (only while the cursor is captured), wheel and 1-9 to the hotbar,
/// B to switch brushes. Needs a window.
pub struct InteractionInputPlugin;

impl Plugin for InteractionInputPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, (choose_hotbar_slot, switch_brush, clicks_to_actions).before(perform_actions));
    }
}

fn refresh_hotbar(world: Res<VoxelWorld>, mut hotbar: ResMut<Hotbar>, mut drawn_for: ResMut<HotbarWorld>) {
    if drawn_for.0 != Some(world.instance) {
        *hotbar = Hotbar::from_palette(&world.palette);
        drawn_for.0 = Some(world.instance);
    }
}

/// The moving object under the crosshair when it is nearer than any voxel: its entity and distance. Clicks do
/// not reach through it (Target is then empty), and the HUD names it.
#[derive(Resource, Clone, Copy, Debug, Default)]
pub struct TargetObject(pub Option<(Entity, f32)>);

/// What a crosshair ray from `origin` along `dir` meets first within reach: a voxel, or object `i` of `objects`
/// at a distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Aim {
    Voxel(Hit),
    Object(usize, f32),
    Nothing,
}

pub fn aim(world: &VoxelWorld, objects: &[PlacedModel], origin: Vec3, dir: Vec3) -> Aim {
    let ray = Ray::new(origin, dir);
    let voxel = trace(&world.grid, &ray, REACH);
    let reach = voxel.map_or(REACH, |h| h.distance);
    let nearest = objects
        .iter()
        .enumerate()
        .filter_map(|(i, o)| o.trace(ray.origin, ray.dir, reach).map(|t| (i, t)))
        .min_by(|a, b| a.1.total_cmp(&b.1));
    match (nearest, voxel) {
        (Some((i, t)), _) => Aim::Object(i, t),
        (None, Some(hit)) => Aim::Voxel(hit),
        (None, None) => Aim::Nothing,
    }
}

/// Traces the crosshair ray (the camera's forward axis) on the CPU, against the voxels and the moving objects.
pub fn update_target(
    world: Res<VoxelWorld>,
    camera: Query<&Transform, With<Player>>,
    objects: Query<(Entity, &DynamicObject, &Transform), Without<Player>>,
    mut target: ResMut<Target>,
    mut target_object: ResMut<TargetObject>,
) {
    let Ok(t) = camera.single() else {
        (target.0, target_object.0) = (None, None);
        return;
    };
    let (entities, placed): (Vec<Entity>, Vec<PlacedModel>) =
        objects.iter().map(|(e, o, t)| (e, PlacedModel { model: &o.model, min: t.translation })).unzip();
    (target.0, target_object.0) = match aim(&world, &placed, t.translation, *t.forward()) {
        Aim::Voxel(hit) => (Some(hit), None),
        Aim::Object(i, distance) => (None, Some((entities[i], distance))),
        Aim::Nothing => (None, None),
    };
}

/// The voxel a place action fills: the air cell in front of the targeted face.
pub fn place_position(hit: &Hit) -> IVec3 {
    hit.voxel + hit.face.normal()
}

/// Turns actions into edits with the current brush and hotbar.
pub fn perform_actions(
    mut actions: MessageReader<PlayerAction>,
    target: Res<Target>,
    world: Res<VoxelWorld>,
    player: Query<(&Transform, &Player)>,
    mut brush: ResMut<Brush>,
    mut hotbar: ResMut<Hotbar>,
    mut edits: MessageWriter<EditRequest>,
) {
    for &action in actions.read() {
        let Some(hit) = target.0 else { continue };
        let material = match action {
            PlayerAction::Pick => {
                let slot = hotbar.selected;
                hotbar.slots[slot] = hit.material;
                continue;
            }
            PlayerAction::Break => 0,
            PlayerAction::Place => hotbar.material(),
        };
        let at = if action == PlayerAction::Place { place_position(&hit) } else { hit.voxel };
        if !world.grid.contains(at) {
            continue;
        }
        match *brush {
            Brush::Single => {
                if action == PlayerAction::Place
                    && let Ok((transform, p)) = player.single()
                {
                    let (lo, hi) = body_box(transform.translation, p.walking);
                    let cell = at.as_vec3();
                    if lo.cmplt(cell + 1.0).all() && hi.cmpgt(cell).all() {
                        continue; // never place a voxel inside the player
                    }
                }
                let edit = if material == 0 { Edit::Break { at } } else { Edit::Place { at, material } };
                edits.write(EditRequest::player(edit));
            }
            Brush::Box { first_corner: None } => *brush = Brush::Box { first_corner: Some(at) },
            Brush::Box { first_corner: Some(first) } => {
                edits.write(EditRequest::player(Edit::FillBox { min: first, max: at, material }));
                *brush = Brush::Box { first_corner: None };
            }
        }
    }
}

fn update_highlight(target: Res<Target>, brush: Res<Brush>, mut highlight: ResMut<Highlight>) {
    let next = Highlight {
        target: target.0.map(|h| (h.voxel, h.face.0)),
        selection: match (*brush, target.0) {
            (Brush::Box { first_corner: Some(a) }, Some(hit)) => Some((a.min(hit.voxel), a.max(hit.voxel))),
            (Brush::Box { first_corner: Some(a) }, None) => Some((a, a)),
            _ => None,
        },
    };
    if *highlight != next {
        *highlight = next;
    }
}

fn choose_hotbar_slot(
    keys: Res<ButtonInput<KeyCode>>,
    scroll: Res<AccumulatedMouseScroll>,
    mut hotbar: ResMut<Hotbar>,
) {
    const DIGITS: [KeyCode; 9] = [
        KeyCode::Digit1,
        KeyCode::Digit2,
        KeyCode::Digit3,
        KeyCode::Digit4,
        KeyCode::Digit5,
        KeyCode::Digit6,
        KeyCode::Digit7,
        KeyCode::Digit8,
        KeyCode::Digit9,
    ];
    if let Some(i) = DIGITS.iter().position(|&k| keys.just_pressed(k)) {
        hotbar.selected = i;
    }
    if scroll.delta.y != 0.0 {
        let step = if scroll.delta.y > 0.0 { 8 } else { 1 };
        hotbar.selected = (hotbar.selected + step) % 9;
    }
}

fn switch_brush(keys: Res<ButtonInput<KeyCode>>, mut brush: ResMut<Brush>) {
    if keys.just_pressed(KeyCode::KeyB) {
        *brush = match *brush {
            Brush::Single => Brush::Box { first_corner: None },
            Brush::Box { .. } => Brush::Single,
        };
    }
}

fn clicks_to_actions(
    buttons: Res<ButtonInput<MouseButton>>,
    cursor: Single<&CursorOptions, With<PrimaryWindow>>,
    mut captured_last_frame: Local<bool>,
    mut actions: MessageWriter<PlayerAction>,
) {
    // The click that captures the cursor is not an edit: act only if it was already captured last frame.
    let captured = cursor.grab_mode != CursorGrabMode::None;
    let act = captured && *captured_last_frame;
    *captured_last_frame = captured;
    if !act {
        return;
    }
    for (button, action) in [
        (MouseButton::Left, PlayerAction::Break),
        (MouseButton::Right, PlayerAction::Place),
        (MouseButton::Middle, PlayerAction::Pick),
    ] {
        if buttons.just_pressed(button) {
            actions.write(action);
        }
    }
}
