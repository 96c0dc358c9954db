//! `glowbrick bench --quick` runs headless on any adapter and writes its three outputs with sane contents.

use std::process::Command;

pub fn quick_bench_writes_csv_markdown_and_plot() {
    let out = std::env::temp_dir().join(format!("glowbrick-bench-{}", std::process::id()));
    let cache = out.join("cache");
    let run = Command::new(env!("CARGO_BIN_EXE_glowbrick"))
        .args(["bench", "--quick", "--out", out.to_str().unwrap()])
        .env("GLOWBRICK_CACHE", &cache)
        .output()
        .unwrap();
    assert!(run.status.success(), "{}", String::from_utf8_lossy(&run.stderr));
    let csv = std::fs::read_to_string(out.join("results.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert_eq!(lines[0], "scene,setting,frame_ms,gpu_ms,mae,mse,relmse,bias");
    let per_scene = glowbrick::bench::SETTINGS.len() + 1;
    assert_eq!(lines.len(), 1 + 2 * per_scene, "two scenes x the settings and the equal-time row:\n{csv}");
    // ReSTIR's one frame beats one NEE frame on both scenes (MAE).
    let mae = |scene: &str, setting: &str| -> f64 {
        let line = lines.iter().find(|l| l.starts_with(&format!("{scene},{setting},"))).unwrap();
        line.split(',').nth(4).unwrap().parse().unwrap()
    };
    for scene in ["cornell", "letters"] {
        assert!(mae(scene, "restir") < mae(scene, "nee-power"), "{scene}: ReSTIR no better than NEE:\n{csv}");
    }
    for line in &lines[1..] {
        let fields: Vec<&str> = line.split(',').collect();
        let frame_ms: f64 = fields[2].parse().unwrap();
        let mae: f64 = fields[4].parse().unwrap();
        assert!(frame_ms > 0.0 && mae.is_finite() && mae > 0.0, "{line}");
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("| cornell | nee-power |") && report.contains("plot.png"));
    let plot = image::open(out.join("plot.png")).unwrap();
    assert!(plot.width() >= 400 && plot.height() >= 300);
    // The references were cached: a second run reuses them.
    let cached = std::fs::read_dir(&cache).unwrap().count();
    assert_eq!(cached, 2);
}
