//! The window opens at 1280x720 or, on a smaller screen, at the largest 16:9 size that fits 90% of it
//! (centred), so the hotbar is never cut off; the player may resize it freely afterwards. Monitors are known only
//! once the window system has started, so this runs each frame until it has seen the primary monitor.

use bevy::prelude::*;
use bevy::window::{Monitor, MonitorSelection, PrimaryMonitor, PrimaryWindow, WindowPosition};

/// The size the game asks for on a large enough screen.
pub const PREFERRED_SIZE: Vec2 = Vec2::new(1280.0, 720.0);

/// The logical size that fits a `screen` of logical size: the preferred size, or a 16:9 rectangle that fills
/// 90% of the screen's limiting side.
pub fn size_for_screen(screen: Vec2) -> Vec2 {
    let room = screen * 0.9;
    let scale = (room.x / PREFERRED_SIZE.x).min(room.y / PREFERRED_SIZE.y).min(1.0);
    (PREFERRED_SIZE * scale).floor().max(Vec2::new(320.0, 180.0))
}

pub fn fit_window_to_screen(
    mut done: Local<bool>,
    monitors: Query<&Monitor, With<PrimaryMonitor>>,
    mut windows: Query<&mut Window, With<PrimaryWindow>>,
) {
    if *done {
        return;
    }
    let (Ok(monitor), Ok(mut window)) = (monitors.single(), windows.single_mut()) else { return };
    *done = true;
    let screen = monitor.physical_size().as_vec2() / monitor.scale_factor.max(0.1) as f32;
    let size = size_for_screen(screen);
    if size.cmplt(Vec2::new(window.width(), window.height())).any() {
        window.resolution.set(size.x, size.y);
        window.position = WindowPosition::Centered(MonitorSelection::Primary);
        info!("the screen is {}x{}: the window opens at {}x{}", screen.x, screen.y, size.x, size.y);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_window_fits_small_screens_and_keeps_its_size_on_large_ones() {
        assert_eq!(size_for_screen(Vec2::new(1920.0, 1080.0)), PREFERRED_SIZE);
        assert_eq!(size_for_screen(Vec2::new(1024.0, 600.0)), Vec2::new(921.0, 518.0));
        assert_eq!(size_for_screen(Vec2::new(800.0, 1280.0)), Vec2::new(720.0, 405.0));
    }
}
