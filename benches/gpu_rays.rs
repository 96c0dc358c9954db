//! GPU rays per second, each walk alone: the ray sets of `glowbrick bench --rays` (camera rays, and from each hit
//! a shadow ray to a random emissive voxel, a cosine diffuse ray and a sky ray) traced by a compute shader that
//! calls `trace` of `shaders/lib/traversal.wgsl` once per ray, composed twice: the plain DDA and the occupancy
//! walk (`TRAVERSAL_OCCUPANCY`). No frame around them, so the walks' own throughput shows, on whatever adapter
//! wgpu picks (lavapipe here, a real GPU where one is lent).
//!
//! `cargo bench --bench gpu_rays -- [--size WxH] [--repeats N] [--scenes a,b] [--out DIR]` writes
//! `gpu-rays.md` and `gpu-rays.csv` (default `target/gpu-rays`). Each ray set is dispatched `repeats` times per
//! walk, the walks alternating; the median submission's wall time (dispatch to the GPU finished) gives rays per
//! second. Every GPU hit is checked against the CPU walk's on the same ray, and the GPU's steps and loads per ray
//! are its own counts (they equal the CPU's when the two walks agree step for step).

#[path = "../tests/shared/compose.rs"]
mod compose;
#[path = "../tests/shared/compute.rs"]
mod compute;
#[path = "../tests/shared/gpu_world.rs"]
mod gpu_world;

use bevy::render::renderer::initialize_renderer;
use bevy::render::settings::{WgpuSettings, WgpuSettingsPriority};
use glowbrick::bench::rays::{CASES, RaysCase, RaysConfig, case_world, ray_sets};
use glowbrick::world::traversal::{Counts, trace_counted, trace_occupancy_counted};
use gpu_world::{GpuWorld, world_layout};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::time::Instant;

/// One ray per thread: its hit and its own step and load counts.
const SHADER: &str = "
#import glowbrick::traversal::{trace, trace_steps, trace_loads}

struct BenchRay {
    origin: vec3<f32>,
    max_distance: f32,
    dir: vec3<f32>,
    _pad: f32,
}

struct BenchHit {
    voxel: vec3<i32>,
    found: u32,
    distance: f32,
    steps: u32,
    loads: u32,
    _pad: u32,
}

@group(0) @binding(100) var<storage, read> rays: array<BenchRay>;
@group(0) @binding(101) var<storage, read_write> hits: array<BenchHit>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= arrayLength(&rays) {
        return;
    }
    let ray = rays[id.x];
    let hit = trace(ray.origin, ray.dir, ray.max_distance);
    hits[id.x] = BenchHit(hit.voxel, u32(hit.found), hit.distance, trace_steps, trace_loads, 0u);
}
";

/// Bytes of one `BenchHit`.
const HIT_BYTES: u64 = 32;
/// The shader's largest distance for a ray without one (`INF` of traversal.wgsl).
const FAR: f32 = 3.0e38;

struct Options {
    config: RaysConfig,
    cases: Vec<RaysCase>,
    out: PathBuf,
}

fn options() -> Result<Options, String> {
    let mut config = RaysConfig { width: 320, height: 180, repeats: 5 };
    let mut cases = CASES.to_vec();
    let mut out = PathBuf::from("target/gpu-rays");
    let mut args = std::env::args().skip(1);
    while let Some(arg) = args.next() {
        let mut value = || args.next().ok_or(format!("{arg} needs a value"));
        match arg.as_str() {
            "--size" => {
                let v = value()?;
                let (w, h) = v.split_once('x').ok_or(format!("--size {v}: expected WxH"))?;
                config.width = w.parse().map_err(|_| format!("--size {v}: bad width"))?;
                config.height = h.parse().map_err(|_| format!("--size {v}: bad height"))?;
            }
            "--repeats" => config.repeats = value()?.parse().map_err(|_| "--repeats: expected a count".to_string())?,
            "--scenes" => {
                let wanted = value()?;
                cases = CASES.iter().filter(|c| wanted.split(',').any(|w| w == c.label)).copied().collect();
                if cases.is_empty() {
                    let labels: Vec<_> = CASES.iter().map(|c| c.label).collect();
                    return Err(format!("--scenes {wanted}: none of {}", labels.join(", ")));
                }
            }
            "--out" => out = PathBuf::from(value()?),
            // cargo bench passes --bench to every bench binary.
            "--bench" => {}
            other => return Err(format!("unknown argument {other}")),
        }
    }
    config.repeats = config.repeats.clamp(1, 101);
    Ok(Options { config, cases, out })
}

/// One walk's pipeline.
struct Walk {
    pipeline: wgpu::ComputePipeline,
}

fn layout(device: &wgpu::Device) -> wgpu::BindGroupLayout {
    world_layout(device, "gpu_rays", &[(compute::INPUT_BINDING, true), (compute::OUTPUT_BINDING, false)])
}

fn walk(device: &wgpu::Device, layout: &wgpu::BindGroupLayout, name: &'static str, flags: &[&str]) -> Walk {
    let module = compose::compose_with(&mut compose::composer(), "gpu_rays.wgsl", SHADER, flags);
    Walk { pipeline: compute::pipeline(device, name, module, Some(layout)) }
}

/// A hit read back: the voxel (when found), steps and loads.
#[derive(Clone, Copy, Debug, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
struct GpuHit {
    voxel: [i32; 3],
    found: u32,
    distance: f32,
    steps: u32,
    loads: u32,
    _pad: u32,
}

/// Seconds of one dispatch of `walk` over the `rays` rays, until the GPU is done.
fn dispatch(device: &wgpu::Device, queue: &wgpu::Queue, walk: &Walk, bind_group: &wgpu::BindGroup, rays: u32) -> f64 {
    let mut encoder = device.create_command_encoder(&Default::default());
    compute::record_dispatch(&mut encoder, &walk.pipeline, bind_group, rays);
    let start = Instant::now();
    queue.submit([encoder.finish()]);
    device.poll(wgpu::PollType::Wait { submission_index: None, timeout: None }).expect("the GPU finishes");
    start.elapsed().as_secs_f64()
}

/// The hits the last dispatch wrote.
fn read_hits(device: &wgpu::Device, queue: &wgpu::Queue, hits: &wgpu::Buffer, rays: u32) -> Vec<GpuHit> {
    let bytes = compute::read_buffer(device, queue, hits, u64::from(rays) * HIT_BYTES);
    bytes.chunks_exact(HIT_BYTES as usize).map(bytemuck::pod_read_unaligned).collect()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// One row of the report.
struct Row {
    scene: &'static str,
    kind: &'static str,
    rays: usize,
    /// Per walk (DDA, occupancy): rays per second, steps and loads per ray on the GPU, hits unlike the CPU walk's.
    walks: [(f64, f64, f64, usize); 2],
}

fn main() {
    if let Err(e) = bench() {
        eprintln!("gpu_rays: {e}");
        std::process::exit(1);
    }
}

fn bench() -> Result<(), String> {
    let options = options()?;
    // The adapter's own limits: the 2048-wide world's pool (297 MB) is past wgpu's default 128 MiB binding.
    let settings = WgpuSettings { priority: WgpuSettingsPriority::Functionality, ..Default::default() };
    let backends = settings.backends.ok_or("no wgpu backend")?;
    let resources = bevy::tasks::block_on(initialize_renderer(backends, None, &settings));
    let adapter = resources.2.name.clone();
    let (device, queue) = (resources.0.wgpu_device(), &resources.1);
    let layout = layout(device);
    let walks = [walk(device, &layout, "dda", &[]), walk(device, &layout, "occupancy", &["TRAVERSAL_OCCUPANCY"])];
    eprintln!("gpu_rays: {adapter}");
    let mut rows = Vec::new();
    let mut skipped = Vec::new();
    for case in &options.cases {
        let (mut world, view) = case_world(case)?;
        let sets = ray_sets(&world, &view, &options.config);
        let gpu_world = match GpuWorld::new(device, &mut world) {
            Ok(gpu_world) => gpu_world,
            Err(why) => {
                eprintln!("gpu_rays: {} skipped: {why}", case.label);
                skipped.push(format!("{}: {why}", case.label));
                continue;
            }
        };
        for set in sets.iter().filter(|s| !s.rays.is_empty()) {
            let n = set.rays.len();
            let packed: Vec<f32> = set
                .rays
                .iter()
                .flat_map(|(ray, max)| {
                    let max = if max.is_finite() { *max } else { FAR };
                    [ray.origin.x, ray.origin.y, ray.origin.z, max, ray.dir.x, ray.dir.y, ray.dir.z, 0.0]
                })
                .collect();
            let io = compute::Io::new(device, "gpu_rays", bytemuck::cast_slice(&packed), n as u64 * HIT_BYTES);
            let bind_group = io.bind_group(device, "gpu_rays", &layout, gpu_world.entries());
            // The CPU walks' hits on the same rays, to check the GPU's.
            let cpu = |traverse: fn(
                &glowbrick::world::BrickGrid,
                &glowbrick::world::traversal::Ray,
                f32,
                &mut Counts,
            ) -> Option<glowbrick::world::Hit>| {
                let mut counts = Counts::default();
                set.rays.iter().map(|(ray, max)| traverse(&world.grid, ray, *max, &mut counts)).collect::<Vec<_>>()
            };
            let cpu_hits = [cpu(trace_counted), cpu(trace_occupancy_counted)];
            // One untimed run of each walk first (pipelines and caches warm), whose hits are checked: a walk writes
            // the same hits every run.
            let last = walks.each_ref().map(|walk| {
                dispatch(device, queue, walk, &bind_group, n as u32);
                read_hits(device, queue, &io.output, n as u32)
            });
            let mut seconds = [Vec::new(), Vec::new()];
            for _ in 0..options.config.repeats {
                for (w, walk) in walks.iter().enumerate() {
                    seconds[w].push(dispatch(device, queue, walk, &bind_group, n as u32));
                }
            }
            let measure = |w: usize| {
                let out = &last[w];
                let steps: u64 = out.iter().map(|h| u64::from(h.steps)).sum();
                let loads: u64 = out.iter().map(|h| u64::from(h.loads)).sum();
                let unlike = out
                    .iter()
                    .zip(&cpu_hits[w])
                    .filter(|(g, c)| match c {
                        Some(c) => g.found == 0 || g.voxel != c.voxel.to_array(),
                        None => g.found != 0,
                    })
                    .count();
                (
                    n as f64 / median(seconds[w].clone()).max(1e-9),
                    steps as f64 / n as f64,
                    loads as f64 / n as f64,
                    unlike,
                )
            };
            let row = Row { scene: case.label, kind: set.kind, rays: n, walks: [measure(0), measure(1)] };
            eprintln!(
                "gpu_rays: {} {}: DDA {:.1} Mrays/s, occupancy {:.1} Mrays/s ({:.2}x)",
                row.scene,
                row.kind,
                row.walks[0].0 / 1e6,
                row.walks[1].0 / 1e6,
                row.walks[1].0 / row.walks[0].0
            );
            rows.push(row);
        }
    }
    std::fs::create_dir_all(&options.out).map_err(|e| format!("{}: {e}", options.out.display()))?;
    let write = |name: &str, text: String| {
        let path = options.out.join(name);
        std::fs::write(&path, text).map_err(|e| format!("{}: {e}", path.display()))
    };
    write("gpu-rays.csv", csv(&adapter, &rows))?;
    write("gpu-rays.md", markdown(&adapter, &rows, &skipped, &options.config))?;
    eprintln!("gpu_rays: wrote {}", options.out.join("gpu-rays.md").display());
    Ok(())
}

fn csv(adapter: &str, rows: &[Row]) -> String {
    let mut s = String::from(
        "adapter,scene,kind,rays,dda_rays_per_s,dda_steps_per_ray,dda_loads_per_ray,dda_unlike_cpu,\
         occupancy_rays_per_s,occupancy_steps_per_ray,occupancy_loads_per_ray,occupancy_unlike_cpu\n",
    );
    for r in rows {
        let [d, o] = r.walks;
        let _ = writeln!(
            s,
            "{},{},{},{},{:.0},{:.2},{:.2},{},{:.0},{:.2},{:.2},{}",
            adapter.replace(',', ";"),
            r.scene,
            r.kind,
            r.rays,
            d.0,
            d.1,
            d.2,
            d.3,
            o.0,
            o.1,
            o.2,
            o.3
        );
    }
    s
}

fn markdown(adapter: &str, rows: &[Row], skipped: &[String], config: &RaysConfig) -> String {
    let mut s = format!("# GPU rays: the occupancy walk against the plain DDA, each alone\n\nOn {adapter}. ");
    let _ = writeln!(
        s,
        "`cargo bench --bench gpu_rays`: the ray sets of `glowbrick bench --rays` ({}x{} camera rays, and from each \
         hit a shadow ray to a random emissive voxel, a cosine diffuse ray and a sky ray), one ray per GPU thread in \
         the order the CPU bench makes them (camera rays in scanline order, so each warp's rays are neighbours), \
         both walks in turn, the median of {} submissions each (wall time of a submission until the GPU is done: \
         on a fast GPU the smaller sets are mostly launch overhead). Steps and loads per ray are the GPU's own \
         counts; unlike CPU: hits whose voxel differs from the CPU walk's on the same ray.\n",
        config.width, config.height, config.repeats
    );
    s.push_str(
        "| scene | kind | rays | DDA Mrays/s | occupancy Mrays/s | speed-up | DDA steps | occupancy steps | \
         DDA loads | occupancy loads | unlike CPU (DDA, occupancy) |\n|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let [d, o] = r.walks;
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.2} | {:.2} | {:.2}x | {:.1} | {:.1} | {:.1} | {:.1} | {}, {} |",
            r.scene,
            r.kind,
            r.rays,
            d.0 / 1e6,
            o.0 / 1e6,
            o.0 / d.0,
            d.1,
            o.1,
            d.2,
            o.2,
            d.3,
            o.3
        );
    }
    for why in skipped {
        let _ = writeln!(s, "\nSkipped: {why}.");
    }
    s
}
