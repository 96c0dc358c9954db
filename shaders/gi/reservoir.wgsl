// The GI cache's direct light from the light pool by resampling (gi_reservoirs=on; seed 002, Boissé 2021, whose
// world-space cells keep reservoirs that every path vertex in them shares): each entry keeps a reservoir of light
// samples (gi_direct's reservoir), carried from frame to frame. Per sample it draws GI_CANDIDATES lights by power,
// each a point on one of its cube's faces, resamples them by their unshadowed reflected light (RIS), merges the
// entry's reservoir of the frames before (its M capped at GI_HISTORY frames' worth), and traces one shadow ray to
// the sample kept. A lamp inside a house, one of thousands, is drawn once in many frames, but once drawn it stays
// in the house's entries. Without it (gi_reservoirs=off) an entry draws one light by power a sample (direct.wgsl).
//
// Candidates and targets are those of the cell's centre, the same every frame, so merging frames is resampling
// one target; the sample is shaded and its shadow ray traced at this frame's point of the cell, and what that
// point sees of lights the centre cannot (outside_support_sample) is added by a small RIS of its own. A blocked sample
// keeps its weight: zeroing it (ReSTIR's visibility reuse) darkened a house at night by 5% more than the cache
// without reservoirs, and dropping its history instead brightened it threefold (docs/bench/gi.md).
#define_import_path glowbrick::gi::reservoir

#import glowbrick::lights::{Light, lights, scene, pick_light, power_pick_on, light_size, face_exposed, sees_light_point}
#import glowbrick::traversal::face_normal
#import glowbrick::random::{Rng, rng_next, rng_next_u32}
#import glowbrick::guards::finite
#import glowbrick::constants::PI
#import glowbrick::gi::cache::{gi_direct, GiReservoir}

// Candidates per sample, and the frames' worth of candidates a reservoir may carry (its M at most
// GI_HISTORY x GI_CANDIDATES): enough to keep a rare light, few enough to let a new one in within a few frames.
// The blend of an entry's direct light averages about ten frames' samples, so its noise follows the candidates
// drawn a frame, not the history: 8, 32 and 64 are measured against their cost in docs/bench/gi.md.
const GI_CANDIDATES: u32 = 32u;
const GI_HISTORY: f32 = 20.0;
const NO_LIGHT: u32 = 0xffffffffu;

fn empty_gi_reservoir() -> GiReservoir {
    return GiReservoir(NO_LIGHT, 0u, 0u, 0u, 0.0, 0.0, 0.0, 0.0);
}

fn luminance_of(c: vec3<f32>) -> f32 {
    return dot(c, vec3(0.2126, 0.7152, 0.0722));
}

// The point (u, v) on face `face` of the light's cube.
fn point_on_face(light: Light, face: u32, uv: vec2<f32>) -> vec3<f32> {
    let lo = vec3<f32>(light.min);
    let size = f32(light_size(light));
    let axis = face / 2u;
    var q = lo;
    q[axis] = select(lo[axis], lo[axis] + size, (face & 1u) == 0u);
    q[(axis + 1u) % 3u] += uv.x * size;
    q[(axis + 2u) % 3u] += uv.y * size;
    return q;
}

// Unshadowed radiance a diffuse surface at p (normal n) reflects from the point (u, v) of the light's face, per
// unit of the face's area: albedo/pi Le cos cos / d^2.
fn reflected(p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, light: Light, face: u32, uv: vec2<f32>) -> vec3<f32> {
    let to_light = point_on_face(light, face, uv) - p;
    let d2 = dot(to_light, to_light);
    if d2 <= 1e-8 {
        return vec3(0.0);
    }
    let wi = to_light * inverseSqrt(d2);
    let cos_surface = dot(n, wi);
    let cos_light = -dot(face_normal(face), wi);
    if cos_surface <= 0.0 || cos_light <= 0.0 {
        return vec3(0.0);
    }
    return albedo * light.radiance * (cos_surface * cos_light / (d2 * PI));
}

// A reservoir read back is used only if its light is still the one it sampled (slot and generation) and its
// fields are sane; one that holds no light keeps its M (its candidates found nothing: evidence all the same).
fn validated_gi(r: GiReservoir) -> GiReservoir {
    if !finite(r.w_sum) || !finite(r.m) || !finite(r.big_w) || r.m < 0.0 || r.big_w < 0.0 {
        return empty_gi_reservoir();
    }
    var none = empty_gi_reservoir();
    none.m = r.m;
    if r.slot == NO_LIGHT {
        return none;
    }
    if r.slot >= arrayLength(&lights) || r.face > 5u {
        return empty_gi_reservoir();
    }
    let light = lights[r.slot];
    if light_size(light) == 0 || light.generation != r.generation {
        return none;
    }
    return r;
}

// Streams one weighted input into r: kept with probability weight / w_sum.
fn stream_gi(r: ptr<function, GiReservoir>, input: GiReservoir, weight: f32, m: f32, u: f32) {
    let w = select(0.0, weight, finite(weight) && weight > 0.0);
    (*r).w_sum += w;
    (*r).m += m;
    if w > 0.0 && u * (*r).w_sum < w {
        (*r).slot = input.slot;
        (*r).generation = input.generation;
        (*r).face = input.face;
        (*r).uv = input.uv;
    }
}

// The exposed faces of a light's cube whose front sides see p, in axis order.
struct FacesSeen {
    faces: array<u32, 3>,
    count: u32,
}

fn faces_seen(light: Light, p: vec3<f32>) -> FacesSeen {
    let size = f32(light_size(light));
    let lo = vec3<f32>(light.min);
    var seen = FacesSeen(array<u32, 3>(0u, 0u, 0u), 0u);
    for (var a = 0u; a < 3u; a++) {
        if p[a] > lo[a] + size && face_exposed(light, a * 2u) {
            seen.faces[seen.count] = a * 2u;
            seen.count++;
        } else if p[a] < lo[a] && face_exposed(light, a * 2u + 1u) {
            seen.faces[seen.count] = a * 2u + 1u;
            seen.count++;
        }
    }
    return seen;
}

// A light by power (or uniformly), one of its exposed faces that look at p uniformly, a point on it uniform in
// area, and the pdf of that point (per unit area); pdf 0 where the light shows p no face.
struct LightPoint {
    slot: u32,
    face: u32,
    uv: vec2<f32>,
    pdf: f32,
}

fn draw_light_point(p: vec3<f32>, rng: ptr<function, Rng>) -> LightPoint {
    let picked = pick_light(scene.light_count, power_pick_on(), rng_next_u32(rng), rng_next(rng));
    let u_face = rng_next(rng);
    let uv = vec2(rng_next(rng), rng_next(rng));
    let light = lights[picked.slot];
    let size = f32(light_size(light));
    let seen = faces_seen(light, p);
    if light_size(light) == 0 || seen.count == 0u {
        return LightPoint(picked.slot, 0u, uv, 0.0);
    }
    let face = seen.faces[min(u32(u_face * f32(seen.count)), seen.count - 1u)];
    return LightPoint(picked.slot, face, uv, picked.pdf / (f32(seen.count) * size * size));
}

// One candidate into r, drawn for the cell's centre c; resampling weight target / pdf.
fn stream_candidate(r: ptr<function, GiReservoir>, c: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, Rng>) {
    let drawn = draw_light_point(c, rng);
    let u_keep = rng_next(rng);
    if drawn.pdf <= 0.0 {
        (*r).m += 1.0;
        return;
    }
    let light = lights[drawn.slot];
    let target_value = luminance_of(reflected(c, n, albedo, light, drawn.face, drawn.uv));
    let candidate = GiReservoir(drawn.slot, light.generation, drawn.face, pack2x16unorm(drawn.uv), 0.0, 0.0, 0.0, 0.0);
    stream_gi(r, candidate, target_value / drawn.pdf, 1.0, u_keep);
}

// Light that p sees and the reservoir can never hold: points of a light whose target at the cell's centre c is
// zero. A coarse cell's faces lie in several planes (a ceiling and the underside of a lamp hanging from it), so
// its centre can miss a lamp that its other faces see; the reservoir alone then loses that light for good. Its
// own small RIS: OUTSIDE_CANDIDATES power-drawn points seen from p, each counted only outside the reservoir's
// support, resampled by their unshadowed light at p, one shadow ray for the one kept (traced only when one
// counts). With the reservoir's estimate of the rest, the sum is unbiased. Only coarse cells need it.
const OUTSIDE_CANDIDATES: u32 = 4u;

fn outside_support_sample(c: vec3<f32>, p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, rng: ptr<function, Rng>) -> vec3<f32> {
    var w_sum = 0.0;
    var kept = LightPoint(0u, 0u, vec2(0.0), 0.0);
    var kept_target = 0.0;
    for (var i = 0u; i < OUTSIDE_CANDIDATES; i++) {
        let drawn = draw_light_point(p, rng);
        let u_keep = rng_next(rng);
        if drawn.pdf <= 0.0 {
            continue;
        }
        let light = lights[drawn.slot];
        if luminance_of(reflected(c, n, albedo, light, drawn.face, drawn.uv)) > 0.0 {
            continue;
        }
        let target_value = luminance_of(reflected(p, n, albedo, light, drawn.face, drawn.uv));
        let w = target_value / drawn.pdf;
        if !(finite(w) && w > 0.0) {
            continue;
        }
        w_sum += w;
        if u_keep * w_sum < w {
            kept = drawn;
            kept_target = target_value;
        }
    }
    if w_sum <= 0.0 {
        return vec3(0.0);
    }
    let light = lights[kept.slot];
    let big_w = w_sum / (f32(OUTSIDE_CANDIDATES) * kept_target);
    if finite(big_w) && sees_light_point(p, n, light, point_on_face(light, kept.face, kept.uv)) {
        return reflected(p, n, albedo, light, kept.face, kept.uv) * big_w;
    }
    return vec3(0.0);
}

// One estimate of the light-pool light a diffuse surface at p (normal n) reflects, for the entry in `slot` whose
// cell's centre is c: new candidates, the entry's reservoir so far, one shadow ray. Writes the reservoir back.
// `coarse`: the cell spans more than one voxel face, so p may see lights its centre cannot (one face's centre
// and its points see the same lights: the planes of a light's faces lie on whole voxels).
fn reservoir_sample(slot: u32, c: vec3<f32>, p: vec3<f32>, n: vec3<f32>, albedo: vec3<f32>, coarse: bool, rng: ptr<function, Rng>) -> vec3<f32> {
    if scene.light_count == 0u {
        return vec3(0.0);
    }
    var r = empty_gi_reservoir();
    for (var i = 0u; i < GI_CANDIDATES; i++) {
        stream_candidate(&r, c, n, albedo, rng);
    }
    let before = validated_gi(gi_direct[slot].reservoir);
    let carried = min(before.m, GI_HISTORY * f32(GI_CANDIDATES));
    var weight = 0.0;
    if before.slot != NO_LIGHT {
        let target_before = luminance_of(reflected(c, n, albedo, lights[before.slot], before.face, unpack2x16unorm(before.uv)));
        weight = target_before * before.big_w * carried;
    }
    stream_gi(&r, before, weight, carried, rng_next(rng));
    var estimate = vec3(0.0);
    r.big_w = 0.0;
    if r.slot != NO_LIGHT && r.m > 0.0 {
        let light = lights[r.slot];
        let uv = unpack2x16unorm(r.uv);
        let unshadowed = reflected(p, n, albedo, light, r.face, uv);
        let target_value = luminance_of(reflected(c, n, albedo, light, r.face, uv));
        if target_value > 0.0 {
            r.big_w = r.w_sum / (r.m * target_value);
            if finite(r.big_w) && sees_light_point(p, n, light, point_on_face(light, r.face, uv)) {
                estimate = unshadowed * r.big_w;
            }
        }
    }
    gi_direct[slot].reservoir = r;
    if coarse {
        estimate += outside_support_sample(c, p, n, albedo, rng);
    }
    return estimate;
}
