// The scene's lighting on the GPU (group 2): this frame's sun (or moon) and sky and their sampling, the light pool's slots and power alias
// table (src/lights), and next-event estimation with one light sample and a shadow ray. Mirrors src/reference (Scene::direct_sample) so GPU and CPU estimate the same
// integral: pick a light (power or uniform), a uniform point on a cube face that sees the point, one shadow ray.
#define_import_path glowbrick::lights

#import glowbrick::traversal::{trace_scene, INF}
#import glowbrick::world::{world_info, stored_index, brick_in_window}
#import glowbrick::random::{Rng, rng_next, rng_next_u32}
#import glowbrick::constants::{RAY_OFFSET, PI, LIGHT_FACES_SHIFT, LIGHT_SIZE_MASK, BRICK_SIZE, BRICK_SHIFT, NO_COLUMN, LIGHT_HASH_X,
    LIGHT_HASH_Y, LIGHT_HASH_Z, LIGHT_HASH_MIX_1, LIGHT_HASH_MIX_2, KEY_GENERIC, KEY_LIGHTING, KEY_SHADOWS, KEY_POWER_PICK}

struct Light {
    min: vec3<i32>,
    // Edge in voxels (below LIGHT_FACES_SHIFT; 0 marks a free slot) and the faces that touch air (bit
    // LIGHT_FACES_SHIFT + f for face f as the traversal numbers faces: 0 +X, 1 -X, ...). Read through light_size
    // and face_exposed.
    size_faces: i32,
    radiance: vec3<f32>,
    generation: u32,
}

struct AliasEntry {
    threshold: f32,
    alias_column: u32,
    slot: u32,
    pdf: f32,
}

// SceneLighting in src/render/gpu_types.rs: the same for every camera and for the GI cache.
struct SceneLighting {
    // xyz: unit direction towards the sun; w: 1 when the sun is on.
    sun: vec4<f32>,
    sun_radiance: vec4<f32>,
    sky_zenith: vec4<f32>,
    sky_horizon: vec4<f32>,
    // LIGHTING_*: full (disk, sky and emitters), emitters only (ReSTIR or next-event estimation), or sun (debug).
    mode: u32,
    // 1: pick lights by power (alias table); 0: uniformly.
    power_pick: u32,
    light_count: u32,
    shadows: u32,
}

@group(2) @binding(0) var<storage, read> lights: array<Light>;
@group(2) @binding(1) var<storage, read> alias_table: array<AliasEntry>;
@group(2) @binding(2) var<uniform> scene: SceneLighting;

// The lighting settings: the pipeline's own (constants.wgsl, KEY_*) or the uniform's in a generic build.
fn lighting_mode() -> u32 {
    if KEY_LIGHTING == KEY_GENERIC {
        return scene.mode;
    }
    return KEY_LIGHTING;
}

fn shadows_on() -> bool {
    if KEY_SHADOWS == KEY_GENERIC {
        return scene.shadows != 0u;
    }
    return KEY_SHADOWS != 0u;
}

fn power_pick_on() -> bool {
    if KEY_POWER_PICK == KEY_GENERIC {
        return scene.power_pick == 1u;
    }
    return KEY_POWER_PICK == 1u;
}
// Light cube -> alias column, open addressing at load <= 1/2 (src/lights/index.rs builds it; an entry is only the
// column, the key is checked against the light itself), then one bit per brick of the world (top-grid order, 32
// a word): the brick holds a light (src/lights/bricks.rs). Word 0 is the index's capacity, its entries follow
// from word 1, the bricks' words after them (render::scene::lights::gpu_light_index).
@group(2) @binding(3) var<storage, read> light_index: array<u32>;

// Sky radiance in direction `dir`, not counting the disk (lights::daylight::Daylight::sky).
fn sky(dir: vec3<f32>) -> vec3<f32> {
    let up = clamp(dir.y * 0.5 + 0.5, 0.0, 1.0);
    return mix(scene.sky_horizon.rgb, scene.sky_zenith.rgb, up);
}

// The sun's (or moon's) disk's cone, 1 - cos(radius).
fn disk_cone() -> f32 {
    return scene.sun_radiance.w;
}

// What a camera ray that leaves the world sees with lighting=full: the sky, and the disk itself (its irradiance
// over its solid angle) where the ray points into it (Daylight::background).
fn background(dir: vec3<f32>) -> vec3<f32> {
    var disk = vec3(0.0);
    if scene.sun.w > 0.0 && dot(dir, scene.sun.xyz) >= 1.0 - disk_cone() {
        disk = scene.sun_radiance.rgb / (2.0 * disk_cone());
    }
    return sky(dir) + disk;
}

// An orthonormal frame (t, b, n) around unit n (Duff et al. 2017), as lights::daylight::frame.
fn frame_of(n: vec3<f32>) -> mat3x3<f32> {
    let sign = select(-1.0, 1.0, n.z >= 0.0);
    let a = -1.0 / (sign + n.z);
    let b = n.x * n.y * a;
    return mat3x3(vec3(1.0 + sign * n.x * n.x * a, sign * b, -sign * n.x), vec3(b, sign + n.y * n.y * a, -n.y), n);
}

// A uniform direction in the disk's cone (pdf 1 / solid angle). Two draws of `rng` whether or not the disk is up.
fn disk_direction(rng: ptr<function, Rng>) -> vec3<f32> {
    let u1 = rng_next(rng);
    let u2 = rng_next(rng);
    let cos_theta = 1.0 - u1 * disk_cone();
    let sin_theta = sqrt(max(1.0 - cos_theta * cos_theta, 0.0));
    let phi = 2.0 * PI * u2;
    return normalize(frame_of(scene.sun.xyz) * vec3(sin_theta * cos(phi), sin_theta * sin(phi), cos_theta));
}

// Whether the disk is up and in front of a surface of normal n (the disk's light there is then non-zero where
// it is not in shadow).
fn disk_faces(n: vec3<f32>) -> bool {
    return scene.sun.w > 0.0 && dot(n, scene.sun.xyz) > 0.0;
}

// One shadow ray toward a point of the disk from p: 1 where it reaches the sky (or shadows are off), 0 where the
// world blocks it.
fn disk_visible(p: vec3<f32>, n: vec3<f32>, dir: vec3<f32>) -> f32 {
    if shadows_on() && trace_scene(p + n * RAY_OFFSET, dir, INF).found {
        return 0.0;
    }
    return 1.0;
}

// The disk's light on a diffuse surface of normal n that sees all of it, over the albedo: its irradiance, the
// cosine taken at the disk's centre (the disk is a fraction of a degree wide).
fn disk_irradiance(n: vec3<f32>) -> vec3<f32> {
    if !disk_faces(n) {
        return vec3(0.0);
    }
    return scene.sun_radiance.rgb * dot(n, scene.sun.xyz);
}

// One sample of the light the disk gives a diffuse surface at p (normal n): a uniform direction in its cone
// (pdf 1 / solid angle, which cancels against the radiance's 1 / solid angle) and one shadow ray.
fn disk_sample(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, Rng>) -> vec3<f32> {
    let dir = disk_direction(rng);
    if scene.sun.w <= 0.0 {
        return vec3(0.0);
    }
    let cos_surface = dot(n, dir);
    if cos_surface <= 0.0 || disk_visible(p, n, dir) == 0.0 {
        return vec3(0.0);
    }
    return albedo * scene.sun_radiance.rgb * cos_surface;
}

// One cosine-distributed ray from a diffuse surface at p: the sky it reaches if it leaves the world (cos / pi
// cancels against the pdf). The sky's direct light where no GI cache brings it.
fn sky_sample(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, Rng>) -> vec3<f32> {
    let r = sqrt(rng_next(rng));
    let phi = 2.0 * PI * rng_next(rng);
    let local = vec3(r * cos(phi), r * sin(phi), sqrt(max(1.0 - r * r, 0.0)));
    let dir = normalize(frame_of(n) * local);
    if trace_scene(p + n * RAY_OFFSET, dir, INF).found {
        return vec3(0.0);
    }
    return albedo * sky(dir);
}

struct PickedLight {
    slot: u32,
    pdf: f32,
}

// The high word of r x n (32x32 -> 64 bits, from 16-bit halves): a column among n that every column gets
// floor or ceil of 2^32 / n codes of, as `lights::alias::column_of` on the CPU. Not floor(u * n) with a float u:
// its 24 bits give columns unequal shares at large n and cannot reach past 2^24 (docs/bench/why.md).
fn column_of(r: u32, n: u32) -> u32 {
    let r_lo = r & 0xffffu;
    let r_hi = r >> 16u;
    let n_lo = n & 0xffffu;
    let n_hi = n >> 16u;
    let lo_lo = r_lo * n_lo;
    let hi_lo = r_hi * n_lo;
    let lo_hi = r_lo * n_hi;
    let hi_hi = r_hi * n_hi;
    // Middle column of partial products, with the carry out of the low 32 bits.
    let middle = (lo_lo >> 16u) + (hi_lo & 0xffffu) + (lo_hi & 0xffffu);
    return hi_hi + (hi_lo >> 16u) + (lo_hi >> 16u) + (middle >> 16u);
}

// A light by power (alias table) or uniformly over the live lights (the table lists them all).
fn pick_light(count: u32, power: bool, r_column: u32, u_pick: f32) -> PickedLight {
    let column = column_of(r_column, count);
    let entry = alias_table[column];
    if !power {
        return PickedLight(entry.slot, 1.0 / f32(count));
    }
    if u_pick < entry.threshold {
        return PickedLight(entry.slot, entry.pdf);
    }
    let other = alias_table[entry.alias_column];
    return PickedLight(other.slot, other.pdf);
}

// The home entry of a light cube (src/lights/index.rs, light_hash): multiply-xor, then murmur3's finaliser.
fn light_hash(min: vec3<i32>, size: i32) -> u32 {
    var h = (u32(min.x) * LIGHT_HASH_X) ^ (u32(min.y) * LIGHT_HASH_Y) ^ (u32(min.z) * LIGHT_HASH_Z) ^ u32(size);
    h ^= h >> 16u;
    h *= LIGHT_HASH_MIX_1;
    h ^= h >> 13u;
    h *= LIGHT_HASH_MIX_2;
    return h ^ (h >> 16u);
}

// The alias column of the light whose cube is (min, size), or NO_COLUMN.
fn find_light(min: vec3<i32>, size: i32) -> u32 {
    let mask = light_index[0] - 1u;
    var i = light_hash(min, size) & mask;
    for (var probe = 0u; probe <= mask; probe++) {
        let column = light_index[1u + i];
        if column == NO_COLUMN {
            break;
        }
        let light = lights[alias_table[column].slot];
        if all(light.min == min) && light_size(light) == size {
            return column;
        }
        i = (i + 1u) & mask;
    }
    return NO_COLUMN;
}

// The alias column of the light that voxel p belongs to: a one-voxel light, or its brick's brick light.
fn light_at_voxel(p: vec3<i32>) -> u32 {
    let column = find_light(p, 1);
    if column != NO_COLUMN {
        return column;
    }
    return find_light(p & vec3(-BRICK_SIZE), BRICK_SIZE);
}

// Whether brick b holds a light: one whose cube lies in it, so no voxel outside such bricks belongs to a light.
fn brick_has_light(b: vec3<i32>) -> bool {
    if !brick_in_window(b) {
        return false;
    }
    let i = stored_index(b, world_info.bricks, BRICK_SHIFT);
    return ((light_index[1u + light_index[0] + (i >> 5u)] >> (i & 31u)) & 1u) == 1u;
}

// Whether any brick overlapping the voxel box [lo, hi] holds a light.
fn light_in_box(lo: vec3<i32>, hi: vec3<i32>) -> bool {
    let b0 = lo >> vec3(3u);
    let b1 = hi >> vec3(3u);
    for (var z = b0.z; z <= b1.z; z++) {
        for (var y = b0.y; y <= b1.y; y++) {
            for (var x = b0.x; x <= b1.x; x++) {
                if brick_has_light(vec3(x, y, z)) {
                    return true;
                }
            }
        }
    }
    return false;
}

fn light_size(light: Light) -> i32 {
    return light.size_faces & i32(LIGHT_SIZE_MASK);
}

fn face_exposed(light: Light, face: u32) -> bool {
    return ((u32(light.size_faces) >> (LIGHT_FACES_SHIFT + face)) & 1u) == 1u;
}

fn light_contains(light: Light, voxel: vec3<i32>) -> bool {
    return all(voxel >= light.min) && all(voxel < light.min + vec3(light_size(light)));
}

// Whether a surface at p (normal n) sees the point q of a light: the first thing a shadow ray from just off the
// surface meets toward q is the light's own cube (a moving object or another voxel in between blocks it).
fn sees_light_point(p: vec3<f32>, n: vec3<f32>, light: Light, q: vec3<f32>) -> bool {
    let origin = p + n * RAY_OFFSET;
    let to_light = q - origin;
    let d = length(to_light);
    let hit = trace_scene(origin, to_light / max(d, 1e-6), d + 1.0);
    return hit.found && hit.object == 0u && light_contains(light, hit.voxel);
}

// One next-event-estimation sample of the radiance reflected by a diffuse surface at p (normal n).
fn direct_sample(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, count: u32, power: bool, rng: ptr<function, Rng>) -> vec3<f32> {
    if count == 0u {
        return vec3(0.0);
    }
    let picked = pick_light(count, power, rng_next_u32(rng), rng_next(rng));
    let light = lights[picked.slot];
    if light_size(light) == 0 {
        return vec3(0.0);
    }
    let lo = vec3<f32>(light.min);
    let size = f32(light_size(light));
    let hi = lo + vec3(size);
    // The exposed cube faces whose front sides see p; choose one uniformly.
    var axes: array<u32, 3>;
    var signs: array<f32, 3>;
    var faces = 0u;
    for (var a = 0u; a < 3u; a++) {
        if p[a] > hi[a] && face_exposed(light, a * 2u) {
            axes[faces] = a;
            signs[faces] = 1.0;
            faces++;
        } else if p[a] < lo[a] && face_exposed(light, a * 2u + 1u) {
            axes[faces] = a;
            signs[faces] = -1.0;
            faces++;
        }
    }
    let u_face = rng_next(rng);
    let u = rng_next(rng);
    let v = rng_next(rng);
    if faces == 0u {
        return vec3(0.0);
    }
    let f = min(u32(u_face * f32(faces)), faces - 1u);
    let axis = axes[f];
    let sign = signs[f];
    var q = lo;
    q[axis] = select(lo[axis], hi[axis], sign > 0.0);
    q[(axis + 1u) % 3u] = lo[(axis + 1u) % 3u] + u * size;
    q[(axis + 2u) % 3u] = lo[(axis + 2u) % 3u] + v * size;
    var light_normal = vec3(0.0);
    light_normal[axis] = sign;
    let pdf_area = 1.0 / (f32(faces) * size * size);

    let to_light = q - p;
    let d2 = dot(to_light, to_light);
    if d2 <= 1e-12 {
        return vec3(0.0);
    }
    let d = sqrt(d2);
    let wi = to_light / d;
    let cos_surface = dot(n, wi);
    let cos_light = -dot(light_normal, wi);
    if cos_surface <= 0.0 || cos_light <= 0.0 {
        return vec3(0.0);
    }
    if !sees_light_point(p, n, light, q) {
        return vec3(0.0);
    }
    let pdf = max(picked.pdf * pdf_area, 1e-30);
    return albedo * light.radiance * (cos_surface * cos_light / d2 / pdf / PI);
}
