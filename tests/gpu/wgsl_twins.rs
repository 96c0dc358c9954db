//! WGSL functions that have a Rust twin, run on the GPU on the same inputs as the Rust and compared, so neither
//! side changes alone: the light index's hash (exactly) and the spherical-rectangle sampler (within f32's
//! reach of the CPU reference's f64).
//!
//! Each test composes a small compute shader that imports the library function as the passes do, runs it once
//! per input and reads the results back.

use crate::{compose, compute};
use bevy::math::{IVec3, Vec3};
use bevy::render::renderer::initialize_renderer;
use bevy::render::settings::WgpuSettings;
use glowbrick::lights::index::light_hash;
use glowbrick::reference::sampling::Pcg;
use glowbrick::reference::spherical_rect::SphericalRect;
use glowbrick::world::grid::BRICK_SIZE;

/// Runs `source`'s `main` (workgroups of 64) once per input element: `input` at group 0 binding 100, the
/// results, `output_bytes` of them, from binding 101. The bindings lie past every binding the libraries declare,
/// and the pipeline's layout holds only the ones `main` uses.
fn run_compute(source: &str, input: &[u8], elements: u32, output_bytes: u64) -> Vec<u8> {
    let module = compose::compose(&mut compose::composer(), "wgsl_twins.wgsl", source);
    let settings = WgpuSettings::default();
    let backends = settings.backends.expect("a wgpu backend");
    let resources = bevy::tasks::block_on(initialize_renderer(backends, None, &settings));
    let (device, queue) = (resources.0.wgpu_device(), &resources.1);
    let pipeline = compute::pipeline(device, "wgsl_twins", module, None);
    let io = compute::Io::new(device, "wgsl_twins", input, output_bytes);
    let bind_group = io.bind_group(device, "wgsl_twins", &pipeline.get_bind_group_layout(0), Vec::new());
    compute::run_and_read(device, queue, &pipeline, &bind_group, elements, &io)
}

fn words(bytes: &[u8]) -> impl Iterator<Item = u32> + '_ {
    bytes.chunks_exact(4).map(|w| u32::from_le_bytes([w[0], w[1], w[2], w[3]]))
}

const LIGHT_HASH_SHADER: &str = "
#import glowbrick::lights::light_hash

@group(0) @binding(100) var<storage, read> cubes: array<vec4<i32>>;
@group(0) @binding(101) var<storage, read_write> hashes: array<u32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&cubes) {
        hashes[id.x] = light_hash(cubes[id.x].xyz, cubes[id.x].w);
    }
}
";

/// `light_hash` in `shaders/lib/lights.wgsl` and in `src/lights/index.rs` agree on every bit: the shader probes
/// the table the CPU built, so one differing bit loses lights. Corners anywhere in i32 (negative ones too: the
/// casts to u32 must wrap alike), one-voxel and brick lights.
pub fn the_light_hash_matches_the_cpu_light_index() {
    let mut rng = Pcg::new(7, 0);
    let mut cubes: Vec<[i32; 4]> = vec![[0, 0, 0, 1], [-1, -1, -1, BRICK_SIZE], [i32::MIN, i32::MAX, 0, 1]];
    while cubes.len() < 512 {
        let mut coordinate = || {
            let word = rng.next_u32() as i32;
            // Half of them world-sized, half across all of i32.
            if cubes.len().is_multiple_of(2) { word % 5000 } else { word }
        };
        let min = [coordinate(), coordinate(), coordinate()];
        let size = if rng.next_u32().is_multiple_of(2) { 1 } else { BRICK_SIZE };
        cubes.push([min[0], min[1], min[2], size]);
    }
    let input: Vec<u8> = cubes.iter().flatten().flat_map(|v| v.to_le_bytes()).collect();
    let output = run_compute(LIGHT_HASH_SHADER, &input, cubes.len() as u32, 4 * cubes.len() as u64);
    let mut wrong = 0;
    for (&[x, y, z, size], gpu) in cubes.iter().zip(words(&output)) {
        let cpu = light_hash(IVec3::new(x, y, z), size);
        if gpu != cpu {
            wrong += 1;
            eprintln!("light_hash(({x}, {y}, {z}), {size}): GPU {gpu:#010x}, CPU {cpu:#010x}");
        }
    }
    assert_eq!(wrong, 0, "{wrong} of {} hashes differ", cubes.len());
}

const FACE_SAMPLE_SHADER: &str = "
#import glowbrick::restir::common::sample_face_solid_angle

// Per case three vec4: (p, face), (lo, size), (u, -, -).
@group(0) @binding(100) var<storage, read> cases: array<vec4<f32>>;
@group(0) @binding(101) var<storage, read_write> samples: array<vec4<f32>>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < arrayLength(&cases) / 3u {
        let a = cases[3u * id.x];
        let b = cases[3u * id.x + 1u];
        let u = cases[3u * id.x + 2u].xy;
        let s = sample_face_solid_angle(a.xyz, b.xyz, b.w, u32(a.w), u);
        samples[id.x] = vec4(s.uv, s.solid_angle, 0.0);
    }
}
";

/// One input of `sample_face_solid_angle`: the shading point, the light cube (lowest corner, edge), the face
/// (0 +X, 1 -X, ... as the traversal numbers them) and the uniform pair.
struct FaceCase {
    p: Vec3,
    lo: Vec3,
    size: f32,
    face: usize,
    u: [f32; 2],
}

impl FaceCase {
    /// The CPU reference's sample of the same face: its (u, v) on the face and the solid angle, `None` when it
    /// declines the rectangle.
    fn cpu(&self) -> Option<([f32; 2], f32)> {
        let axis = self.face / 2;
        let (a, b) = ((axis + 1) % 3, (axis + 2) % 3);
        let mut corner = self.lo;
        if self.face.is_multiple_of(2) {
            corner[axis] += self.size;
        }
        let (mut edge_a, mut edge_b) = (Vec3::ZERO, Vec3::ZERO);
        edge_a[a] = self.size;
        edge_b[b] = self.size;
        let rect = SphericalRect::new(self.p, corner, edge_a, edge_b)?;
        let point = rect.sample(self.u[0], self.u[1]) - corner;
        Some(([point[a] / self.size, point[b] / self.size], rect.solid_angle as f32))
    }
}

/// Largest differences allowed between the GPU's f32 sampler and the CPU's f64 one, over points from 0.05 to
/// NEAR_FACE face sizes from the face's centre and at least 0.02 face sizes off its plane (the range where
/// candidates are drawn this way, less the nearly edge-on views f32 cannot resolve). Vulkan lets `acos` be
/// thousands of ulp off, so the GPU's corner angles carry an absolute error (lavapipe: solid angles up to 1.6e-3
/// off, relative, 3.3e-4 at the median); a point drawn within a solid angle S then moves by about that error over
/// S, in face sizes (lavapipe: at most 5.2e-4 sr / S beyond 2e-3). A changed formula on either side moves the
/// samples by a sizeable part of the face.
const SOLID_ANGLE_TOLERANCE: f32 = 5e-3;
fn uv_tolerance(solid_angle: f32) -> f32 {
    2e-3 + 1e-3 / solid_angle
}

/// `sample_face_solid_angle` in `shaders/restir/common.wgsl` draws the point the CPU reference
/// (`src/reference/spherical_rect.rs`) draws from the same uniforms, with the same solid angle: the two sides
/// are one algorithm written twice, and a change to one alone fails here.
pub fn the_spherical_rectangle_sampler_matches_the_cpu_reference() {
    let near_face = glowbrick::reference::sampling::NEAR_FACE as f32;
    let mut rng = Pcg::new(11, 0);
    let mut cases = Vec::new();
    while cases.len() < 600 {
        let size = [1.0, 2.0, 8.0][(rng.next_u32() % 3) as usize];
        let lo = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()).map(|c| (c * 200.0 - 100.0).floor());
        let face = (rng.next_u32() % 6) as usize;
        let axis = face / 2;
        let mut centre = lo + Vec3::splat(0.5 * size);
        centre[axis] = if face.is_multiple_of(2) { lo[axis] + size } else { lo[axis] };
        let direction = Vec3::new(rng.next_f32(), rng.next_f32(), rng.next_f32()) * 2.0 - 1.0;
        if direction.length() < 0.1 {
            continue;
        }
        let distance = (0.05 + rng.next_f32() * (near_face - 0.05)) * size;
        let p = centre + direction.normalize() * distance;
        if (p[axis] - centre[axis]).abs() < 0.02 * size {
            continue;
        }
        let case = FaceCase { p, lo, size, face, u: [rng.next_f32(), rng.next_f32()] };
        if case.cpu().is_some_and(|(_, solid_angle)| solid_angle > 1e-3) {
            cases.push(case);
        }
    }
    let input: Vec<u8> = cases
        .iter()
        .flat_map(|c| [c.p.extend(c.face as f32), c.lo.extend(c.size), bevy::math::Vec4::new(c.u[0], c.u[1], 0.0, 0.0)])
        .flat_map(|v| v.to_array())
        .flat_map(f32::to_le_bytes)
        .collect();
    let output = run_compute(FACE_SAMPLE_SHADER, &input, cases.len() as u32, 16 * cases.len() as u64);
    let gpu: Vec<f32> = words(&output).map(f32::from_bits).collect();
    let (mut worst_solid_angle, mut worst_uv) = (0.0f32, 0.0f32);
    let mut wrong = 0;
    for (case, gpu) in cases.iter().zip(gpu.chunks_exact(4)) {
        let (uv, solid_angle) = case.cpu().expect("kept only cases the CPU samples");
        let solid_angle_error = (gpu[2] - solid_angle).abs() / solid_angle;
        let uv_error = (gpu[0] - uv[0]).abs().max((gpu[1] - uv[1]).abs());
        worst_solid_angle = worst_solid_angle.max(solid_angle_error);
        worst_uv = worst_uv.max(uv_error);
        if !(solid_angle_error <= SOLID_ANGLE_TOLERANCE && uv_error <= uv_tolerance(solid_angle)) {
            wrong += 1;
            eprintln!(
                "p {} lo {} size {} face {} u {:?}: GPU uv ({}, {}) solid angle {}, CPU uv {uv:?} solid angle \
                 {solid_angle}",
                case.p, case.lo, case.size, case.face, case.u, gpu[0], gpu[1], gpu[2]
            );
        }
    }
    eprintln!(
        "{} cases: worst solid-angle error {worst_solid_angle:.2e} (relative), worst uv error {worst_uv:.2e}",
        cases.len()
    );
    assert_eq!(wrong, 0, "{wrong} of {} samples differ", cases.len());
}
