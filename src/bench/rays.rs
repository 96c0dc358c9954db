//! `glowbrick bench --rays`: the CPU traversal's rays per second, steps and memory loads per ray, for the four
//! kinds of rays a frame traces (primary, shadow to a light, cosine diffuse, sky), the occupancy traversal
//! (`world::traversal::trace_occupancy`) against the plain two-level DDA (`trace`) on the same rays in one run.
//! The GPU walks the same loops (`shaders/lib/traversal.wgsl`, the `traversal` setting); its steps and loads per
//! ray and its pass times are in the frame profile (`bench --frame --set traversal=occupancy`).

use crate::reference::sampling::{Pcg, cosine_direction};
use crate::world::camera::{camera_ray, view_transform, world_from_clip};
use crate::world::occupancy::WALK_LEVELS;
use crate::world::recipe::generated_world;
use crate::world::traversal::{Counts, RAY_OFFSET, Ray, trace_counted, trace_occupancy_counted};
use crate::world::{CameraView, Hit, VoxelWorld};
use bevy::math::{UVec2, UVec3, Vec3};
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// A scene of the bench: a bench scene name (`bench::load_bench_scene`) or `generated-WxHxD`, and its view.
#[derive(Clone, Copy, Debug)]
pub struct RaysCase {
    pub label: &'static str,
    pub scene: &'static str,
    pub view: &'static str,
}

pub const CASES: [RaysCase; 6] = [
    RaysCase { label: "thesis-letters", scene: "thesis-letters", view: "letters1" },
    RaysCase { label: "thesis-cornell", scene: "thesis-cornellbox", view: "cornell1" },
    RaysCase { label: "window-room", scene: "window-room", view: "inside" },
    RaysCase { label: "apartments", scene: "apartments", view: "street" },
    RaysCase { label: "mountain", scene: "mountain", view: "" },
    RaysCase { label: "generated-2048", scene: "generated-2048x256x2048", view: "" },
];

/// The sun direction the sky rays take (towards the sky, as the game's noon sun roughly).
const SKY_DIR: Vec3 = Vec3::new(0.3, 1.0, 0.2);

#[derive(Clone, Copy, Debug)]
pub struct RaysConfig {
    /// Camera rays per scene: width x height pixels.
    pub width: u32,
    pub height: u32,
    /// Timed passes over each ray set per traversal (alternating old and new; the median is kept).
    pub repeats: u32,
}

impl RaysConfig {
    pub fn full() -> Self {
        RaysConfig { width: 320, height: 180, repeats: 5 }
    }

    pub fn quick() -> Self {
        RaysConfig { width: 64, height: 36, repeats: 3 }
    }
}

/// One traversal on one ray set.
#[derive(Clone, Copy, Debug, Default)]
pub struct Measure {
    pub rays_per_second: f64,
    pub steps_per_ray: f64,
    pub loads_per_ray: f64,
    /// Steps per ray by the level of the cell left (`WALK_LEVELS`: edge 1, 2, 4 .. 128 voxels).
    pub levels: [f64; WALK_LEVELS],
}

/// One row: a scene's ray kind, old and new.
#[derive(Clone, Debug)]
pub struct RaysRow {
    pub scene: String,
    pub kind: &'static str,
    pub rays: usize,
    pub hit_share: f64,
    /// Rays whose hit differs between the two (voxel, face or distance): edge ties.
    pub different: usize,
    pub dda: Measure,
    pub occupancy: Measure,
}

/// The rays of one kind, each with its largest distance.
pub struct RaySet {
    pub kind: &'static str,
    pub rays: Vec<(Ray, f32)>,
}

/// The world of a case: `generated-WxHxD` is the default generator at that size.
pub fn case_world(case: &RaysCase) -> Result<(VoxelWorld, CameraView), String> {
    let world = match case.scene.strip_prefix("generated-") {
        Some(size) => {
            let dims: Vec<u32> = size.split('x').filter_map(|s| s.parse().ok()).collect();
            let &[x, y, z] = dims.as_slice() else { return Err(format!("bad generated size '{size}'")) };
            generated_world(1, UVec3::new(x, y, z)).map_err(|e| e.to_string())?
        }
        None => super::load_bench_scene(case.scene)?,
    };
    let view = match case.view {
        "" => world.view(None).cloned().unwrap_or_else(|| world.overview()),
        name => world.view(Some(name)).cloned().ok_or_else(|| format!("{}: no view '{name}'", case.scene))?,
    };
    Ok((world, view))
}

/// Primary rays through every pixel, and from each primary hit a shadow ray to a random emissive voxel (the sky
/// direction in a world without one), a cosine diffuse ray and a sky ray.
pub fn ray_sets(world: &VoxelWorld, view: &CameraView, config: &RaysConfig) -> Vec<RaySet> {
    let (w, h) = (config.width, config.height);
    let transform = view_transform(view);
    let clip = world_from_clip(&transform, view.fov_deg.to_radians(), w, h);
    let mut emitters = Vec::new();
    let emissive: Vec<bool> =
        std::iter::once(false).chain(world.palette.materials.iter().map(|m| m.radiance() != [0.0; 3])).collect();
    world.grid.for_each_solid(|p, m| {
        if emissive.get(m as usize).copied().unwrap_or(false) {
            emitters.push(p);
        }
    });
    let mut rng = Pcg::new(7, 1);
    let mut primary = Vec::new();
    let (mut shadow, mut diffuse, mut sky) = (Vec::new(), Vec::new(), Vec::new());
    for y in 0..h {
        for x in 0..w {
            let ray = camera_ray(clip, view.origin(), UVec2::new(x, y), w, h);
            primary.push((ray, f32::INFINITY));
            let Some(hit) = crate::world::trace(&world.grid, &ray, f32::INFINITY) else { continue };
            let normal = hit.face.normal().as_vec3();
            let at = ray.at(hit.distance) + normal * RAY_OFFSET;
            if emitters.is_empty() {
                shadow.push((Ray::new(at, SKY_DIR), f32::INFINITY));
            } else {
                let target = emitters[rng.next_u32() as usize % emitters.len()];
                let point = target.as_vec3() + Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32());
                let to = point - at;
                shadow.push((Ray::new(at, to), to.length() * 0.999));
            }
            let dir = cosine_direction(normal, rng.next_f32(), rng.next_f32());
            diffuse.push((Ray::new(at, dir), f32::INFINITY));
            sky.push((Ray::new(at, cosine_direction(SKY_DIR.normalize(), rng.next_f32(), 0.05)), f32::INFINITY));
        }
    }
    vec![
        RaySet { kind: "primary", rays: primary },
        RaySet { kind: "shadow", rays: shadow },
        RaySet { kind: "diffuse", rays: diffuse },
        RaySet { kind: "sky", rays: sky },
    ]
}

type Traverse = fn(&crate::world::BrickGrid, &Ray, f32, &mut Counts) -> Option<Hit>;

fn run_set(world: &VoxelWorld, set: &RaySet, traverse: Traverse) -> (Vec<Option<Hit>>, Counts) {
    let mut counts = Counts::default();
    let hits = set.rays.iter().map(|(ray, max)| traverse(&world.grid, ray, *max, &mut counts)).collect();
    (hits, counts)
}

/// Seconds of one pass over the rays with the traversal as the game and the reference call it (no tally).
fn time_set(
    world: &VoxelWorld,
    set: &RaySet,
    uncounted: fn(&crate::world::BrickGrid, &Ray, f32) -> Option<Hit>,
) -> f64 {
    let start = Instant::now();
    let mut found = 0usize;
    for (ray, max) in &set.rays {
        found += uncounted(&world.grid, ray, *max).is_some() as usize;
    }
    std::hint::black_box(found);
    start.elapsed().as_secs_f64()
}

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

/// Measures one case.
pub fn measure_case(case: &RaysCase, config: &RaysConfig) -> Result<Vec<RaysRow>, String> {
    let (world, view) = case_world(case)?;
    let mut rows = Vec::new();
    for set in ray_sets(&world, &view, config) {
        if set.rays.is_empty() {
            continue;
        }
        let n = set.rays.len();
        let (new_hits, new_counts) = run_set(&world, &set, trace_occupancy_counted);
        let (old_hits, old_counts) = run_set(&world, &set, trace_counted);
        let different = new_hits.iter().zip(&old_hits).filter(|(a, b)| a != b).count();
        let hits = new_hits.iter().filter(|h| h.is_some()).count();
        let (mut old_s, mut new_s) = (Vec::new(), Vec::new());
        for _ in 0..config.repeats.max(1) {
            old_s.push(time_set(&world, &set, crate::world::trace));
            new_s.push(time_set(&world, &set, crate::world::traversal::trace_occupancy));
        }
        let measure = |counts: Counts, seconds: f64| Measure {
            rays_per_second: n as f64 / seconds.max(1e-9),
            steps_per_ray: counts.steps as f64 / n as f64,
            loads_per_ray: counts.loads as f64 / n as f64,
            levels: counts.levels.map(|c| c as f64 / n as f64),
        };
        rows.push(RaysRow {
            scene: case.label.to_string(),
            kind: set.kind,
            rays: n,
            hit_share: hits as f64 / n as f64,
            different,
            dda: measure(old_counts, median(old_s)),
            occupancy: measure(new_counts, median(new_s)),
        });
    }
    Ok(rows)
}

/// Runs the cases and writes `rays.md` and `rays.csv` under `out`.
pub fn run_rays_bench(cases: &[RaysCase], config: &RaysConfig, out: &Path) -> Result<Vec<RaysRow>, String> {
    std::fs::create_dir_all(out).map_err(|e| format!("{}: {e}", out.display()))?;
    let mut rows = Vec::new();
    for case in cases {
        let started = Instant::now();
        let case_rows = measure_case(case, config)?;
        eprintln!("rays: {} in {:.1} s", case.label, started.elapsed().as_secs_f64());
        rows.extend(case_rows);
    }
    std::fs::write(out.join("rays.csv"), csv(&rows)).map_err(|e| e.to_string())?;
    std::fs::write(out.join("rays.md"), markdown(&rows, config)).map_err(|e| e.to_string())?;
    Ok(rows)
}

fn csv(rows: &[RaysRow]) -> String {
    let mut s = String::from(
        "scene,kind,rays,hit_share,different_hits,dda_rays_per_s,dda_steps_per_ray,dda_loads_per_ray,\
         occupancy_rays_per_s,occupancy_steps_per_ray,occupancy_loads_per_ray\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "{},{},{},{:.4},{},{:.0},{:.2},{:.2},{:.0},{:.2},{:.2}",
            r.scene,
            r.kind,
            r.rays,
            r.hit_share,
            r.different,
            r.dda.rays_per_second,
            r.dda.steps_per_ray,
            r.dda.loads_per_ray,
            r.occupancy.rays_per_second,
            r.occupancy.steps_per_ray,
            r.occupancy.loads_per_ray
        );
    }
    s
}

fn markdown(rows: &[RaysRow], config: &RaysConfig) -> String {
    let mut s = String::from("# CPU rays: the occupancy traversal against the plain DDA\n\n");
    let _ = writeln!(
        s,
        "`glowbrick bench --rays`: camera rays through {}x{} pixels and, from each hit, a shadow ray to a random \
         emissive voxel (the sky direction without one), a cosine diffuse ray and a sky ray; one CPU thread, both \
         traversals on the same rays in turn, median of {} passes each. Steps: loop iterations (the DDA: a \
         brick or a voxel; the occupancy walk: a cell left, the coarsest its masks prove empty); loads: words read from memory (a mask bit a ray already holds is not one; the plain DDA loads \
         once per step). Different: rays whose hit differs (an edge or corner met within rounding).\n",
        config.width, config.height, config.repeats
    );
    s.push_str(
        "| scene | rays | kind | hit | different | DDA Mrays/s | new Mrays/s | speed-up | DDA steps | new steps | \
         steps ratio | DDA loads | new loads | loads ratio |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {:.0}% | {} | {:.2} | {:.2} | {:.2}x | {:.1} | {:.1} | {:.2}x | {:.1} | {:.1} | {:.2}x |",
            r.scene,
            r.rays,
            r.kind,
            100.0 * r.hit_share,
            r.different,
            r.dda.rays_per_second / 1e6,
            r.occupancy.rays_per_second / 1e6,
            r.occupancy.rays_per_second / r.dda.rays_per_second,
            r.dda.steps_per_ray,
            r.occupancy.steps_per_ray,
            r.dda.steps_per_ray / r.occupancy.steps_per_ray.max(1e-9),
            r.dda.loads_per_ray,
            r.occupancy.loads_per_ray,
            r.dda.loads_per_ray / r.occupancy.loads_per_ray.max(1e-9),
        );
    }
    s.push_str(
        "\nSteps per ray of the occupancy traversal by the edge of the cell left (a hit counts as a voxel; the \
         derived levels are boxes of 2^3 or 3^3 of a mask's children, edge 4 or 6, 16 or 24, 64 or 96):\n\n\
         | scene | kind | 1 | 2 | 4-6 | 8 (brick) | 16-24 | 32 (sector) | 64-96 | 128 (region) |\n\
         |---|---|---|---|---|---|---|---|---|---|\n",
    );
    for r in rows {
        let levels: Vec<String> = r.occupancy.levels.iter().map(|l| format!("{l:.1}")).collect();
        let _ = writeln!(s, "| {} | {} | {} |", r.scene, r.kind, levels.join(" | "));
    }
    s
}
