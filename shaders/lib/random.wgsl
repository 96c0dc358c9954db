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
