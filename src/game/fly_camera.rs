//! Fly camera: WASD to move, mouse to look (click to capture the cursor, Esc to release), Space / Shift for up and
//! down, Ctrl to move faster.

use crate::world::CameraView;
use bevy::input::mouse::AccumulatedMouseMotion;
use bevy::prelude::*;
use bevy::window::{CursorGrabMode, CursorOptions, PrimaryWindow};

/// A camera steered by the player. Angles in radians.
#[derive(Component, Clone, Copy, Debug)]
pub struct FlyCamera {
    pub yaw: f32,
    pub pitch: f32,
    /// Voxels per second.
    pub speed: f32,
}

impl FlyCamera {
    /// A fly camera looking along the view's direction.
    pub fn looking(view: &CameraView) -> Self {
        let d = view.direction();
        FlyCamera { yaw: (-d.x).atan2(-d.z), pitch: d.y.clamp(-1.0, 1.0).asin(), speed: 12.0 }
    }
}

const MOUSE_SENSITIVITY: f32 = 0.0025;
const PITCH_LIMIT: f32 = 1.54;

pub struct FlyCameraPlugin;

impl Plugin for FlyCameraPlugin {
    fn build(&self, app: &mut App) {
        app.add_systems(Update, (grab_cursor, steer_camera).chain());
    }
}

fn grab_cursor(
    buttons: Res<ButtonInput<MouseButton>>,
    keys: Res<ButtonInput<KeyCode>>,
    mut cursor: Single<&mut CursorOptions, With<PrimaryWindow>>,
) {
    if buttons.just_pressed(MouseButton::Left) {
        cursor.grab_mode = CursorGrabMode::Locked;
        cursor.visible = false;
    }
    if keys.just_pressed(KeyCode::Escape) {
        cursor.grab_mode = CursorGrabMode::None;
        cursor.visible = true;
    }
}

fn steer_camera(
    time: Res<Time>,
    keys: Res<ButtonInput<KeyCode>>,
    motion: Res<AccumulatedMouseMotion>,
    cursor: Single<&CursorOptions, With<PrimaryWindow>>,
    mut camera: Single<(&mut Transform, &mut FlyCamera)>,
) {
    let (transform, fly) = &mut *camera;
    if cursor.grab_mode != CursorGrabMode::None {
        fly.yaw -= motion.delta.x * MOUSE_SENSITIVITY;
        fly.pitch = (fly.pitch - motion.delta.y * MOUSE_SENSITIVITY).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }
    transform.rotation = Quat::from_euler(EulerRot::YXZ, fly.yaw, fly.pitch, 0.0);
    let forward = *transform.forward();
    let right = *transform.right();
    let mut velocity = Vec3::ZERO;
    for (key, dir) in [
        (KeyCode::KeyW, forward),
        (KeyCode::KeyS, -forward),
        (KeyCode::KeyD, right),
        (KeyCode::KeyA, -right),
        (KeyCode::Space, Vec3::Y),
        (KeyCode::ShiftLeft, Vec3::NEG_Y),
    ] {
        if keys.pressed(key) {
            velocity += dir;
        }
    }
    let boost = if keys.pressed(KeyCode::ControlLeft) { 4.0 } else { 1.0 };
    transform.translation += velocity.normalize_or_zero() * fly.speed * boost * time.delta_secs();
}
