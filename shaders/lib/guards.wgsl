// Guards against non-finite values, by the exponent bits: WGSL lets a compiler assume floats are never NaN or
// infinite and fold `x == x` or `abs(x) <= MAX` to true, but it cannot fold a test of the bits.
#define_import_path glowbrick::guards

const EXPONENT_BITS: u32 = 0x7f800000u;

// Neither NaN nor infinite.
fn finite(x: f32) -> bool {
    return (bitcast<u32>(x) & EXPONENT_BITS) != EXPONENT_BITS;
}

fn finite3(v: vec3<f32>) -> bool {
    return finite(v.x) && finite(v.y) && finite(v.z);
}
