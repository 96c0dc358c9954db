//! `glowbrick bench --quick` runs headless on any adapter and writes its outputs with sane contents: the table,
//! the convergence curves (at least four points per method, error falling), the plot and the image strips.

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
    assert_eq!(lines[0], "scene,setting,frames,frame_ms,gpu_ms,mae,mse,relmse,bias,flip,fireflies");
    let field = |line: &str, i: usize| -> f64 { line.split(',').nth(i).unwrap().parse().unwrap() };
    let single = |scene: &str, setting: &str| -> &str {
        lines.iter().find(|l| l.starts_with(&format!("{scene},{setting},1,"))).unwrap()
    };
    let methods = glowbrick::bench::convergence::METHODS;
    for scene in ["cornell", "letters"] {
        // ReSTIR's one frame beats one NEE frame on both scenes (MAE and FLIP).
        let (restir, nee) = (single(scene, "restir"), single(scene, "nee-power"));
        assert!(field(restir, 5) < field(nee, 5), "{scene}: ReSTIR no better than NEE (MAE):\n{csv}");
        assert!(field(restir, 9) < field(nee, 9), "{scene}: ReSTIR no better than NEE (FLIP):\n{csv}");
        // A curve per method: 1, 2, 4, 8, 16 frames (the readback may land a frame later), MAE falling. (Not
        // relMSE: NEE's cornell curve is ruled by contact fireflies, whose squared error can rise as one lands.)
        for method in methods {
            let curve: Vec<&str> = lines
                .iter()
                .copied()
                .filter(|l| l.starts_with(&format!("{scene},{} accumulated,", method.name)))
                .collect();
            assert!(curve.len() >= 4, "{scene} {}: {} points:\n{csv}", method.name, curve.len());
            let (first, last) = (curve[0], curve[curve.len() - 1]);
            assert!(field(last, 2) >= 16.0 && field(last, 3) > field(first, 3), "{first} .. {last}");
            assert!(
                field(last, 5) < 0.9 * field(first, 5),
                "{scene} {}: MAE did not fall: {first} .. {last}",
                method.name
            );
        }
        let strip = image::open(out.join(format!("strip-{scene}.png"))).unwrap();
        assert_eq!((strip.width(), strip.height()), (4 * 96 + 3 * 4, 64));
    }
    for line in &lines[1..] {
        let (frame_ms, mae, flip) = (field(line, 3), field(line, 5), field(line, 9));
        assert!(frame_ms > 0.0 && mae.is_finite() && mae > 0.0 && flip > 0.0 && flip < 1.0, "{line}");
    }
    let report = std::fs::read_to_string(out.join("report.md")).unwrap();
    assert!(report.contains("| cornell | nee-power | 1 |") && report.contains("plot.svg"), "{report}");
    assert!(report.contains("reference's own noise") && report.contains("strip-letters.png"));
    let plot = std::fs::read_to_string(out.join("plot.svg")).unwrap();
    assert!(plot.starts_with("<svg") && plot.contains("restir-biased") && plot.contains("relMSE"));
    // The references (two seeds per scene, for the reference's noise) were cached: a second run reuses them.
    let cached = std::fs::read_dir(&cache).unwrap().count();
    assert_eq!(cached, 4);
}
