// Guided GI rays (gi_guiding=on; seed 004's idea, VXPG: send path vertices toward the voxels that carry light).
// VXPG finds those voxels by bounding voxel sampling over the whole scene; here each entry learns them from its
// own rays instead, which the cache traces every frame anyway: a histogram of where its incoming light came
// from, over GUIDE_BINS equal parts of the cosine lobe (GUIDE_ROWS rings of sin^2 theta by GUIDE_COLUMNS
// sectors of azimuth, the unit square that cosine_direction maps onto the hemisphere). An entry's rays are then
// drawn from a mixture of that histogram and the cosine lobe, and each is weighted by the cosine lobe's density
// over the mixture's, so the estimate stays unbiased whatever the histogram holds; the cosine share bounds a ray's
// weight by 1 / COSINE_SHARE. The mixture is piecewise constant on the square, so a ray's point of the square is
// warped through its inverse CDF: the entry's low-discrepancy sequence stays stratified.
//
// The histogram is kept normalised (its bins sum to 1, or all 0 before the entry's first light) in 16-bit floats
// beside the entry's direct light (GiDirect::guide); each frame's bins (the rays' luminance over their density)
// are normalised and blended in at GUIDE_BLEND (a young entry's first frames averaged evenly).
#define_import_path glowbrick::gi::guide

#import glowbrick::gi::cache::gi_direct

// Four rings by four sectors: guided_point picks among four of each (pick_of_four).
const GUIDE_ROWS: u32 = 4u;
const GUIDE_COLUMNS: u32 = 4u;
const GUIDE_BINS: u32 = 16u;
const COSINE_SHARE: f32 = 0.5;
const GUIDE_BLEND: f32 = 0.1;

// This thread's entry's mixture density per bin (mean 1 over the square), and its rays' light per bin this frame.
var<private> guide_density: array<f32, GUIDE_BINS>;
var<private> guide_energy: array<f32, GUIDE_BINS>;

// A point of the unit square drawn from the mixture, its bin and its density there.
struct GuidedPoint {
    u: vec2<f32>,
    bin: u32,
    density: f32,
}

fn guide_bin(u: vec2<f32>) -> u32 {
    let row = min(u32(u.x * f32(GUIDE_ROWS)), GUIDE_ROWS - 1u);
    let column = min(u32(u.y * f32(GUIDE_COLUMNS)), GUIDE_COLUMNS - 1u);
    return row * GUIDE_COLUMNS + column;
}

// Reads the entry's histogram into this thread's mixture density and clears its frame's bins.
fn load_guide(slot: u32) {
    var packed = gi_direct[slot].guide;
    var total = 0.0;
    for (var i = 0u; i < GUIDE_BINS / 2u; i++) {
        let pair = unpack2x16float(packed[i / 4u][i % 4u]);
        guide_density[2u * i] = max(pair.x, 0.0);
        guide_density[2u * i + 1u] = max(pair.y, 0.0);
        total += guide_density[2u * i] + guide_density[2u * i + 1u];
    }
    for (var b = 0u; b < GUIDE_BINS; b++) {
        // No light learnt yet: the cosine lobe alone.
        var learnt = 1.0;
        if total > 0.0 {
            learnt = guide_density[b] * f32(GUIDE_BINS) / total;
        }
        guide_density[b] = COSINE_SHARE + (1.0 - COSINE_SHARE) * learnt;
        guide_energy[b] = 0.0;
    }
}

// Where `u` falls among four masses that sum to 1: which one, and its place within that one (0..1).
struct Pick {
    index: u32,
    within: f32,
}

fn pick_of_four(masses: vec4<f32>, u: f32) -> Pick {
    var below = 0.0;
    var i = 0u;
    for (; i < 3u; i++) {
        if u < below + masses[i] {
            break;
        }
        below += masses[i];
    }
    return Pick(i, clamp((u - below) / masses[i], 0.0, 0.99999));
}

// The mixture's point for the uniform point `u`: the ring by u.x through the rings' masses, then the sector by
// u.y through that ring's (four of each: pick_of_four).
fn guided_point(u: vec2<f32>) -> GuidedPoint {
    var rings = vec4(0.0);
    for (var b = 0u; b < GUIDE_BINS; b++) {
        rings[b / GUIDE_COLUMNS] += guide_density[b];
    }
    let ring = pick_of_four(rings / f32(GUIDE_BINS), u.x);
    let first = ring.index * GUIDE_COLUMNS;
    let sectors = vec4(guide_density[first], guide_density[first + 1u], guide_density[first + 2u], guide_density[first + 3u]);
    let sector = pick_of_four(sectors / rings[ring.index], u.y);
    let point = (vec2(f32(ring.index), f32(sector.index)) + vec2(ring.within, sector.within)) / f32(GUIDE_ROWS);
    let bin = first + sector.index;
    return GuidedPoint(point, bin, guide_density[bin]);
}

// A ray of this frame brought `luminance` (already over its density) through `bin`.
fn guide_record(bin: u32, luminance: f32) {
    guide_energy[bin] += max(luminance, 0.0);
}

// Blends this frame's bins into the entry's histogram: at 1 / (age + 1) while young (the first frame replaces
// whatever the slot held), GUIDE_BLEND after. A frame without light leaves it as it was.
fn store_guide(slot: u32, age: u32) {
    var total = 0.0;
    for (var b = 0u; b < GUIDE_BINS; b++) {
        total += guide_energy[b];
    }
    if !(total > 0.0) || total > 3.0e38 {
        return;
    }
    let weight = max(GUIDE_BLEND, 1.0 / f32(age + 1u));
    var packed = gi_direct[slot].guide;
    for (var i = 0u; i < GUIDE_BINS / 2u; i++) {
        let old = unpack2x16float(packed[i / 4u][i % 4u]);
        let now = vec2(guide_energy[2u * i], guide_energy[2u * i + 1u]) / total;
        packed[i / 4u][i % 4u] = pack2x16float(mix(max(old, vec2(0.0)), now, weight));
    }
    gi_direct[slot].guide = packed;
}
