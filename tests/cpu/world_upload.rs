//! The renderer's upload staging: the first frame uploads the whole world, later frames only the dirty bricks.

use bevy::prelude::*;
use glowbrick::render::scene::world::{UploadState, WorldUpload, stage_world_upload};
use glowbrick::world::recipe::load_scene;
use glowbrick::world::{Edit, VoxelWorld};

fn app_with(world: VoxelWorld) -> App {
    let mut app = App::new();
    app.insert_resource(world)
        .init_resource::<UploadState>()
        .init_resource::<WorldUpload>()
        .add_systems(Update, stage_world_upload);
    app
}

#[test]
fn first_frame_is_full_then_only_dirty_bricks() {
    let mut app = app_with(load_scene("test-room").unwrap());
    app.update();
    let upload = app.world().resource::<WorldUpload>().clone();
    assert!(upload.full.is_some() && upload.materials.is_some());
    // Nothing changed: nothing to send.
    app.update();
    assert!(app.world().resource::<WorldUpload>().is_empty());
    // One placed voxel: one top cell, one pooled brick and its masks.
    app.world_mut().resource_mut::<VoxelWorld>().apply(Edit::Place { at: IVec3::new(9, 9, 9), material: 1 }).unwrap();
    app.update();
    let upload = app.world().resource::<WorldUpload>().clone();
    assert!(upload.full.is_none() && upload.materials.is_none());
    let brick = app.world().resource::<VoxelWorld>().grid.brick_index(IVec3::ONE) as u32;
    assert_eq!(upload.top_cells.iter().map(|c| c.0).collect::<Vec<_>>(), vec![brick]);
    assert_eq!(upload.bricks.len(), 1);
    assert_eq!(upload.bricks[0].1[1 + 8 * (1 + 8)], 1, "the placed voxel is in the uploaded brick");
    // The top cell, the brick's voxels, and the occupancy masks of the brick, its sector and its region, then the
    // 8 words of the brick's voxel mask, the grid's: the voxel's local (1, 1, 1) is bit 1 + 4 + 16 of its first
    // quadrant.
    assert_eq!(upload.occupancy.len(), 3 + 8);
    assert_eq!(upload.bytes(), 4 + 1024 + 11 * 8);
    let voxel_words: Vec<u64> = upload.occupancy[3..].iter().map(|&(_, w)| w).collect();
    assert_eq!(voxel_words, app.world().resource::<VoxelWorld>().grid.voxel_mask(upload.bricks[0].0));
    assert_ne!(voxel_words[0] & 1 << 21, 0, "the placed voxel is in the uploaded voxel mask");
    assert_eq!(upload.occupancy[3].0 + 7, upload.occupancy[10].0, "a slot's words are consecutive");
    // A whole-brick fill uploads the top cell only (the brick is homogeneous, not pooled).
    app.world_mut()
        .resource_mut::<VoxelWorld>()
        .apply(Edit::FillBox { min: IVec3::new(8, 0, 16), max: IVec3::new(15, 7, 23), material: 2 })
        .unwrap();
    app.update();
    let upload = app.world().resource::<WorldUpload>().clone();
    assert_eq!(upload.bricks.len(), 0);
    assert_eq!(upload.top_cells.len(), 1);
    // A palette change sends the material table alone.
    app.world_mut().resource_mut::<VoxelWorld>().palette.materials[0].albedo = [0.1, 0.2, 0.3];
    app.update();
    let upload = app.world().resource::<WorldUpload>().clone();
    assert!(upload.materials.is_some() && upload.top_cells.is_empty() && upload.full.is_none());
    // A new world (loaded or generated) is uploaded whole.
    app.insert_resource(load_scene("test-room").unwrap());
    app.update();
    assert!(app.world().resource::<WorldUpload>().full.is_some());
}

/// `required_binding` covers every buffer the first (full) upload creates: the top grid and the masks whole, the
/// brick pool in `POOL_PARTS` parts; a limit below it gives an error naming the buffer, at or above it none.
#[test]
fn a_world_past_the_gpu_binding_limit_is_refused_before_upload() {
    use glowbrick::render::scene::world::{POOL_PARTS, fits_gpu, pool_part_shift, required_binding};
    let world = load_scene("test-room").unwrap();
    let (name, bytes) = required_binding(&world);
    let mut app = app_with(world);
    app.update();
    let full = app.world().resource::<WorldUpload>().full.clone().expect("a full upload");
    let pool = full.pool.len() as u64 * 2;
    assert!(bytes >= full.occupancy.len() as u64 * 8 && bytes >= full.top_cells.len() as u64 * 4, "{name}");
    // At the limit, the parts the renderer makes hold the pool.
    assert!((POOL_PARTS as u64) << pool_part_shift(bytes) >= pool / 1024, "{name}: {bytes} bytes, pool {pool}");
    let world = app.world().resource::<VoxelWorld>();
    assert_eq!(fits_gpu(world, bytes), Ok(()));
    let refused = fits_gpu(world, bytes - 1).unwrap_err();
    assert!(refused.contains("too large for this GPU") && refused.contains(name), "{refused}");
}
