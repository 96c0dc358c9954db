//! `glowbrick stress --quick` in CI: a short soak (random edits, lights placed, broken and recoloured every frame,
//! camera teleports, the game's own frame with its clock moving, settings at their extremes) with no non-finite
//! pixel or reservoir field, and a static view afterwards that neither drifts nor strays from the CPU reference
//! (the command's own checks, exit code 1), and memory sampled from the process and the GPU device.

use std::process::Command;

pub fn quick_stress_run_finds_no_non_finite_value_and_no_drift() {
    let run = Command::new(env!("CARGO_BIN_EXE_glowbrick")).args(["stress", "--quick"]).output().unwrap();
    let stdout = String::from_utf8_lossy(&run.stdout);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stdout}\n{stderr}");
    assert!(stdout.contains("non-finite pixels: 0"), "{stdout}");
    assert!(stdout.contains("non-finite 0,"), "{stdout}");
    // The soak really edited and moved: the report counts what it did.
    let count = |after: &str| -> u32 {
        let rest = stdout.split(after).nth(1).unwrap_or_default();
        rest.split(|c: char| !c.is_ascii_digit()).next().and_then(|n| n.parse().ok()).unwrap_or(0)
    };
    let frames = count("frames ");
    assert!(frames >= 330 && count("edits ") >= frames, "{stdout}");
    // The game's own frame (full lighting, GI, denoiser, the clock moving) was among those soaked.
    assert!(count("the clock moving): ") >= 30, "{stdout}");
    // Memory is sampled: the process and the GPU device (wgpu's counters are on) both hold something.
    let last = stdout.split("last frame: resident ").nth(1).unwrap_or_default();
    let mib = |s: &str| s.split(" MiB").next().and_then(|n| n.trim().parse::<f64>().ok()).unwrap_or(0.0);
    let gpu = last.split("GPU buffers + textures ").nth(1).map(mib).unwrap_or(0.0);
    assert!(mib(last) > 50.0 && gpu > 1.0, "{stdout}");
}
