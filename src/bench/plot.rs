//! The bench plot: error (MAE) against frame time, one panel per scene, one colour per setting. Drawn directly
//! into an image with the 5 x 7 font, so the report needs no plotting or font dependency.

use super::{BenchRow, SETTINGS};
use crate::world::font::glyph;
use image::{Rgb, RgbImage};
use std::path::Path;

const PANEL_W: u32 = 420;
const PANEL_H: u32 = 300;
const MARGIN: i32 = 56;
const COLOURS: [[u8; 3]; 12] = [
    [230, 90, 40],
    [40, 120, 230],
    [40, 170, 80],
    [180, 60, 200],
    [200, 170, 30],
    [90, 90, 90],
    [0, 180, 180],
    [240, 120, 170],
    [120, 70, 20],
    [20, 40, 120],
    [150, 200, 60],
    [200, 30, 60],
];

fn put(img: &mut RgbImage, x: i32, y: i32, c: [u8; 3]) {
    if x >= 0 && y >= 0 && (x as u32) < img.width() && (y as u32) < img.height() {
        img.put_pixel(x as u32, y as u32, Rgb(c));
    }
}

fn rect(img: &mut RgbImage, x0: i32, y0: i32, x1: i32, y1: i32, c: [u8; 3]) {
    for y in y0..=y1 {
        for x in x0..=x1 {
            put(img, x, y, c);
        }
    }
}

/// Writes `text` with its top left at (x, y), `scale` pixels per font pixel.
fn text(img: &mut RgbImage, x: i32, y: i32, scale: i32, s: &str, c: [u8; 3]) {
    for (i, ch) in s.chars().enumerate() {
        let rows = glyph(ch).unwrap_or([0b11111; 7]);
        for (r, bits) in rows.iter().enumerate() {
            for col in 0..5 {
                if bits & (0b10000 >> col) != 0 {
                    let (px, py) = (x + (i as i32 * 6 + col) * scale, y + r as i32 * scale);
                    rect(img, px, py, px + scale - 1, py + scale - 1, c);
                }
            }
        }
    }
}

/// Draws one panel per scene and saves the PNG.
pub fn write_plot(rows: &[BenchRow], path: &Path) -> Result<(), String> {
    let mut scenes: Vec<&str> = Vec::new();
    for r in rows {
        if !scenes.contains(&r.scene.as_str()) {
            scenes.push(&r.scene);
        }
    }
    let columns = scenes.len().clamp(1, 2) as u32;
    let panel_rows = (scenes.len() as u32).div_ceil(columns).max(1);
    let legend_h = 20 + 16 * SETTINGS.len() as u32;
    let mut img = RgbImage::from_pixel(PANEL_W * columns, PANEL_H * panel_rows + legend_h, Rgb([255, 255, 255]));
    for (i, scene) in scenes.iter().enumerate() {
        let ox = (i as u32 % columns * PANEL_W) as i32;
        let oy = (i as u32 / columns * PANEL_H) as i32;
        let points: Vec<&BenchRow> = rows.iter().filter(|r| r.scene == *scene).collect();
        let max_x = points.iter().map(|r| r.frame_ms).fold(0.0, f64::max).max(1e-9) * 1.15;
        let max_y = points.iter().map(|r| r.metrics.mae).fold(0.0, f64::max).max(1e-9) * 1.15;
        let (x0, y0) = (ox + MARGIN, oy + PANEL_H as i32 - 40);
        let (x1, y1) = (ox + PANEL_W as i32 - 16, oy + 30);
        text(&mut img, ox + MARGIN, oy + 8, 2, scene, [0, 0, 0]);
        rect(&mut img, x0, y1, x0, y0, [0, 0, 0]);
        rect(&mut img, x0, y0, x1, y0, [0, 0, 0]);
        text(&mut img, x0 - 4, y0 + 8, 1, "0", [0, 0, 0]);
        text(&mut img, x1 - 60, y0 + 8, 1, &format!("{max_x:.2} MS"), [0, 0, 0]);
        text(&mut img, (x0 + x1) / 2 - 30, y0 + 22, 1, "FRAME TIME", [0, 0, 0]);
        text(&mut img, ox + 4, y1, 1, &format!("{max_y:.4}"), [0, 0, 0]);
        text(&mut img, ox + 4, y1 + 12, 1, "MAE", [0, 0, 0]);
        for r in points {
            let colour =
                SETTINGS.iter().position(|s| s.name == r.setting).map_or([0, 0, 0], |k| COLOURS[k % COLOURS.len()]);
            let px = x0 + ((r.frame_ms / max_x) * (x1 - x0) as f64) as i32;
            let py = y0 - ((r.metrics.mae / max_y) * (y0 - y1) as f64) as i32;
            rect(&mut img, px - 4, py - 4, px + 4, py + 4, colour);
        }
    }
    let ly = (PANEL_H * panel_rows) as i32 + 8;
    for (k, s) in SETTINGS.iter().enumerate() {
        let y = ly + 16 * k as i32;
        rect(&mut img, 16, y, 26, y + 10, COLOURS[k % COLOURS.len()]);
        text(&mut img, 34, y + 2, 1, s.name, [0, 0, 0]);
    }
    img.save(path).map_err(|e| format!("{}: cannot write plot: {e}", path.display()))
}
