//! The pixels where the GPU's camera ray and the CPU reference's hit the same voxel face.
//!
//! Both cast one ray through each pixel's centre, but in different float arithmetic: where a ray passes within
//! rounding of a voxel edge, one renderer may hit the voxel and the other its neighbour. On the thesis' letters
//! (lamps one voxel thick, set into dark walls) such a pixel is a lamp (luminance ~4.5) in one image and a dark
//! wall in the other: a geometry difference of one pixel, not a lighting error, yet each adds about 0.035 to a
//! 320x180 image's relMSE, as much as all of ReSTIR's lighting error. The bench states its equal-time ratio
//! over the pixels both see alike as well as over all of them, with the count left out.

use crate::headless::{HeadlessOptions, HeadlessRenderer};
use crate::image_io::LinearImage;
use crate::settings::RenderSettings;
use crate::world::{CameraView, VoxelWorld, camera_ray, trace, view_transform, world_from_clip};
use bevy::math::{IVec3, UVec2};

/// One flag per pixel: the GPU's primary hit (a `debug=hit` frame: voxel and face + 1, or alpha 0 for a miss)
/// equals the CPU traversal's of the same pixel.
pub fn same_hit_pixels(world: &VoxelWorld, view: &CameraView, width: u32, height: u32) -> Result<Vec<bool>, String> {
    let settings = RenderSettings::default().with_pairs(&["debug=hit".to_string()])?;
    let options = HeadlessOptions { width, height, settings, ..Default::default() };
    let hits = HeadlessRenderer::new(world.clone(), view, &options)?.render(1)?;
    let transform = view_transform(view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), width, height);
    Ok((0..width * height)
        .map(|i| {
            let ray = camera_ray(m, transform.translation, UVec2::new(i % width, i / width), width, height);
            let p = hits.pixels[i as usize];
            match trace(&world.grid, &ray, f32::INFINITY) {
                Some(hit) => {
                    let voxel = IVec3::new(p[0] as i32, p[1] as i32, p[2] as i32);
                    p[3] > 0.0 && voxel == hit.voxel && p[3] as u8 == hit.face.0 + 1
                }
                None => p[3] == 0.0,
            }
        })
        .collect())
}

/// The pixels of `image` where `keep` holds, as one row (metrics compare pixel by pixel, so two images masked
/// alike compare as their kept pixels).
pub fn kept(image: &LinearImage, keep: &[bool]) -> LinearImage {
    let pixels: Vec<[f32; 4]> = image.pixels.iter().zip(keep).filter(|(_, k)| **k).map(|(p, _)| *p).collect();
    LinearImage { width: pixels.len() as u32, height: 1, pixels }
}
