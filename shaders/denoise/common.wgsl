// What the denoiser's passes share (render::denoise).
#define_import_path glowbrick::denoise::common

#import glowbrick::frame::Surface

// A history this long (in frames) blends new frames at 1 / MAX_HISTORY; the debug view shows length / this.
const MAX_HISTORY: f32 = 10.0;
// Albedo below this is treated as this when (de)modulating, so a black surface does not divide by zero.
const ALBEDO_FLOOR: f32 = 0.02;

// Whether b lies on a's voxel-face plane: same face axis and sign, same object, same coordinate along the axis.
// Voxel faces are flat, so this is an exact geometry edge stop.
fn same_plane(a: Surface, b: Surface) -> bool {
    let axis = a.face / 2u;
    return b.found && a.face == b.face && a.object == b.object && abs(a.point[axis] - b.point[axis]) < 1e-3;
}
