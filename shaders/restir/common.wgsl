// Voxel ReSTIR's shared pieces (seed 000, DESIGN.md "Voxel ReSTIR"): the reservoir, light samples in area
// measure (a point on one face of a light's cube) or point measure (the cube's centre), the target function, the
// visibility test and the resampling steps. The passes: initial.wgsl (candidates), temporal.wgsl (their
// visibility, temporal reuse), spatial.wgsl, shade.wgsl.
#define_import_path glowbrick::restir::common

#import glowbrick::world::{materials, voxel_at, albedo_at}
#import glowbrick::traversal::{trace_scene, face_normal}
#import glowbrick::lights::{power_pick_on, Light, lights, scene, alias_table, pick_light, light_contains, light_size,
    face_exposed, light_at_voxel, light_in_box}
#import glowbrick::random::{Rng, rng_next, rng_next_u32, pcg}
#import glowbrick::counters::counters
#import glowbrick::guards::finite
#import glowbrick::constants::{RAY_OFFSET, PI, RESTIR_POINT, RESTIR_UNBIASED, RESTIR_ONE_RAY, RESTIR_LOCAL,
    RESTIR_LIGHT_TILES, LIGHT_TILES, LIGHT_TILE_SIZE, COUNT_RESERVOIR_RESETS, NO_COLUMN, NEAR_FACE}
#import glowbrick::frame::{restir_flag, frame, view, Surface, luminance, surface_voxel, render_size}

// 32 bytes. `face` is the light cube's face (0 +X, 1 -X, ... as the traversal numbers faces) or POINT_FACE,
// `uv` the point on it (pack2x16unorm). `w_sum` is only meaningful while a pass streams candidates; `big_w` is the
// unbiased contribution weight of the sample.
struct Reservoir {
    slot: u32,
    generation: u32,
    face: u32,
    uv: u32,
    w_sum: f32,
    m: f32,
    big_w: f32,
    // Target of the sample at the pixel that owns the reservoir, this frame (reuse reads it instead of
    // recomputing it).
    target_value: f32,
}

// Written by initial.wgsl (candidates), then temporal.wgsl (visibility, temporal reuse); read by spatial.wgsl.
@group(1) @binding(6) var<storage, read_write> reservoirs_temporal: array<Reservoir>;
// Written by spatial.wgsl, read by shade.wgsl (which zeroes occluded samples) and next frame's temporal reuse.
@group(1) @binding(7) var<storage, read_write> reservoirs_final: array<Reservoir>;

// A light of this frame's light tiles (tiles.wgsl): a copy of the slot, the slot, the pick's probability.
struct TileLight {
    light: Light,
    slot: u32,
    pdf: f32,
}

// LIGHT_TILES tiles of LIGHT_TILE_SIZE lights, written by tiles.wgsl, read by initial.wgsl's candidates.
@group(1) @binding(8) var<storage, read_write> light_tiles: array<TileLight>;
// No tile: the candidates pick from the alias table themselves (light_tiles=off).
const NO_TILE: u32 = 0xffffffffu;

const NO_LIGHT: u32 = 0xffffffffu;
const POINT_FACE: u32 = 6u;

fn empty_reservoir() -> Reservoir {
    return Reservoir(NO_LIGHT, 0u, 0u, 0u, 0.0, 0.0, 0.0, 0.0);
}

// A reservoir read from memory is used only if its fields are sane and its light is still the one it sampled:
// a freed or reused slot has another generation, so a removed light is never shaded.
// A non-finite field is also counted (COUNT_RESERVOIR_RESETS, read back by the stress run).
// A reservoir that holds no light keeps its M: "M candidates found nothing to light this pixel" is evidence the
// next merge must weigh like any other. Dropping it (M = 0) made the confidence weights depend on the outcome,
// so temporal reuse forgot its zeros and brightened scenes whose candidates are mostly occluded.
fn validated(r: Reservoir) -> Reservoir {
    if !finite(r.w_sum) || !finite(r.m) || !finite(r.big_w) || !finite(r.target_value) {
        atomicAdd(&counters[COUNT_RESERVOIR_RESETS], 1u);
        return empty_reservoir();
    }
    if r.slot == NO_LIGHT && r.m >= 0.0 {
        var none = empty_reservoir();
        none.m = r.m;
        return none;
    }
    if r.slot >= arrayLength(&lights) || r.m < 0.0 || r.big_w < 0.0 || r.face > POINT_FACE {
        return empty_reservoir();
    }
    let light = lights[r.slot];
    if light_size(light) == 0 || light.generation != r.generation {
        return empty_reservoir();
    }
    return r;
}

// The sampled point: on face `face` of the light's cube at (u, v) along the face's two other axes, or the centre.
fn light_point(light: Light, face: u32, uv: vec2<f32>) -> vec3<f32> {
    let lo = vec3<f32>(light.min);
    let size = f32(light_size(light));
    if face == POINT_FACE {
        return lo + vec3(0.5 * size);
    }
    let axis = face / 2u;
    var q = lo;
    q[axis] = select(lo[axis], lo[axis] + size, (face & 1u) == 0u);
    q[(axis + 1u) % 3u] += uv.x * size;
    q[(axis + 2u) % 3u] += uv.y * size;
    return q;
}

// Shading point data every pass needs.
struct Shading {
    point: vec3<f32>,
    normal: vec3<f32>,
    albedo: vec3<f32>,
}

fn shading(s: Surface) -> Shading {
    return Shading(s.point, face_normal(s.face), albedo_at(s.material, surface_voxel(s), s.object));
}

// Unshadowed reflected radiance from the sample, per unit of the sample's measure: area (albedo/pi Le cos cos/d^2)
// or, for the centre, per light (the projected area of the cube's exposed faces towards the point stands in for
// A cos_l).
fn unshadowed(x: Shading, light: Light, face: u32, uv: vec2<f32>) -> vec3<f32> {
    let q = light_point(light, face, uv);
    let to_light = q - x.point;
    let d2 = dot(to_light, to_light);
    if d2 <= 1e-8 {
        return vec3(0.0);
    }
    let wi = to_light * inverseSqrt(d2);
    let cos_surface = dot(x.normal, wi);
    var cos_area = 0.0;
    if face == POINT_FACE {
        // The faces that face the point and touch air: a buried face emits nothing (the reference skips it too).
        // On axis a the face towards the point is -a when the light lies at +a (face index 2a + 1).
        // Only point mode's pipelines hold this: in area mode a centre sample (one kept from before a switch of
        // mode) is worth nothing, and every candidate's target would pay for the loop on software Vulkan.
        if restir_flag(RESTIR_POINT) {
            var projected = 0.0;
            for (var axis = 0u; axis < 3u; axis++) {
                if face_exposed(light, axis * 2u + select(0u, 1u, wi[axis] > 0.0)) {
                    projected += abs(wi[axis]);
                }
            }
            let size = f32(light_size(light));
            cos_area = projected * size * size;
        }
    } else {
        cos_area = -dot(face_normal(face), wi);
    }
    if cos_surface <= 0.0 || cos_area <= 0.0 {
        return vec3(0.0);
    }
    return x.albedo * light.radiance * (cos_surface * cos_area / (d2 * PI));
}

fn target_of(x: Shading, r: Reservoir) -> f32 {
    if r.slot == NO_LIGHT {
        return 0.0;
    }
    return luminance(unshadowed(x, lights[r.slot], r.face, unpack2x16unorm(r.uv)));
}

// A shadow ray towards the sample; visible iff the first voxel hit belongs to the light's cube (no step cap).
fn visible(x: Shading, light: Light, face: u32, uv: vec2<f32>) -> bool {
    let origin = x.point + x.normal * RAY_OFFSET;
    let to_light = light_point(light, face, uv) - origin;
    let d = length(to_light);
    if d <= 1e-6 {
        return false;
    }
    let hit = trace_scene(origin, to_light / d, d + 1.0);
    return hit.found && hit.object == 0u && light_contains(light, hit.voxel);
}

fn reservoir_visible(x: Shading, r: Reservoir) -> bool {
    return r.slot != NO_LIGHT && visible(x, lights[r.slot], r.face, unpack2x16unorm(r.uv));
}

// How much of the light cube [lo, lo + size]^3 face `face` shows p, for choosing among its faces: the face's area
// times the cosine at its centre over the squared distance (its solid angle far away), at most a hemisphere's. A
// face is chosen in proportion to it and the candidate's pdf uses the same shares, so any positive share keeps the
// estimate unbiased; the exact solid angle (two atan2 per face) cost a quarter of each candidate for the same error
// (docs/bench/why.md).
fn face_share(p: vec3<f32>, lo: vec3<f32>, size: f32, face: u32) -> f32 {
    let axis = face / 2u;
    var centre = lo + vec3(0.5 * size);
    centre[axis] += select(-0.5 * size, 0.5 * size, (face & 1u) == 0u);
    let to_centre = centre - p;
    let d2 = max(dot(to_centre, to_centre), 1e-8);
    return min(size * size * abs(to_centre[axis]) * inverseSqrt(d2) / d2, 2.0 * PI);
}

// A point of face `face` of the cube [lo, lo + size]^3 drawn uniformly in the solid angle the face subtends from
// p (the spherical-rectangle parametrisation of Urena, Fajardo and King 2013), as (u, v) on the face, with that
// solid angle; solid angle 0 when it is too small to sample this way in f32. Beside a lamp lying on the floor a
// uniform point on its side face weighs cos cos / d^2, unbounded (fireflies that temporal reuse keeps); drawn by
// solid angle the weight is the receiver's cosine times the solid angle. src/reference/spherical_rect.rs is the
// CPU twin.
struct FaceSample {
    uv: vec2<f32>,
    solid_angle: f32,
}

fn sample_face_solid_angle(p: vec3<f32>, lo: vec3<f32>, size: f32, face: u32, u: vec2<f32>) -> FaceSample {
    let axis = face / 2u;
    var corner = lo - p;
    corner[axis] += select(0.0, size, (face & 1u) == 0u);
    // The face's frame: x and y along its two other axes, z away from p so the face lies at z = z0 < 0.
    let z0 = -abs(corner[axis]);
    let x0 = corner[(axis + 1u) % 3u];
    let y0 = corner[(axis + 2u) % 3u];
    let x1 = x0 + size;
    let y1 = y0 + size;
    let n0 = normalize(vec3(0.0, z0, -y0));
    let n1 = normalize(vec3(-z0, 0.0, x1));
    let n2 = normalize(vec3(0.0, -z0, y1));
    let n3 = normalize(vec3(z0, 0.0, -x0));
    let g0 = acos(clamp(-dot(n0, n1), -1.0, 1.0));
    let g1 = acos(clamp(-dot(n1, n2), -1.0, 1.0));
    let g2 = acos(clamp(-dot(n2, n3), -1.0, 1.0));
    let g3 = acos(clamp(-dot(n3, n0), -1.0, 1.0));
    let k = 2.0 * PI - g2 - g3;
    let solid_angle = g0 + g1 - k;
    if !(solid_angle > 1e-4) || !finite(solid_angle) {
        return FaceSample(vec2(0.0), 0.0);
    }
    let b0 = n0.z;
    let b1 = n2.z;
    let au = u.x * solid_angle + k;
    let fu = (cos(au) * b0 - b1) / sin(au);
    let cu = clamp(select(-1.0, 1.0, fu > 0.0) * inverseSqrt(fu * fu + b0 * b0), -1.0, 1.0);
    let xu = clamp(-(cu * z0) * inverseSqrt(max(1.0 - cu * cu, 1e-12)), x0, x1);
    let d = sqrt(xu * xu + z0 * z0);
    let h0 = y0 * inverseSqrt(d * d + y0 * y0);
    let h1 = y1 * inverseSqrt(d * d + y1 * y1);
    let hv = h0 + u.y * (h1 - h0);
    let yv = select(y1, clamp(hv * d * inverseSqrt(max(1.0 - hv * hv, 1e-12)), y0, y1), hv * hv < 1.0 - 1e-6);
    let uv = clamp(vec2((xu - x0) / size, (yv - y0) / size), vec2(0.0), vec2(1.0));
    return FaceSample(uv, solid_angle);
}

struct Candidate {
    r: Reservoir,
    // Source pdf: per unit area of the point for a far face, of the (light, face) pair for a near one (its point is
    // drawn after resampling, draw_point), per light in point mode.
    pdf: f32,
}

// The lights touching the air in front of a face, found once per pixel: a lamp lying beside a surface lights it
// most (its contribution grows without bound at the edge), yet the power pick finds it once in N lights, so
// among 10^5 lamps one candidate in thousands of frames found it and that pixel flashed. Candidates are a mixture:
// with probability LOCAL_SHARE one of these lights uniformly, else the power pick; every candidate's pdf is the
// mixture's, so the estimate stays unbiased.
const LOCAL_LIGHTS: u32 = 8u;
const LOCAL_SHARE: f32 = 0.25;

struct LocalLights {
    slots: array<u32, LOCAL_LIGHTS>,
    // The power pick's probability of each (its alias entry's pdf, or 1 / n when picking uniformly).
    pick_pdfs: array<f32, LOCAL_LIGHTS>,
    count: u32,
}

// The lights among the 3x3 voxels around the air voxel in front of the face and the 3x3 beyond them (17 voxels:
// the face's own layer holds nothing that can shine on it). None with local_lights off or a single light.
fn local_lights(x: Shading) -> LocalLights {
    var local: LocalLights;
    local.count = 0u;
    if !restir_flag(RESTIR_LOCAL) || scene.light_count <= 1u {
        return local;
    }
    let n = vec3<i32>(round(x.normal));
    let front = vec3<i32>(floor(x.point + 0.5 * x.normal));
    let axis = select(select(2u, 1u, n.y != 0), 0u, n.x != 0);
    var t = vec3(0);
    t[(axis + 1u) % 3u] = 1;
    var b = vec3(0);
    b[(axis + 2u) % 3u] = 1;
    // Most surfaces have no light near them, and the one or two bricks the 17 voxels lie in say so. One loop whose
    // length says it: software Vulkan (Mesa 22.3's lavapipe) runs a loop's body at least once under a mask however
    // few lanes enter, so a fixed 3 x 3 x 2 scan behind an early return cost every pixel all 18 lookups.
    let corner_a = front - t - b;
    let corner_b = front + n + t + b;
    let cells = select(0, 18, light_in_box(min(corner_a, corner_b), max(corner_a, corner_b)));
    for (var cell = 0; cell < cells; cell++) {
        // Layer by layer, rows of three across t then b, as (layer, du, dv) from (0, -1, -1).
        let layer = cell / 9;
        let du = (cell / 3) % 3 - 1;
        let dv = cell % 3 - 1;
        if layer == 0 && du == 0 && dv == 0 {
            continue;
        }
        let q = front + layer * n + du * t + dv * b;
        let material = voxel_at(q);
        if material == 0u || all(materials[material].radiance.rgb == vec3(0.0)) {
            continue;
        }
        let column = light_at_voxel(q);
        if column == NO_COLUMN {
            continue;
        }
        let slot = alias_table[column].slot;
        var known = false;
        for (var i = 0u; i < local.count; i++) {
            known = known || local.slots[i] == slot;
        }
        if !known && local.count < LOCAL_LIGHTS {
            local.slots[local.count] = slot;
            local.pick_pdfs[local.count] =
                select(1.0 / f32(scene.light_count), alias_table[column].pdf, power_pick_on());
            local.count++;
        }
    }
    return local;
}

// The light tile a 4x4 block of pixels draws its candidates from this frame, or NO_TILE with light_tiles=off.
// Blocks of 8x8 read a little faster still on lavapipe, but their 64 pixels drew all their power picks from one
// tile's lights, and that correlation raised the one-frame error; at 4x4 it is that of the alias table
// (docs/bench/why.md).
fn pixel_tile(pixel: vec2<u32>) -> u32 {
    if !restir_flag(RESTIR_LIGHT_TILES) {
        return NO_TILE;
    }
    let block = pixel / 4u;
    return pcg((block.x | (block.y << 16u)) ^ pcg(frame.frame + 0x3C6EF372u)) % LIGHT_TILES;
}

// A light picked for a candidate: its slot, the probability of picking it, and the light itself.
struct CandidateLight {
    slot: u32,
    pdf: f32,
    light: Light,
}

// One draw of the power pick (or the uniform one): a light of the pixel's tile, or from the alias table.
fn power_pick(tile: u32, rng: ptr<function, Rng>) -> CandidateLight {
    // (The setting, not `tile != NO_TILE`: a constant the compiler folds, so only one path is in the shader.)
    if restir_flag(RESTIR_LIGHT_TILES) {
        let t = light_tiles[tile * LIGHT_TILE_SIZE + (rng_next_u32(rng) & (LIGHT_TILE_SIZE - 1u))];
        return CandidateLight(t.slot, t.pdf, t.light);
    }
    let picked = pick_light(scene.light_count, power_pick_on(), rng_next_u32(rng), rng_next(rng));
    return CandidateLight(picked.slot, picked.pdf, lights[picked.slot]);
}

// A light by the mixture of the power pick and the local lights, with the mixture's probability.
// One call site of each pick: software Vulkan runs every branch's code, so a second copy of the power pick would
// cost every candidate its time again (the same draws as two branches would take).
fn pick_candidate_light(local: ptr<function, LocalLights>, tile: u32, rng: ptr<function, Rng>) -> CandidateLight {
    let count = (*local).count;
    var from_local = false;
    if count > 0u {
        from_local = rng_next(rng) < LOCAL_SHARE;
    }
    var picked: CandidateLight;
    if from_local {
        let i = min(u32(rng_next(rng) * f32(count)), count - 1u);
        let slot = (*local).slots[i];
        picked = CandidateLight(slot, (*local).pick_pdfs[i], lights[slot]);
    } else {
        picked = power_pick(tile, rng);
    }
    if count > 0u {
        var local_pdf = 0.0;
        for (var i = 0u; i < count; i++) {
            local_pdf = select(local_pdf, 1.0 / f32(count), (*local).slots[i] == picked.slot);
        }
        picked.pdf = (1.0 - LOCAL_SHARE) * picked.pdf + LOCAL_SHARE * local_pdf;
    }
    return picked;
}

// Whether the point on face `face` is drawn by solid angle (within NEAR_FACE face sizes of its centre), not by area.
fn near_face(x: Shading, light: Light, face: u32) -> bool {
    return distance(x.point, light_point(light, face, vec2(0.5))) < f32(NEAR_FACE) * f32(light_size(light));
}

// A near face's target, which a candidate is resampled by before its point exists: the light's reflected luminance
// through the face, albedo/pi Le times the receiver's cosine towards the face's centre times the face's share
// (face_share). It must be positive wherever the face lights the pixel at all: a face whose centre lies below the
// pixel's horizon while an edge rises above it gets a quarter of that edge's cosine.
fn face_target(x: Shading, light: Light, face: u32, share: f32) -> f32 {
    let size = f32(light_size(light));
    let to_centre = light_point(light, face, vec2(0.5)) - x.point;
    // The receiver's normal lies on one axis; along it the face spans its size unless it is the face's own axis.
    let height = dot(x.normal, to_centre);
    let span = select(0.5 * size, 0.0, abs(x.normal[face / 2u]) > 0.5);
    let highest = height + span;
    if !(highest > 0.0) {
        return 0.0;
    }
    let cos_surface = min(max(height, 0.25 * highest) * inverseSqrt(max(dot(to_centre, to_centre), 1e-8)), 1.0);
    return luminance(x.albedo * light.radiance) * cos_surface * share / PI;
}

// One candidate: a light from the alias table (power or uniform) or the local lights, then, in area mode, one of
// the exposed faces that see the shading point in proportion to its share (face_share) and, far from the face, a
// point on it uniform in area; in point mode the centre.
//
// Near a face its point is drawn by solid angle, and that draw (four acos) cost a fifth of the candidates' pass
// when every candidate made it: software Vulkan runs it for every candidate under a mask where any lane of the
// group is near a light. So a near candidate is the (light, face) pair with target face_target x p(point | pair):
// its resampling weight face_target / p(pair) does not depend on the point, which is drawn only for the chosen one
// (draw_point), from the random numbers the candidate kept. The target is still a function of the sample alone
// (which faces are near depends only on the pixel and the face), so the reservoir's W stays unbiased.
fn sample_candidate(x: Shading, local: ptr<function, LocalLights>, tile: u32, rng: ptr<function, Rng>) -> Candidate {
    var c = Candidate(empty_reservoir(), 0.0);
    let picked = pick_candidate_light(local, tile, rng);
    let u_face = rng_next(rng);
    let uv = vec2(rng_next(rng), rng_next(rng));
    let light = picked.light;
    if light_size(light) == 0 {
        return c;
    }
    c.r.slot = picked.slot;
    c.r.generation = light.generation;
    if restir_flag(RESTIR_POINT) {
        c.r.face = POINT_FACE;
        c.r.uv = pack2x16unorm(vec2(0.5));
        c.pdf = picked.pdf;
        c.r.target_value = luminance(unshadowed(x, light, POINT_FACE, vec2(0.5)));
        return c;
    }
    let lo = vec3<f32>(light.min);
    let size = f32(light_size(light));
    var omega: array<f32, 3>;
    var faces: array<u32, 3>;
    var total = 0.0;
    for (var axis = 0u; axis < 3u; axis++) {
        var face = 6u;
        if x.point[axis] > lo[axis] + size && face_exposed(light, axis * 2u) {
            face = axis * 2u;
        } else if x.point[axis] < lo[axis] && face_exposed(light, axis * 2u + 1u) {
            face = axis * 2u + 1u;
        }
        faces[axis] = face;
        omega[axis] = 0.0;
        if face != 6u {
            omega[axis] = face_share(x.point, lo, size, face);
            total += omega[axis];
        }
    }
    if !(total > 0.0) || !finite(total) {
        return c;
    }
    // Pick a face by its share of the total solid angle.
    var pick = u_face * total;
    var chosen = 0u;
    for (var axis = 0u; axis < 3u; axis++) {
        if omega[axis] > 0.0 {
            chosen = axis;
            if pick < omega[axis] {
                break;
            }
            pick -= omega[axis];
        }
    }
    c.r.face = faces[chosen];
    c.r.uv = pack2x16unorm(uv);
    let pair_pdf = picked.pdf * (omega[chosen] / total);
    if near_face(x, light, c.r.face) {
        c.pdf = pair_pdf;
        c.r.target_value = face_target(x, light, c.r.face, omega[chosen]);
    } else {
        c.pdf = pair_pdf / (size * size);
        c.r.target_value = luminance(unshadowed(x, light, c.r.face, unpack2x16unorm(c.r.uv)));
    }
    return c;
}

// The chosen candidate's point where it was left to be drawn (a near face): uniform in the solid angle the face
// subtends, from the random numbers the candidate kept in `uv` (uniform in area where that angle is too small to
// sample in f32). Returns the point's pdf per unit area, or 1 where the candidate's target was already its point's
// (a far face, point mode, no light).
fn draw_point(x: Shading, r: ptr<function, Reservoir>) -> f32 {
    if (*r).slot == NO_LIGHT || (*r).face == POINT_FACE {
        return 1.0;
    }
    let light = lights[(*r).slot];
    if !near_face(x, light, (*r).face) {
        return 1.0;
    }
    let lo = vec3<f32>(light.min);
    let size = f32(light_size(light));
    let near = sample_face_solid_angle(x.point, lo, size, (*r).face, unpack2x16unorm((*r).uv));
    if !(near.solid_angle > 0.0) {
        return 1.0 / (size * size);
    }
    // Quantise first so the pdf is that of the point actually stored.
    (*r).uv = pack2x16unorm(near.uv);
    let to_point = light_point(light, (*r).face, unpack2x16unorm((*r).uv)) - x.point;
    let d2 = dot(to_point, to_point);
    let cos_light = -dot(face_normal((*r).face), to_point) * inverseSqrt(d2);
    // Uniform in solid angle, per unit area: cos / (d^2 x solid angle).
    return max(cos_light, 0.0) / (d2 * near.solid_angle);
}

// Streams one weighted input into `r`: kept with probability weight / w_sum. Returns whether it was kept.
fn stream(r: ptr<function, Reservoir>, input: Reservoir, weight: f32, m: f32, u: f32) -> bool {
    let w = select(0.0, weight, finite(weight) && weight > 0.0);
    (*r).w_sum += w;
    (*r).m += m;
    if w > 0.0 && u * (*r).w_sum < w {
        let w_sum = (*r).w_sum;
        let total_m = (*r).m;
        *r = input;
        (*r).w_sum = w_sum;
        (*r).m = total_m;
        return true;
    }
    return false;
}

// The contribution weight W = w_sum / p_hat(y), and the target stored. Reuse puts its MIS weights into the
// resampling weights, so w_sum already holds them.
fn finalize(r: ptr<function, Reservoir>, target_value: f32) {
    (*r).big_w = select(0.0, (*r).w_sum / target_value, target_value > 0.0);
    if !finite((*r).big_w) {
        (*r).big_w = 0.0;
    }
    (*r).target_value = target_value;
}

// Pairwise MIS (after Bitterli's dissertation, sec. 9.1.3), with confidence weights M: the pixel's own reservoir
// c is the canonical input and each of the k neighbours i is weighed against it alone:
//   m_i(x) = (M_i + M_c/k) / M_total * M_i p_i(x) / (M_i p_i(x) + (M_c/k) p_c(x)),   m_c(x) = 1 - sum_i m_i(x).
// The weights sum to 1 wherever some input can produce x and none is negative, so the reuse is unbiased when
// p_i includes input i's visibility (the unbiased variant: two rays per neighbour) and only slightly biased where
// visibility differs when it does not (the biased variant: no rays). Unlike the thesis' 1/M, the weight falls
// with p_i, cancelling a neighbour's large W where its own target was small, so a sample that was a firefly at
// one pixel does not spread to its neighbours and stay for the whole history (measured in docs/bench/restir.md).
fn pair_weight(m_i: f32, p_i: f32, m_c_share: f32, p_c: f32, share: f32) -> f32 {
    let denominator = m_i * p_i + m_c_share * p_c;
    return select(0.0, share * m_i * p_i / denominator, denominator > 0.0 && finite(denominator));
}

fn unbiased() -> bool {
    return restir_flag(RESTIR_UNBIASED);
}

// Whether the MIS weight of a pixel's own sample tests that the other input sees it: in both unbiased variants.
// That ray is what keeps the weights summing to 1 where visibility differs; the second ray of `unbiased` only
// keeps occluded samples from being picked (noise, not bias).
fn own_sample_rays() -> bool {
    return restir_flag(RESTIR_UNBIASED | RESTIR_ONE_RAY);
}

// Random numbers per pixel, pass and frame.
fn pixel_rng(pixel: vec2<u32>, pass_salt: u32) -> Rng {
    let size = render_size();
    return Rng(pcg(pixel.x + size.x * pixel.y) ^ pcg(frame.frame * 0x9E3779B9u + pass_salt));
}
