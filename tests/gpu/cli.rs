//! The command line's GPU half: `render` headless (the rest of the command-line contract is in the CPU tests).

use std::process::{Command, Output};

fn glowbrick(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_glowbrick")).args(args).output().expect("run glowbrick")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

/// `render` writes linear float EXR (values above 1 survive) and an 8-bit PNG, headless.
pub fn render_writes_exr_and_png_headless() {
    let dir = std::env::temp_dir().join(format!("glowbrick-render-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exr = dir.join("room.exr");
    let out = glowbrick(&[
        "render",
        "--scene",
        "test-room",
        "--view",
        "inside",
        "--width",
        "96",
        "--height",
        "64",
        "--out",
        exr.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let image = image::open(&exr).unwrap().into_rgba32f();
    assert_eq!(image.dimensions(), (96, 64));
    let brightest = image.pixels().map(|p| p.0[0]).fold(0.0f32, f32::max);
    assert!(brightest > 1.0, "the lamp (radiance 10) should exceed 1 in linear EXR, got {brightest}");
    assert!(image.pixels().all(|p| p.0.iter().all(|c| c.is_finite())));
    let png = dir.join("room.png");
    let out = glowbrick(&[
        "render",
        "--scene",
        "test-room",
        "--width",
        "96",
        "--height",
        "64",
        "--out",
        png.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert_eq!(image::open(&png).unwrap().into_rgb8().dimensions(), (96, 64));
}
