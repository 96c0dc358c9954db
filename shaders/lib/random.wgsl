// Random numbers for every pass: the PCG hash and a small generator on top of it.
#define_import_path glowbrick::random

// PCG hash (Jarzynski & Olano 2020).
fn pcg(v: u32) -> u32 {
    let state = v * 747796405u + 2891336453u;
    let word = ((state >> ((state >> 28u) + 4u)) ^ state) * 277803737u;
    return (word >> 22u) ^ word;
}

struct Rng {
    state: u32,
}

// A uniform 32-bit number.
fn rng_next_u32(rng: ptr<function, Rng>) -> u32 {
    (*rng).state = pcg((*rng).state);
    return (*rng).state;
}

// A uniform number in [0, 1) with 24 bits.
fn rng_next(rng: ptr<function, Rng>) -> f32 {
    (*rng).state = pcg((*rng).state);
    return f32((*rng).state >> 8u) * (1.0 / 16777216.0);
}

// Low-discrepancy points for estimates averaged over frames (the GI cache's): point k of a Kronecker sequence,
// shifted per estimate by `rotation`. Any run of consecutive points covers the unit square (or 4D cube) evenly,
// so a blend of the last frames' samples integrates with far less noise than independent random points. Fixed
// point (0.32) keeps k exact to 2^32. In 2D Roberts' R2 (the plastic number's generators). In 4D R2's two
// (first, for a direction) then the golden ratio's and sqrt(2)'s: every 1D and 2D projection of that set
// integrates boxes better than random points, while Roberts' own R4 has 7 a1 within 0.003 of 6, so its first
// coordinate nearly repeats every 7 points and a long run draws its elevations from a handful of values.
fn r2_point(k: u32, rotation: vec2<u32>) -> vec2<f32> {
    let x = vec2(k * 3242174889u, k * 2447445414u) + rotation;
    return vec2<f32>(x >> vec2(8u)) * (1.0 / 16777216.0);
}

fn r4_point(k: u32, rotation: vec4<u32>) -> vec4<f32> {
    let x = vec4(k * 3242174889u, k * 2447445414u, k * 2654435769u, k * 1779033704u) + rotation;
    return vec4<f32>(x >> vec4(8u)) * (1.0 / 16777216.0);
}

// A shift for one estimate's sequence, drawn from its seed.
fn rotation2(seed: u32) -> vec2<u32> {
    return vec2(pcg(seed ^ 0x9E3779B9u), pcg(seed ^ 0x7F4A7C15u));
}

fn rotation4(seed: u32) -> vec4<u32> {
    return vec4(rotation2(seed), pcg(seed ^ 0x94D049BBu), pcg(seed ^ 0xBF58476Du));
}
