//! The bench's figures: the convergence curves (relMSE against cumulative time, log-log, one panel per scene,
//! one line per method, the one-frame settings as crosses) as an SVG drawn with plotters, and the image strips.

use super::convergence::CurvePoint;
use super::sweep::BenchRow;
use crate::image_io::{LinearImage, display_rgb8, plain_rgb8};
use image::RgbImage;
use plotters::prelude::*;
use std::path::Path;

const PANEL: (u32, u32) = (560, 400);

/// Writes `plot.svg`: a panel per scene (two per row).
pub fn write_plot(rows: &[BenchRow], curves: &[CurvePoint], path: &Path) -> Result<(), String> {
    let mut scenes: Vec<&str> = Vec::new();
    for scene in rows.iter().map(|r| r.scene.as_str()).chain(curves.iter().map(|p| p.scene.as_str())) {
        if !scenes.contains(&scene) {
            scenes.push(scene);
        }
    }
    let columns = scenes.len().clamp(1, 2);
    let panel_rows = scenes.len().div_ceil(columns).max(1);
    let size = (PANEL.0 * columns as u32, PANEL.1 * panel_rows as u32);
    let root = SVGBackend::new(path, size).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let panels = root.split_evenly((panel_rows, columns));
    for (panel, scene) in panels.iter().zip(&scenes) {
        draw_panel(panel, scene, rows, curves).map_err(|e| format!("{}: cannot draw the plot: {e}", path.display()))?;
    }
    root.present().map_err(|e| format!("{}: cannot write the plot: {e}", path.display()))
}

fn draw_panel<DB: DrawingBackend>(
    panel: &DrawingArea<DB, plotters::coord::Shift>,
    scene: &str,
    rows: &[BenchRow],
    curves: &[CurvePoint],
) -> Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let singles: Vec<&BenchRow> =
        rows.iter().filter(|r| r.scene == scene && r.frames == 1 && r.metrics.relmse > 0.0).collect();
    let points: Vec<&CurvePoint> = curves.iter().filter(|p| p.scene == scene && p.metrics.relmse > 0.0).collect();
    let xs = singles.iter().map(|r| r.frame_ms).chain(points.iter().map(|p| p.ms));
    let ys = singles.iter().map(|r| r.metrics.relmse).chain(points.iter().map(|p| p.metrics.relmse));
    let (x_lo, x_hi) = xs.fold((f64::MAX, f64::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
    let (y_lo, y_hi) = ys.fold((f64::MAX, f64::MIN), |(lo, hi), y| (lo.min(y), hi.max(y)));
    if x_lo > x_hi || y_lo > y_hi {
        return Ok(());
    }
    let mut chart = ChartBuilder::on(panel)
        .caption(scene, ("sans-serif", 20))
        .margin(12)
        .x_label_area_size(40)
        .y_label_area_size(70)
        .build_cartesian_2d((x_lo * 0.7..x_hi * 1.4).log_scale(), (y_lo * 0.7..y_hi * 1.4).log_scale())?;
    chart
        .configure_mesh()
        .x_desc("cumulative frame time (ms)")
        .y_desc("relMSE")
        .y_label_formatter(&|y| format!("{y:.0e}"))
        .draw()?;
    let mut methods: Vec<&str> = Vec::new();
    for p in &points {
        if !methods.contains(&p.method) {
            methods.push(p.method);
        }
    }
    for (i, method) in methods.into_iter().enumerate() {
        let colour = Palette99::pick(i).to_rgba();
        let line: Vec<(f64, f64)> =
            points.iter().filter(|p| p.method == method).map(|p| (p.ms, p.metrics.relmse)).collect();
        if line.is_empty() {
            continue;
        }
        chart
            .draw_series(LineSeries::new(line.clone(), colour.stroke_width(2)))?
            .label(method)
            .legend(move |(x, y)| PathElement::new(vec![(x, y), (x + 20, y)], colour.stroke_width(2)));
        chart.draw_series(line.into_iter().map(|p| Circle::new(p, 3, colour.filled())))?;
    }
    if !singles.is_empty() {
        chart
            .draw_series(singles.iter().map(|r| Cross::new((r.frame_ms, r.metrics.relmse), 4, BLACK.stroke_width(1))))?
            .label("one frame, each setting")
            .legend(|(x, y)| Cross::new((x + 10, y), 4, BLACK.stroke_width(1)));
    }
    // Lower left: the curves fall towards the lower right.
    chart
        .configure_series_labels()
        .position(SeriesLabelPosition::LowerLeft)
        .border_style(BLACK)
        .background_style(WHITE.mix(0.9))
        .draw()?;
    Ok(())
}

/// Writes images side by side as one PNG: linear images tonemapped as `write_image` does, except the last
/// (a false-colour map, already display values).
pub fn write_strip(images: &[LinearImage], path: &Path) -> Result<(), String> {
    let (w, h) = (images[0].width, images[0].height);
    let gap = 4;
    let mut strip = RgbImage::from_pixel((w + gap) * images.len() as u32 - gap, h, image::Rgb([255, 255, 255]));
    for (i, picture) in images.iter().enumerate() {
        // The FLIP map holds linear values of its sRGB colours: encode them back as they are.
        let bytes = if i + 1 == images.len() { plain_rgb8(picture) } else { display_rgb8(picture) };
        for (k, rgb) in bytes.chunks_exact(3).enumerate() {
            let (x, y) = (k as u32 % w, k as u32 / w);
            strip.put_pixel(i as u32 * (w + gap) + x, y, image::Rgb([rgb[0], rgb[1], rgb[2]]));
        }
    }
    strip.save(path).map_err(|e| format!("{}: cannot write image strip: {e}", path.display()))
}
