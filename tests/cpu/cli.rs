//! The command-line contract: exit codes, one-line errors, and the summary `check-world` prints (`render` itself
//! needs a GPU: tests/gpu/cli.rs).

use std::path::PathBuf;
use std::process::{Command, Output};

fn glowbrick(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_glowbrick")).args(args).output().expect("run glowbrick")
}

fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn repo(path: &str) -> String {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join(path).display().to_string()
}

#[test]
fn check_world_summarises_a_recipe() {
    let out = glowbrick(&["check-world", &repo("assets/scenes/cornell.ron")]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.contains("size: 144x144x144"), "{stdout}");
    assert!(stdout.contains("lights: 256 voxel=0 brick=256"), "{stdout}");
    assert!(stdout.contains("emitters: 131072"), "{stdout}");
    assert!(stdout.contains("views: front, inside"), "{stdout}");
}

#[test]
fn check_world_reports_a_broken_file_in_one_line() {
    let dir = std::env::temp_dir().join(format!("glowbrick-cli-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("broken.ron");
    std::fs::write(&path, "(format: \"glowbrick-world\", version: 1, size: (8, 8, 8), palette: [], bricks: [(at: (0, 0, 0), fill: Uniform(3))])").unwrap();
    let out = glowbrick(&["check-world", path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("bricks[0] at (0, 0, 0): material id 3 out of range"), "{stderr}");
    let out = glowbrick(&["check-world", dir.join("missing.ron").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(1));
}

#[test]
fn bad_settings_and_arguments_fail_cleanly() {
    let out = glowbrick(&["render", "--scene", "test-room", "--set", "colour=blue", "--out", "/tmp/x.png"]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("unknown setting 'colour'") && stderr.contains("debug="), "{stderr}");
    let out = glowbrick(&["render", "--scene", "test-room", "--set", "sun=maybe", "--out", "/tmp/x.png"]);
    assert!(text(&out.stderr).contains("not one of on|off"));
    let out = glowbrick(&["render", "--scene", "test-room", "--view", "nope", "--out", "/tmp/x.png"]);
    assert!(text(&out.stderr).contains("no view 'nope' (this world has: inside, top)"), "{}", text(&out.stderr));
    let out = glowbrick(&["render", "--scene", "test-room", "--out", "/tmp/x.jpg"]);
    assert!(text(&out.stderr).contains("must end in .png or .exr"));
    let out = glowbrick(&["render", "--scene", "test-room", "--width", "0", "--out", "/tmp/x.png"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("image size 0x180"), "{}", text(&out.stderr));
    // No scene folder where the scenes are looked for: one line saying where and what to do, not an empty list.
    let out = Command::new(env!("CARGO_BIN_EXE_glowbrick"))
        .args(["render", "--scene", "test-room", "--out", "/tmp/x.png"])
        .env("GLOWBRICK_ASSETS", "/nonexistent/glowbrick-assets")
        .output()
        .expect("run glowbrick");
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("/nonexistent/glowbrick-assets/scenes") && stderr.contains("GLOWBRICK_ASSETS"), "{stderr}");
    // ReSTIR settings: out of range, not a number, or not a choice, each with the valid range in the message.
    for (pair, expected) in [
        ("candidates=0", "candidates: 0 is out of range (valid: 1..64)"),
        ("candidates=1000000000", "candidates: 1000000000 is out of range (valid: 1..64)"),
        ("candidates=lots", "candidates: 'lots' is not a whole number (valid: 1..64)"),
        ("taps=17", "taps: 17 is out of range (valid: 0..16)"),
        ("radius=-1", "radius: -1 is out of range (valid: 0..100)"),
        ("radius=NaN", "radius: NaN is out of range (valid: 0..100)"),
        ("sample=sphere", "sample: 'sphere' is not one of area|point"),
        ("reuse=maybe", "reuse: 'maybe' is not one of biased|one-ray|unbiased"),
        ("lighting=path", "lighting: 'path' is not one of full|emitters|nee|sun"),
    ] {
        let out = glowbrick(&["render", "--scene", "test-room", "--set", pair, "--out", "/tmp/x.png"]);
        assert_eq!(out.status.code(), Some(1), "{pair}");
        assert!(text(&out.stderr).contains(expected), "{pair}: {}", text(&out.stderr));
    }
    let out = glowbrick(&["play", "--new", "--size", "4,4,4"]);
    assert!(!out.status.success());
    assert!(text(&out.stderr).contains("must be within 8..=2048"), "{}", text(&out.stderr));
}

#[test]
fn reference_and_compare_work_together() {
    let dir = std::env::temp_dir().join(format!("glowbrick-ref-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let exr = dir.join("ref.exr");
    let out = glowbrick(&[
        "reference",
        "--scene",
        "test-room",
        "--width",
        "16",
        "--height",
        "9",
        "--spp",
        "4",
        "--out",
        exr.to_str().unwrap(),
    ]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("4 spp"), "{}", text(&out.stdout));
    let diff = dir.join("diff.png");
    let out = glowbrick(&["compare", exr.to_str().unwrap(), exr.to_str().unwrap(), "--diff", diff.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    assert!(stdout.starts_with("mae=0.000000 mse=0.000000 relmse=0.000000 bias=+0.000000 flip=0.000000 "), "{stdout}");
    // The reference's mean luminance, what a bias is a share of: the lit test room is not black.
    assert!(field(&stdout, "reference_mean") > 0.0, "{stdout}");
    assert!(diff.is_file());
    // The same reference as a PNG (display values, compared as they are): FLIP 0 against itself and against the
    // EXR (tonemapped as the PNG was written); `--diff-kind flip` writes the FLIP map.
    let png = dir.join("ref.png");
    let args = ["reference", "--scene", "test-room", "--width", "16", "--height", "9", "--spp", "4", "--out"];
    assert!(glowbrick(&[&args[..], &[png.to_str().unwrap()]].concat()).status.success());
    for (a, b) in [(&png, &png), (&png, &exr)] {
        let flip_map = dir.join("flip.png");
        let out = glowbrick(&[
            "compare",
            a.to_str().unwrap(),
            b.to_str().unwrap(),
            "--diff",
            flip_map.to_str().unwrap(),
            "--diff-kind",
            "flip",
        ]);
        assert!(out.status.success(), "{}", text(&out.stderr));
        assert_eq!(field(&text(&out.stdout), "flip"), 0.0, "{}", text(&out.stdout));
        assert!(flip_map.is_file());
    }
    // A corrupt or missing input is one clear error, not a number.
    let corrupt = dir.join("corrupt.exr");
    std::fs::write(&corrupt, b"not an image").unwrap();
    for bad in [corrupt.to_str().unwrap(), "/nonexistent/x.exr"] {
        let out = glowbrick(&["compare", exr.to_str().unwrap(), bad]);
        assert_eq!(out.status.code(), Some(1));
        let stderr = text(&out.stderr);
        assert!(stderr.contains("cannot read image") && stderr.lines().count() == 1, "{stderr}");
    }
    let other = dir.join("other.exr");
    glowbrick(&[
        "reference",
        "--scene",
        "test-room",
        "--width",
        "8",
        "--height",
        "9",
        "--spp",
        "1",
        "--out",
        other.to_str().unwrap(),
    ]);
    let out = glowbrick(&["compare", exr.to_str().unwrap(), other.to_str().unwrap()]);
    assert!(text(&out.stderr).contains("differ in size: 16x9 against 8x9"), "{}", text(&out.stderr));
}

/// The number after `name=` in `compare`'s line.
fn field(stdout: &str, name: &str) -> f64 {
    let prefix = format!("{name}=");
    let word = stdout.split_whitespace().find_map(|w| w.strip_prefix(prefix.as_str()));
    word.and_then(|v| v.parse().ok()).unwrap_or_else(|| panic!("no {name} in {stdout}"))
}

#[test]
fn flip_matches_nvidias_reference_implementation_on_a_shipped_pair() {
    let data = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/flip");
    let (test, reference) = (data.join("test.png"), data.join("reference.png"));
    let out = glowbrick(&["compare", test.to_str().unwrap(), reference.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    let stdout = text(&out.stdout);
    let flip = field(&stdout, "flip");
    // flip-evaluator 1.7 (NVIDIA's Python package of the same C++ code) gives 0.1932898759841919 (README there).
    assert!((flip - 0.193_289_876).abs() < 1e-5, "{stdout}");
}

/// An output folder that cannot be created: a bench sweep that got past the parser stops at once.
const NOWHERE: &str = "/dev/null/glowbrick";

/// Flags of another `bench` mode, or of a world that is not generated, are a usage error naming both flags
/// (clap's exit code 2), never silently ignored. Clap checks conflicts before missing arguments such as --out.
#[test]
fn conflicting_flags_are_refused() {
    let camera = "--camera=1,2,3,0,0,1";
    for (args, first, second) in [
        (&["bench", "--thesis", "--quick"][..], "--thesis", "--quick"),
        (&["bench", "--thesis", "--scenes", "x"], "--thesis", "--scenes"),
        (&["bench", "--thesis", "--gi"], "--thesis", "--gi"),
        (&["bench", "--gi", "--settings", "restir"], "--gi", "--settings"),
        (&["bench", "--gi", camera], "--gi", "--camera"),
        (&["bench", "--gi", "--scale", "0.5"], "--gi", "--scale"),
        (&["bench", "--daylight", "--scale", "0.5"], "--daylight", "--scale"),
        (&["bench", "--daylight", "--quick"], "--daylight", "--quick"),
        (&["bench", "--daylight", "--gi"], "--daylight", "--gi"),
        (&["bench", "--denoise", "--settings", "restir"], "--denoise", "--settings"),
        (&["bench", "--gi", "--lattice", "4"], "--gi", "--lattice"),
        (&["bench", "--denoise", "--cost", "--lattice", "4"], "--cost", "--lattice"),
        (&["bench", "--denoise", "--motion", "--scenes", "cornell"], "--motion", "--scenes"),
        (&["bench", "--scale", "0.5", "--settings", "restir"], "--scale", "--settings"),
        (&["bench", "--quick", "--spp", "4"], "--spp", "--quick"),
        (&["bench", "--frame", "--spp", "4"], "--spp", "--frame"),
        (&["bench", "--frame", "--gi"], "--frame", "--gi"),
        (&["bench", "--scale", "0.5", "--out", NOWHERE], "--thesis", "required"),
        (&["bench", "--spp", "4", "--out", NOWHERE], "--thesis|--gi", "required"),
        (&["render", "--scene", "test-room", "--view", "top", camera], "--view", "--camera"),
        (&["render", "--world", "a.ron", "--scene", "test-room"], "--world", "--scene"),
        (&["play", "--new", "--world", "a.ron"], "--new", "--world"),
        (&["play", "--scene", "test-room", "--seed", "3"], "--seed", "--scene"),
        (&["--world", "a.ron", "--size", "8,8,8"], "--size", "--world"),
    ] {
        let out = glowbrick(args);
        assert_eq!(out.status.code(), Some(2), "{args:?}");
        let stderr = text(&out.stderr);
        assert!(stderr.contains(first) && stderr.contains(second), "{args:?}: {stderr}");
    }
}

/// Each bench mode still takes its own flags: these parse and stop at the first check of the values, before any
/// GPU work.
#[test]
fn each_bench_mode_takes_its_own_flags() {
    let out = glowbrick(&["bench", "--thesis", "--scale", "2", "--spp", "4", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("--scale 2 must be within (0, 1]"), "{}", text(&out.stderr));
    let args = ["--quick", "--scenes", "cornell", "--settings", "bogus", "--camera=1,2,3,0,0,1"];
    let out = glowbrick(&[&["bench"][..], &args, &["--out", NOWHERE]].concat());
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("unknown bench setting 'bogus'"), "{}", text(&out.stderr));
    // The reference's lattice: the denoiser's one frame takes it (within a quarter of the image's side), the
    // default sweep does not.
    let out = glowbrick(&["bench", "--denoise", "--one-frame", "--lattice", "40", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("--lattice 40 must be within 1..=22"), "{}", text(&out.stderr));
    // The denoiser's one frame takes a subset of its four scenes, and names them when given another.
    let out = glowbrick(&["bench", "--denoise", "--one-frame", "--scenes", "cornell,mountain", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("no scene 'mountain'") && stderr.contains("window-room, cornell"), "{stderr}");
    // The upscaler's table measures the frame profile's scenes, and names them when given another.
    let out = glowbrick(&["bench", "--denoise", "--upscale", "--scenes", "generated-night,mountain", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("--upscale has no scene 'mountain'") && stderr.contains("generated-noon"), "{stderr}");
    let out = glowbrick(&["bench", "--denoise", "--upscale", "--motion", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(2), "two sections of the denoiser bench are a usage error");
    // A setting on top of the thesis protocol is checked before the references' minutes.
    let out = glowbrick(&["bench", "--thesis", "--set", "bogus=1", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("unknown setting 'bogus'"), "{}", text(&out.stderr));
    let out = glowbrick(&["bench", "--gi", "--set", "denoise=on", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("--set needs --thesis, --denoise or --frame"), "{}", text(&out.stderr));
    // Realisations to average belong to the denoiser's bench and the cache's light alone.
    let out = glowbrick(&["bench", "--gi", "--seeds", "4", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("--seeds needs --denoise or --gi --indirect"), "{}", text(&out.stderr));
    let out = glowbrick(&["bench", "--lattice", "4", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("--lattice needs --thesis or --denoise"), "{}", text(&out.stderr));
    // Sizes belong to the two cost tables, not to the denoiser's one frame.
    let out = glowbrick(&["bench", "--denoise", "--one-frame", "--sizes", "1920x1080", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("--sizes needs --gi --game-sizes, --denoise --cost or --frame"), "{stderr}");
    // The frame profile names its cases when given another, and checks its settings before any GPU work.
    let out = glowbrick(&["bench", "--frame", "--scenes", "cornell,mountain", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    let stderr = text(&out.stderr);
    assert!(stderr.contains("no scene 'mountain'") && stderr.contains("window-room, cornell"), "{stderr}");
    let out = glowbrick(&["bench", "--frame", "--quick", "--set", "taps=99", "--out", NOWHERE]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("taps: 99 is out of range"), "{}", text(&out.stderr));
}

/// `src/main.rs` only parses and dispatches; the commands live in `src/cli/`.
#[test]
fn main_only_dispatches() {
    let main = std::fs::read_to_string(repo("src/main.rs")).unwrap();
    assert!(main.lines().count() < 60, "src/main.rs has {} lines", main.lines().count());
}

/// Every command, given each kind of wrong argument (a missing file, a folder for a file, a path through a file,
/// a dangling link, binary junk, zero, huge and negative numbers, an output in a missing folder), exits with
/// code 1 or 2 and one line on stderr, and writes nothing. (Unreadable permissions cannot be tested here: the
/// tests run as root, who reads everything.)
#[test]
fn every_command_refuses_each_kind_of_wrong_argument_in_one_line() {
    let dir = std::env::temp_dir().join(format!("glowbrick-badargs-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(dir.join("folder.ron")).unwrap();
    std::fs::write(dir.join("file.ron"), "(a: 1)").unwrap();
    std::fs::write(dir.join("binary.ron"), [0xffu8, 0xfe, 0, 1, 2, 0x80]).unwrap();
    std::fs::write(dir.join("image.exr"), b"not an image").unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink(dir.join("nowhere.ron"), dir.join("dangling.ron")).unwrap();
    let p = |name: &str| dir.join(name).display().to_string();
    let bad_worlds = ["missing.ron", "folder.ron", "file.ron/inside.ron", "dangling.ron", "binary.ron", "world.txt"];
    let (png, exr) = (p("out.png"), p("out.exr"));
    let mut cases: Vec<Vec<String>> = Vec::new();
    let args = |a: &[&str]| a.iter().map(|s| s.to_string()).collect::<Vec<String>>();
    for world in bad_worlds {
        let world = p(world);
        cases.push(args(&["check-world", &world]));
        cases.push(args(&["render", "--world", &world, "--out", &png]));
        cases.push(args(&["reference", "--world", &world, "--out", &exr]));
        cases.push(args(&["play", "--world", &world]));
        cases.push(args(&["compare", &world, &p("image.exr")]));
    }
    for out in [p("nofolder/out.png"), p("folder.ron"), p("out.jpg")] {
        cases.push(args(&["render", "--scene", "test-room", "--out", &out]));
        cases.push(args(&["reference", "--scene", "test-room", "--out", &out]));
    }
    for size in [["--width", "0"], ["--height", "0"], ["--width", "100000"], ["--width", "-5"], ["--width", "x"]] {
        cases.push(args(&[&["render", "--scene", "test-room", "--out", &png][..], &size].concat()));
        cases.push(args(&[&["reference", "--scene", "test-room", "--out", &exr][..], &size].concat()));
    }
    cases.extend([
        args(&["render", "--scene", "test-room", "--frames", "0", "--out", &png]),
        args(&["render", "--scene", "test-room", "--frames", "-3", "--out", &png]),
        args(&["render", "--scene", "no-such-scene", "--out", &png]),
        args(&["render", "--scene", "../../etc/passwd", "--out", &png]),
        args(&["render", "--scene", "test-room", "--config", &p("missing.ron"), "--out", &png]),
        args(&["render", "--scene", "test-room", "--config", &p("binary.ron"), "--out", &png]),
        args(&["reference", "--scene", "test-room", "--spp", "0", "--out", &exr]),
        args(&["reference", "--scene", "test-room", "--seconds", "-1", "--out", &exr]),
        args(&["reference", "--scene", "test-room", "--bounces", "99999", "--out", &exr]),
        args(&["compare", &p("image.exr"), &p("image.exr")]),
        args(&["compare", &p("folder.ron"), &p("folder.ron")]),
        args(&["bench", "--out", &p("file.ron")]),
        args(&["bench", "--quick", "--scenes", "no-such-scene", "--out", &p("bench")]),
        args(&["stress", "--frames", "0"]),
        args(&["stress", "--frames", "-10"]),
        args(&["stress", "--scene", "no-such-scene", "--quick"]),
        args(&["stress", "--fuzz", "0"]),
        args(&["stress", "--fuzz", "10", "--fuzz-target", "nothing"]),
        args(&["stress", "--fuzz-only", "world"]),
        args(&["stress", "--fuzz-only", "world:x"]),
        args(&["stress", "--saves", "0"]),
        args(&["play", "--size", "0,0,0"]),
        args(&["play", "--size", "99999,64,64"]),
        args(&["play", "--set", "colour=blue"]),
        args(&["play", "--model", &p("missing.vox")]),
        args(&["play", "--model", &p("binary.ron")]),
        args(&["no-such-command"]),
        args(&["--no-such-flag"]),
    ]);
    let before = std::fs::read_dir(&dir).unwrap().count();
    for case in &cases {
        let refs: Vec<&str> = case.iter().map(String::as_str).collect();
        let out = glowbrick(&refs);
        let stderr = text(&out.stderr);
        let code = out.status.code();
        assert!(matches!(code, Some(1) | Some(2)), "{case:?}: exit {code:?}\n{stderr}");
        assert_eq!(stderr.trim_end().lines().count(), 1, "{case:?}: not one line:\n{stderr}");
        assert!(stderr.starts_with("error") && !stderr.contains("panicked"), "{case:?}: {stderr}");
    }
    assert_eq!(std::fs::read_dir(&dir).unwrap().count(), before, "a refused command wrote a file");
    let _ = std::fs::remove_dir_all(&dir);
}

/// `play` on a machine without a display says so in one line (and what works instead), never winit's panic.
#[test]
fn play_without_a_display_says_so_in_one_line() {
    let out = Command::new(env!("CARGO_BIN_EXE_glowbrick"))
        .args(["play", "--size", "32,32,32"])
        .env_remove("DISPLAY")
        .env_remove("WAYLAND_DISPLAY")
        .output()
        .unwrap();
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no display") && stderr.contains("glowbrick render"), "{stderr}");
}

/// With a display but no GPU adapter (the Vulkan loader pointed at no driver), `play` names the driver to
/// install, in one line.
#[test]
fn play_without_a_gpu_adapter_says_which_driver_to_install() {
    let out = Command::new(env!("CARGO_BIN_EXE_glowbrick"))
        .args(["play", "--size", "32,32,32"])
        .env("DISPLAY", ":4242")
        .env("VK_ICD_FILENAMES", "/nonexistent/icd.json")
        .env("VK_DRIVER_FILES", "/nonexistent/icd.json")
        .env("WGPU_BACKEND", "vulkan")
        .output()
        .unwrap();
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no GPU adapter") && stderr.contains("mesa-vulkan-drivers"), "{stderr}");
}

/// `play --view` of a view the world lacks names the views it has, in one line, before any window opens; `generate`
/// reports what it made.
#[test]
fn play_at_a_missing_view_lists_the_views_and_generate_reports_its_world() {
    let out = glowbrick(&["play", "--size", "128,48,128", "--view", "nowhere"]);
    let stderr = text(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert_eq!(stderr.trim_end().lines().count(), 1, "{stderr}");
    assert!(stderr.contains("no view 'nowhere'") && stderr.contains("village, house"), "{stderr}");

    let out = glowbrick(&["generate", "--size", "128,48,128", "--seed", "3"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("generated 128x48x128 (seed 3)") && stdout.contains("houses"), "{stdout}");
    assert!(stdout.contains("views: village, house, lantern, overview"), "{stdout}");
}

/// `reference --endless SEED` traces a window of the endless world around a camera given in world coordinates,
/// a million voxels out as at the start; a camera past f32's whole voxels is one clear error.
#[test]
fn reference_of_the_endless_world_stands_anywhere() {
    let dir = std::env::temp_dir().join(format!("glowbrick-endless-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out = dir.join("far.exr");
    let camera = "1000000.5,110,1000000.5,0.7,-0.35,0.6";
    let args = ["reference", "--endless", "1", "--camera", camera, "--width", "24", "--height", "16", "--spp", "1"];
    let run = glowbrick(&[&args[..], &["--out", out.to_str().unwrap()]].concat());
    assert!(run.status.success(), "{}", text(&run.stderr));
    let image = glowbrick::image_io::read_image(&out).unwrap();
    assert!(image.mean_luminance() > 0.01, "the far land is lit: {}", image.mean_luminance());
    let run =
        glowbrick(&["reference", "--endless", "1", "--camera", "3e7,100,0,1,0,0", "--out", out.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(1));
    assert!(text(&run.stderr).contains("within 16777216 voxels"), "{}", text(&run.stderr));
    let run = glowbrick(&["reference", "--endless", "1", "--view", "village", "--out", out.to_str().unwrap()]);
    assert_eq!(run.status.code(), Some(2), "a named view belongs to a world file");
}

/// `generate --endless R` makes R x R regions of the endless world and says how fast; a height too low for a
/// village is one clear error.
#[test]
fn generate_endless_makes_regions_and_refuses_a_world_too_low() {
    let out = glowbrick(&["generate", "--size", "64,64,64", "--seed", "2", "--endless", "2"]);
    let stdout = text(&out.stdout);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(stdout.contains("made 4 regions of 64x64x64 (seed 2") && stdout.contains("regions/s"), "{stdout}");
    let out = glowbrick(&["generate", "--size", "64,30,64", "--endless", "1"]);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("height must be 40..=2048, not 30"), "{}", text(&out.stderr));
    // --out writes an endless world's save folder; `reference --saves` reads it, refusing another seed's.
    let dir = std::env::temp_dir().join(format!("glowbrick-endless-save-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    let out =
        glowbrick(&["generate", "--size", "64,48,64", "--seed", "2", "--endless", "1", "--out", dir.to_str().unwrap()]);
    assert!(out.status.success(), "{}", text(&out.stderr));
    assert!(text(&out.stdout).contains("saved 1 regions"), "{}", text(&out.stdout));
    assert!(dir.join("world.ron").is_file());
    assert_eq!(std::fs::read_dir(dir.join("regions")).unwrap().count(), 1, "one region file");
    let exr = dir.join("shot.exr");
    let args = ["reference", "--endless", "3", "--saves", dir.to_str().unwrap(), "--out", exr.to_str().unwrap()];
    let out = glowbrick(&args);
    assert_eq!(out.status.code(), Some(1));
    assert!(text(&out.stderr).contains("holds the endless world of seed 2, not 3"), "{}", text(&out.stderr));
    let _ = std::fs::remove_dir_all(&dir);
}
