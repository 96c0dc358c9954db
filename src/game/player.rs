//! The player: a camera that flies (WASD, mouse, Space / Shift) or walks with gravity and collision with voxels
//! and moving objects (toggle with F). Click captures the mouse, Esc releases it; Ctrl moves faster.

use crate::dynamic::{DynamicObject, PlacedModel};
use crate::world::{CameraView, VoxelWorld};
use bevy::input::mouse::AccumulatedMouseMotion;
use bevy::prelude::*;
use bevy::window::{CursorGrabMode, CursorOptions, PrimaryWindow};

/// The player's state; the camera entity carries it. Angles in radians, speeds in voxels per second.
#[derive(Component, Clone, Copy, Debug)]
pub struct Player {
    pub yaw: f32,
    pub pitch: f32,
    pub walking: bool,
    /// Vertical speed while walking.
    pub fall_speed: f32,
    pub on_ground: bool,
}

/// Half extents of the walking body (a 0.6 x 1.8 x 0.6 box) and the eye height above its feet.
pub const BODY_HALF: Vec3 = Vec3::new(0.3, 0.9, 0.3);
pub const EYE_HEIGHT: f32 = 1.6;
const FLY_SPEED: f32 = 12.0;
/// Ctrl's speed-up, walking or flying.
const BOOST: f32 = 4.0;
/// The fastest the player moves, voxels a second (flying with Ctrl held): what streaming must keep up with.
pub const TOP_FLYING_SPEED: f32 = FLY_SPEED * BOOST;
const WALK_SPEED: f32 = 5.0;
const GRAVITY: f32 = 25.0;
const JUMP_SPEED: f32 = 8.0;
const MOUSE_SENSITIVITY: f32 = 0.0025;
const PITCH_LIMIT: f32 = 1.54;

impl Player {
    /// A player looking along the view's direction.
    pub fn looking(view: &CameraView) -> Self {
        let d = view.direction();
        Player {
            yaw: (-d.x).atan2(-d.z),
            pitch: d.y.clamp(-1.0, 1.0).asin(),
            walking: false,
            fall_speed: 0.0,
            on_ground: false,
        }
    }
}

/// The box the player occupies when the eye is at `eye`: the walking body, or a small box around a flying camera.
pub fn body_box(eye: Vec3, walking: bool) -> (Vec3, Vec3) {
    if walking {
        let feet = eye - Vec3::Y * EYE_HEIGHT;
        (feet - Vec3::new(BODY_HALF.x, 0.0, BODY_HALF.z), feet + Vec3::new(BODY_HALF.x, 2.0 * BODY_HALF.y, BODY_HALF.z))
    } else {
        (eye - Vec3::splat(0.25), eye + Vec3::splat(0.25))
    }
}

/// Whether any solid voxel overlaps the open box `(lo, hi)`.
pub fn box_hits_solid(world: &VoxelWorld, lo: Vec3, hi: Vec3) -> bool {
    let a = (lo + 1e-4).floor().as_ivec3();
    let b = (hi - 1e-4).floor().as_ivec3();
    for z in a.z..=b.z {
        for y in a.y..=b.y {
            for x in a.x..=b.x {
                if world.grid.get(IVec3::new(x, y, z)) != 0 {
                    return true;
                }
            }
        }
    }
    false
}

/// Moves a walking eye by `delta`, one axis at a time in small steps, stopping an axis at the first solid
/// voxel. Returns the new eye position and which axes were blocked.
pub fn move_with_collision(world: &VoxelWorld, eye: Vec3, delta: Vec3) -> (Vec3, BVec3) {
    move_among_objects(world, &[], eye, delta)
}

/// `move_with_collision` that moving objects block too. An object that already overlaps the body (it moved into
/// the player) does not, so the player can step out of it rather than stick.
pub fn move_among_objects(world: &VoxelWorld, objects: &[PlacedModel], eye: Vec3, delta: Vec3) -> (Vec3, BVec3) {
    let (lo, hi) = body_box(eye, true);
    let solid: Vec<PlacedModel> = objects.iter().copied().filter(|o| !o.overlaps_box(lo, hi)).collect();
    let box_hits_solid = |world: &VoxelWorld, lo: Vec3, hi: Vec3| {
        box_hits_solid(world, lo, hi) || solid.iter().any(|o| o.overlaps_box(lo, hi))
    };
    let mut eye = eye;
    let mut blocked = BVec3::FALSE;
    let steps = (delta.abs().max_element() / 0.25).ceil().max(1.0) as usize;
    let step = delta / steps as f32;
    for _ in 0..steps {
        for axis in [1, 0, 2] {
            if blocked.test(axis) || step[axis] == 0.0 {
                continue;
            }
            let mut next = eye;
            next[axis] += step[axis];
            let (lo, hi) = body_box(next, true);
            if box_hits_solid(world, lo, hi) {
                // Close the gap: bisect how far this step can go so the body rests against the voxel.
                let (mut free, mut hit) = (0.0, 1.0);
                for _ in 0..10 {
                    let mid = 0.5 * (free + hit);
                    let mut probe = eye;
                    probe[axis] += step[axis] * mid;
                    let (lo, hi) = body_box(probe, true);
                    if box_hits_solid(world, lo, hi) { hit = mid } else { free = mid }
                }
                eye[axis] += step[axis] * free;
                blocked.set(axis, true);
            } else {
                eye = next;
            }
        }
    }
    (eye, blocked)
}

pub struct PlayerPlugin;

impl Plugin for PlayerPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, (grab_cursor, toggle_walking, steer_player).chain());
    }
}

fn grab_cursor(
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    mut cursor: Single<&mut CursorOptions, With<PrimaryWindow>>,
) {
    if buttons.just_pressed(MouseButton::Left) && cursor.grab_mode == CursorGrabMode::None {
        cursor.grab_mode = CursorGrabMode::Locked;
        cursor.visible = false;
    }
    if keys.just_pressed(KeyCode::Escape) {
        cursor.grab_mode = CursorGrabMode::None;
        cursor.visible = true;
    }
}

fn toggle_walking(keys: Res<ButtonInput<KeyCode>>, mut player: Single<&mut Player>) {
    if keys.just_pressed(KeyCode::KeyF) {
        player.walking = !player.walking;
        player.fall_speed = 0.0;
        info!("{}", if player.walking { "walking" } else { "flying" });
    }
}

fn steer_player(
    time: Res<Time>,
    keys: Res<ButtonInput<KeyCode>>,
    motion: Res<AccumulatedMouseMotion>,
    cursor: Single<&CursorOptions, With<PrimaryWindow>>,
    world: Res<VoxelWorld>,
    mut camera: Single<(&mut Transform, &mut Player)>,
    objects: Query<(&DynamicObject, &Transform), Without<Player>>,
) {
    let (transform, player) = &mut *camera;
    if cursor.grab_mode != CursorGrabMode::None {
        player.yaw -= motion.delta.x * MOUSE_SENSITIVITY;
        player.pitch = (player.pitch - motion.delta.y * MOUSE_SENSITIVITY).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }
    transform.rotation = Quat::from_euler(EulerRot::YXZ, player.yaw, player.pitch, 0.0);
    // Long frames (software rendering) must not tunnel through walls or launch the player.
    let dt = time.delta_secs().min(0.1);
    let boost = if keys.pressed(KeyCode::ControlLeft) { BOOST } else { 1.0 };
    let pressed = |k: KeyCode| keys.pressed(k) as i32 as f32;
    let forward_axis = pressed(KeyCode::KeyW) - pressed(KeyCode::KeyS);
    let right_axis = pressed(KeyCode::KeyD) - pressed(KeyCode::KeyA);
    if player.walking {
        // Walk in the horizontal plane whatever the pitch.
        let forward = Vec3::new(-player.yaw.sin(), 0.0, -player.yaw.cos());
        let right = Vec3::new(-forward.z, 0.0, forward.x);
        let horizontal = (forward * forward_axis + right * right_axis).normalize_or_zero() * WALK_SPEED * boost;
        if player.on_ground && keys.just_pressed(KeyCode::Space) {
            player.fall_speed = JUMP_SPEED;
        }
        player.fall_speed -= GRAVITY * dt;
        let delta = (horizontal + Vec3::Y * player.fall_speed) * dt;
        let placed: Vec<PlacedModel> =
            objects.iter().map(|(o, t)| PlacedModel { model: &o.model, min: t.translation }).collect();
        let (eye, blocked) = move_among_objects(&world, &placed, transform.translation, delta);
        player.on_ground = blocked.y && player.fall_speed < 0.0;
        if blocked.y {
            player.fall_speed = 0.0;
        }
        transform.translation = eye;
    } else {
        let forward = *transform.forward();
        let right = *transform.right();
        let up = pressed(KeyCode::Space) - pressed(KeyCode::ShiftLeft);
        let velocity = (forward * forward_axis + right * right_axis + Vec3::Y * up).normalize_or_zero();
        transform.translation += velocity * FLY_SPEED * boost * dt;
    }
}
