//! `glowbrick bench --frame`: the game's frame pass by pass. Every voxel pass's GPU time (timestamp queries, where
//! the adapter has them), the frame's wall-clock time beside their sum, and the deterministic counters that hold on
//! any adapter: rays per pixel of each per-pixel pass, rays per hit pixel of the direct light, traversal
//! steps and memory loads per ray, candidates per hit pixel, GI entries updated and the GI passes' rays.
//! The scenes are the bundled rooms, the generated world a player opens (noon and night) and the thesis' letters.
//!
//! Its quick mode (`--quick`, and the GPU test `ray_budget`) holds each pass to the frame's ray budget
//! (`RAY_BUDGET`), so a change that adds rays fails.

use super::load_bench_scene;
use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::render::denoise::DENOISE_PASS_NAMES;
use crate::render::frame::all_passes;
use crate::render::gi::{DYNAMIC_GI_PASS_NAMES, GI_PASS_NAMES, WARM_UP_FRAMES};
use crate::render::gpu_types::{COUNTERS, GpuCounter};
use crate::render::plan::render_size;
use crate::render::primary::PRIMARY_PASS_NAME;
use crate::render::restir::{self, RESTIR_PASS_NAMES};
use crate::render::upscale::{self, UPSCALE_PASS_NAMES};
use crate::settings::RenderSettings;
use crate::world::recipe::generated_world;
use crate::world::{CameraView, VoxelWorld};
use bevy::math::{UVec2, UVec3};
use std::path::Path;
use std::time::Instant;

/// One scene and view of the profile, with the settings that make it (a time of day).
#[derive(Clone, Copy, Debug)]
pub struct FrameCase {
    pub label: &'static str,
    /// A bench scene (`load_bench_scene`), or `generated` for the world `glowbrick play` opens.
    pub scene: &'static str,
    /// The view's name (empty: the scene's first view).
    pub view: &'static str,
    pub settings: &'static [&'static str],
}

/// The night case is at 2:00, not midnight: the moon at 0:00 stands exactly where the noon sun does
/// (`lights::daylight`), so its shadow rays and the frame's cost would be noon's (docs/bench/why.md).
pub const CASES: [FrameCase; 6] = [
    FrameCase { label: "window-room", scene: "window-room", view: "inside", settings: &[] },
    FrameCase { label: "cornell", scene: "cornell", view: "front", settings: &[] },
    FrameCase { label: "apartments", scene: "apartments", view: "street", settings: &[] },
    FrameCase { label: "generated-noon", scene: "generated", view: "", settings: &["time=12"] },
    FrameCase { label: "generated-night", scene: "generated", view: "", settings: &["time=2"] },
    FrameCase { label: "thesis-letters", scene: "thesis-letters", view: "letters1", settings: &[] },
];

/// The generated world of the profile: `glowbrick play`'s default seed and size (`cli::play::DEFAULT_SIZE`), seen
/// from its start view on the village plaza.
const GENERATED_SEED: u32 = 1;
const GENERATED_SIZE: UVec3 = UVec3::new(1024, 192, 1024);

/// The two lightings profiled: the game's frame (`RenderSettings::game()`: sun, sky and emitters, GI cache,
/// denoiser), and the same with emitters only (the thesis' protocol, no sun or sky).
pub const LIGHTINGS: [(&str, &[&str]); 2] = [("game", &[]), ("emitters", &["lighting=emitters"])];

/// Rays per pixel each per-pixel pass of the game's frame may trace at most: the primary ray; the chosen
/// candidate's visibility; one for the spatial tap (`taps=1`, with `reuse=one-ray`); the final shadow ray and the
/// sun's disk. The quick mode fails a frame over any of them.
pub const RAY_BUDGET: [(GpuCounter, &str, f64); 4] = [
    (GpuCounter::RaysPrimary, "primary", 1.0),
    (GpuCounter::RaysRestirInitial, "ReSTIR initial", 1.0),
    (GpuCounter::RaysRestirSpatial, "ReSTIR spatial", 1.0),
    (GpuCounter::RaysRestirShade, "ReSTIR shade", 2.0),
];

/// Rays per hit pixel of the whole direct light (its primary ray included) in every quick case: issue 43's
/// target. A pass that adds one ray for a large share of the pixels crosses this line.
pub const QUICK_HIT_PIXEL_BUDGET: f64 = 4.0;

/// How big and how long the profile runs.
#[derive(Clone, Debug)]
pub struct FrameConfig {
    pub sizes: Vec<(u32, u32)>,
    pub cases: Vec<FrameCase>,
    pub lightings: Vec<(&'static str, &'static [&'static str])>,
    /// Frames before timing: pipelines, the GI cache's warm-up and the temporal history.
    pub warm_frames: u32,
    pub timed_frames: u32,
    /// Settings on top of every row's (`--set`), e.g. `taps=1`.
    pub extra: Vec<String>,
}

impl FrameConfig {
    pub fn full(sizes: Vec<(u32, u32)>) -> Self {
        FrameConfig {
            sizes: if sizes.is_empty() { vec![(320, 180), (1280, 720)] } else { sizes },
            cases: CASES.to_vec(),
            lightings: LIGHTINGS.to_vec(),
            warm_frames: WARM_UP_FRAMES + 8,
            timed_frames: 8,
            extra: Vec::new(),
        }
    }

    /// The test suite's run: the game's frame at 48x32 on four scenes, a frame after the temporal history and the
    /// GI warm-up began, counters only.
    pub fn quick() -> Self {
        let quick = ["cornell", "window-room", "apartments", "thesis-letters"];
        FrameConfig {
            sizes: vec![(48, 32)],
            cases: CASES.iter().filter(|c| quick.contains(&c.label)).copied().collect(),
            lightings: vec![LIGHTINGS[0]],
            warm_frames: 4,
            timed_frames: 1,
            extra: Vec::new(),
        }
    }
}

/// One case x lighting x size.
#[derive(Clone, Debug)]
pub struct FrameRow {
    pub case: &'static str,
    pub lighting: &'static str,
    pub size: (u32, u32),
    /// Wall-clock ms per frame (the GPU waited for every frame).
    pub wall_ms: f64,
    /// GPU ms of every pass that ran, in `all_passes` order (empty without timestamps).
    pub passes: Vec<(&'static str, f64)>,
    /// One frame's counters, read after the timed frames.
    pub counters: [u32; COUNTERS],
    /// ReSTIR's candidates per hit pixel (the setting), 0 where ReSTIR does not run.
    pub candidates: u32,
    /// The lighting passes' share of the output's pixels per axis (`render_scale`).
    pub render_scale: f32,
}

impl FrameRow {
    fn count(&self, counter: GpuCounter) -> f64 {
        self.counters[counter as usize] as f64
    }

    pub fn pixels(&self) -> f64 {
        (self.size.0 * self.size.1) as f64
    }

    /// The lighting passes' pixels (`render_scale` of the output's per axis).
    pub fn render_pixels(&self) -> f64 {
        let size = render_size(UVec2::new(self.size.0, self.size.1), self.render_scale);
        f64::from(size.x) * f64::from(size.y)
    }

    /// Brick-grid rays of the lighting passes (ReSTIR's candidates' visibility, spatial taps and shading, the
    /// GI cache's refresh and update rays, and the upscaler's shadow rays on the disk's shadow edges) per output
    /// pixel: what render scale lowers.
    pub fn lighting_rays_per_output_pixel(&self) -> f64 {
        let rays = self.restir_rays() + self.count(GpuCounter::RaysGi) + self.count(GpuCounter::RaysUpscale);
        rays / self.pixels()
    }

    /// ReSTIR's rays per render pixel (the same at every scale for the same scene).
    pub fn restir_rays_per_render_pixel(&self) -> f64 {
        self.restir_rays() / self.render_pixels()
    }

    fn restir_rays(&self) -> f64 {
        self.direct_rays() - self.count(GpuCounter::RaysPrimary)
    }

    /// Rays per (output) pixel of one budgeted pass.
    pub fn rays_per_pixel(&self, counter: GpuCounter) -> f64 {
        self.count(counter) / self.pixels()
    }

    /// Rays of the direct light (primary, ReSTIR's passes) in the frame.
    pub fn direct_rays(&self) -> f64 {
        RAY_BUDGET.iter().map(|&(c, _, _)| self.count(c)).sum()
    }

    /// The direct light's rays per pixel whose primary ray hit: its primary ray and the rays ReSTIR traces for it
    /// (only hit pixels trace those). A pixel of sky costs its primary ray alone.
    pub fn rays_per_hit_pixel(&self) -> f64 {
        let hits = self.count(GpuCounter::PrimaryHits);
        let restir = self.direct_rays() - self.count(GpuCounter::RaysPrimary);
        (hits + restir) / hits.max(1.0)
    }

    pub fn hit_share(&self) -> f64 {
        self.count(GpuCounter::PrimaryHits) / self.pixels()
    }

    /// Traversal steps (the walk's loop steps) and memory loads per ray of the per-pixel passes.
    pub fn steps_per_ray(&self) -> (f64, f64) {
        let rays = self.direct_rays().max(1.0);
        (self.count(GpuCounter::TraceSteps) / rays, self.count(GpuCounter::TraceLoads) / rays)
    }

    /// GPU ms of the passes whose names start with `prefix`, or None when none ran or were timed.
    /// The GPU ms of the passes `names` together, if any of them ran.
    pub fn gpu_ms_of(&self, names: &[&str]) -> Option<f64> {
        let times: Vec<f64> = self.passes.iter().filter(|(n, _)| names.contains(n)).map(|(_, ms)| *ms).collect();
        (!times.is_empty()).then(|| times.iter().sum())
    }

    pub fn gpu_total_ms(&self) -> Option<f64> {
        (!self.passes.is_empty()).then(|| self.passes.iter().map(|(_, ms)| ms).sum())
    }

    /// Every budget this frame breaks, as one line each (empty: within budget).
    pub fn over_budget(&self, hit_pixel_budget: f64) -> Vec<String> {
        let mut over: Vec<String> = RAY_BUDGET
            .iter()
            .filter(|&&(c, _, budget)| self.rays_per_pixel(c) > budget)
            .map(|&(c, pass, budget)| {
                format!("{}: {pass} traces {:.3} rays per pixel, over {budget}", self.case, self.rays_per_pixel(c))
            })
            .collect();
        let per_hit = self.rays_per_hit_pixel();
        if per_hit > hit_pixel_budget {
            over.push(format!(
                "{}: the direct light traces {per_hit:.3} rays per hit pixel, over {hit_pixel_budget}",
                self.case
            ));
        }
        over
    }
}

pub(crate) fn case_world(case: &FrameCase) -> Result<(VoxelWorld, CameraView), String> {
    let world = match case.scene {
        "generated" => generated_world(GENERATED_SEED, GENERATED_SIZE).map_err(|e| e.to_string())?,
        scene => load_bench_scene(scene)?,
    };
    let view = match case.view {
        "" => world.view(None).cloned().unwrap_or_else(|| world.overview()),
        name => world.view(Some(name)).cloned().ok_or_else(|| format!("{}: no view '{name}'", case.scene))?,
    };
    Ok((world, view))
}

/// One row: warm up, time `timed_frames` frames, then read one frame's counters.
pub fn measure(
    case: &FrameCase,
    lighting: (&'static str, &[&str]),
    size: (u32, u32),
    config: &FrameConfig,
) -> Result<FrameRow, String> {
    let (world, view) = case_world(case)?;
    let pairs: Vec<String> =
        case.settings.iter().chain(lighting.1).map(|p| p.to_string()).chain(config.extra.iter().cloned()).collect();
    let settings = RenderSettings::game().with_pairs(&pairs)?;
    let candidates = if settings.lighting.uses_restir() { settings.restir.candidates } else { 0 };
    let render_scale = upscale::frame_scale(&settings, None, restir::shades(&settings));
    let options = HeadlessOptions { width: size.0, height: size.1, settings, ..Default::default() };
    let mut renderer = HeadlessRenderer::new(world, &view, &options)?;
    renderer.render(config.warm_frames)?;
    renderer.clear_gpu_pass_times();
    let start = Instant::now();
    for _ in 0..config.timed_frames {
        renderer.step();
    }
    let wall_ms = start.elapsed().as_secs_f64() * 1000.0 / config.timed_frames.max(1) as f64;
    let passes = all_passes().iter().filter_map(|p| renderer.gpu_pass_ms(p.name).map(|ms| (p.name, ms))).collect();
    let counters = renderer.counters()?;
    Ok(FrameRow { case: case.label, lighting: lighting.0, size, wall_ms, passes, counters, candidates, render_scale })
}

/// Every case x lighting at each size, printing a line per row.
pub fn measure_all(config: &FrameConfig) -> Result<Vec<FrameRow>, String> {
    let mut rows = Vec::new();
    for &size in &config.sizes {
        for case in &config.cases {
            for &lighting in &config.lightings {
                let row = measure(case, lighting, size, config)?;
                let (steps, loads) = row.steps_per_ray();
                eprintln!(
                    "frame: {} {} {}x{}: {:.1} ms wall, {} ms GPU, {:.2} rays per hit pixel, {:.1} steps and {:.1} loads per ray",
                    row.case,
                    row.lighting,
                    size.0,
                    size.1,
                    row.wall_ms,
                    row.gpu_total_ms().map_or("n/a".into(), |ms| format!("{ms:.2}")),
                    row.rays_per_hit_pixel(),
                    steps,
                    loads
                );
                rows.push(row);
            }
        }
    }
    Ok(rows)
}

/// The quick mode: the rows, and an error naming every budget broken.
pub fn run_quick() -> Result<Vec<FrameRow>, String> {
    let rows = measure_all(&FrameConfig::quick())?;
    let over: Vec<String> = rows.iter().flat_map(|r| r.over_budget(QUICK_HIT_PIXEL_BUDGET)).collect();
    if over.is_empty() { Ok(rows) } else { Err(over.join("; ")) }
}

/// Runs the profile and writes `frame.csv` and `frame.md` into `out`.
pub fn run_frame_bench(config: &FrameConfig, quick: bool, out: &Path) -> Result<(), String> {
    std::fs::create_dir_all(out).map_err(|e| format!("cannot create {}: {e}", out.display()))?;
    let rows = if quick { run_quick()? } else { measure_all(config)? };
    let write = |name: &str, text: String| {
        let path = out.join(name);
        std::fs::write(&path, text).map_err(|e| format!("cannot write {}: {e}", path.display()))
    };
    write("frame.csv", csv(&rows))?;
    write("frame.md", markdown(&rows, config))?;
    eprintln!("frame bench: wrote {} and {}", out.join("frame.csv").display(), out.join("frame.md").display());
    Ok(())
}

/// The pass groups of the report's time table: the passes (from the techniques' tables) and the column.
const GROUPS: [(&[&str], &str); 13] = [
    (&[PRIMARY_PASS_NAME], "primary"),
    (&[RESTIR_PASS_NAMES[0]], "ReSTIR tiles"),
    (&[RESTIR_PASS_NAMES[1]], "ReSTIR initial"),
    (&[RESTIR_PASS_NAMES[2]], "ReSTIR temporal"),
    (&[RESTIR_PASS_NAMES[3]], "ReSTIR spatial"),
    (&[RESTIR_PASS_NAMES[4]], "ReSTIR shade"),
    (&[GI_PASS_NAMES[0]], "GI lists"),
    (&[GI_PASS_NAMES[1]], "GI refresh"),
    (&[GI_PASS_NAMES[2]], "GI update"),
    (&[GI_PASS_NAMES[3]], "GI filter"),
    (&DYNAMIC_GI_PASS_NAMES, "GI objects"),
    (&DENOISE_PASS_NAMES, "denoiser"),
    (&UPSCALE_PASS_NAMES, "upscale"),
];

pub fn csv(rows: &[FrameRow]) -> String {
    let mut text = String::from(
        "adapter,case,lighting,width,height,wall_ms,gpu_total_ms,pass,pass_gpu_ms,rays_primary,rays_initial,\
         rays_spatial,rays_shade,primary_hits,trace_steps,trace_loads,candidates,gi_updated,gi_rays,render_scale\n",
    );
    let adapter = crate::render::adapter::adapter_name().replace(',', ";");
    for r in rows {
        let c = |g: GpuCounter| r.counters[g as usize];
        let counts = format!(
            "{},{},{},{},{},{},{},{},{},{},{}",
            c(GpuCounter::RaysPrimary),
            c(GpuCounter::RaysRestirInitial),
            c(GpuCounter::RaysRestirSpatial),
            c(GpuCounter::RaysRestirShade),
            c(GpuCounter::PrimaryHits),
            c(GpuCounter::TraceSteps),
            c(GpuCounter::TraceLoads),
            r.candidates,
            c(GpuCounter::GiUpdated),
            c(GpuCounter::RaysGi),
            r.render_scale
        );
        let total = r.gpu_total_ms().map_or(String::new(), |ms| format!("{ms:.4}"));
        let head = format!("{adapter},{},{},{},{},{:.3},{total}", r.case, r.lighting, r.size.0, r.size.1, r.wall_ms);
        if r.passes.is_empty() {
            text += &format!("{head},,,{counts}\n");
        }
        for (pass, ms) in &r.passes {
            text += &format!("{head},{pass},{ms:.4},{counts}\n");
        }
    }
    text
}

pub fn markdown(rows: &[FrameRow], config: &FrameConfig) -> String {
    let ms = |v: Option<f64>| v.map_or("-".into(), |v| format!("{v:.2}"));
    let mut text = format!(
        "# The frame, pass by pass\n\nOn {}. `glowbrick bench --frame`: the game's frame (`RenderSettings::game()`: \
         sun, sky and emitters by Voxel ReSTIR, the GI cache, the denoiser) and the same with emitters only, after \
         {} frames of warm-up, {} frames timed{}. GPU ms are timestamp queries of each pass averaged over the timed \
         frames (`-`: the pass did not run, or no timestamps); wall ms is the whole frame with the GPU waited for, \
         which also holds what no pass times (Bevy's own work, uploads, the readback's copy).\n\n\
         ## GPU time per pass (ms)\n\n| case | lighting | size | {} | sum | wall |\n|---|---|---|{}---|---|\n",
        crate::render::adapter::adapter_name(),
        config.warm_frames,
        config.timed_frames,
        if config.extra.is_empty() { String::new() } else { format!(", with `{}`", config.extra.join(" ")) },
        GROUPS.map(|(_, column)| column).join(" | "),
        "---|".repeat(GROUPS.len())
    );
    for r in rows {
        let groups: Vec<String> = GROUPS.iter().map(|(names, _)| ms(r.gpu_ms_of(names))).collect();
        text += &format!(
            "| {} | {} | {}x{} | {} | {} | {:.1} |\n",
            r.case,
            r.lighting,
            r.size.0,
            r.size.1,
            groups.join(" | "),
            ms(r.gpu_total_ms()),
            r.wall_ms
        );
    }
    text += "\n## Counters (one frame after the timed ones)\n\nRays per pixel of each per-pixel pass (all pixels), \
             the direct light's rays per pixel whose primary ray hit (its primary ray and ReSTIR's rays), the share of such pixels, steps per ray (cells \
             visited at any level of the occupancy hierarchy) and memory loads per ray over those rays, \
             ReSTIR's candidates per hit pixel, and the GI cache's entries updated and brick-grid rays traced (refresh and \
             update passes) in the frame. Below render scale 1 the per-pass rays are per output pixel; the lighting \
             passes' rays (ReSTIR's and the GI cache's) are given per output pixel, and ReSTIR's per render pixel.\n\n\
             | case | lighting | size | scale | primary | initial | spatial | shade | rays / hit pixel | hit share | \
             steps / ray | loads / ray | candidates | GI updated | GI rays | lighting rays / output px | \
             ReSTIR rays / render px |\n\
             |---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n";
    for r in rows {
        let (steps, loads) = r.steps_per_ray();
        let rays: Vec<String> = RAY_BUDGET.iter().map(|&(c, _, _)| format!("{:.2}", r.rays_per_pixel(c))).collect();
        text += &format!(
            "| {} | {} | {}x{} | {} | {} | {:.2} | {:.2} | {:.1} | {:.1} | {} | {} | {} | {:.3} | {:.2} |\n",
            r.case,
            r.lighting,
            r.size.0,
            r.size.1,
            r.render_scale,
            rays.join(" | "),
            r.rays_per_hit_pixel(),
            r.hit_share(),
            steps,
            loads,
            r.candidates,
            r.counters[GpuCounter::GiUpdated as usize],
            r.counters[GpuCounter::RaysGi as usize],
            r.lighting_rays_per_output_pixel(),
            r.restir_rays_per_render_pixel()
        );
    }
    text
}
