//! After edits travel the game's edit path (messages -> world -> dirty bricks -> partial GPU upload), the GPU
//! world equals the CPU world: the GPU's primary hits match the CPU traversal of the edited world, and the render
//! world's light buffers follow the light pool (count and the "no lights" flag).

use crate::common;

use bevy::prelude::*;
use bevy::render::RenderApp;
use common::compare_hits;
use glowbrick::headless::HeadlessOptions;
use glowbrick::lights::LightPool;
use glowbrick::render::scene::lights::GpuLights;
use glowbrick::render::scene::world::GpuWorld;
use glowbrick::render::scene::world::WorldUpload;
use glowbrick::settings::RenderSettings;
use glowbrick::world::events::EditRequest;
use glowbrick::world::recipe::{generated_world, load_scene};
use glowbrick::world::{Edit, VoxelWorld, camera_ray, trace, view_transform, world_from_clip};

fn gpu_light_state(app: &mut App) -> (u32, bool) {
    let gpu = app.sub_app(RenderApp).world().resource::<GpuLights>();
    (gpu.light_count, gpu.has_lights)
}

pub fn gpu_world_follows_edits() {
    let world = load_scene("test-room").unwrap();
    let view = world.view(Some("inside")).unwrap().clone();
    let settings = RenderSettings::default().with_pairs(&["debug=hit".to_string()]).unwrap();
    let options = HeadlessOptions { width: 96, height: 64, settings, ..Default::default() };
    let mut renderer = common::renderer(world, &view, &options);
    renderer.render(1).unwrap();
    let lamp = renderer.app_mut().world().resource::<VoxelWorld>().palette.id_of("lamp").unwrap();
    let red = renderer.app_mut().world().resource::<VoxelWorld>().palette.id_of("red").unwrap();
    assert_eq!(gpu_light_state(renderer.app_mut()), (2, true), "the room's lamp is a column of two voxel lights");

    let edits = [
        Edit::FillBox { min: IVec3::new(8, 1, 8), max: IVec3::new(15, 8, 15), material: red },
        Edit::Break { at: IVec3::new(10, 8, 10) },
        Edit::Place { at: IVec3::new(20, 4, 12), material: lamp },
        Edit::FillBox { min: IVec3::new(3, 1, 10), max: IVec3::new(5, 12, 11), material: lamp },
        Edit::Break { at: IVec3::new(4, 5, 10) },
    ];
    for edit in edits {
        renderer.app_mut().world_mut().write_message(EditRequest::player(edit));
    }
    // The frame that applies the edits uploads only the five dirty bricks (x + 4 * (y + 2 * z) = 8, 9, 10, 12,
    // 13): their top cells, pooled voxels, voxel masks and occupancy masks, and the masks of the one sector and
    // region above.
    renderer.step();
    let staged = renderer.app_mut().world().resource::<WorldUpload>().clone();
    let uploaded = renderer.app_mut().sub_app(RenderApp).world().resource::<GpuWorld>().uploaded_bytes;
    assert!(staged.full.is_none() && staged.top_cells.len() == 5, "bricks touched: {:?}", staged.top_cells);
    assert_eq!(uploaded, staged.bytes());
    assert!(uploaded <= 5 * (4 + 1024 + 64 + 8) + 2 * 8, "{uploaded} bytes for five bricks");
    let image = renderer.render(1).unwrap();
    let world = renderer.app_mut().world().resource::<VoxelWorld>().clone();
    let c = compare_hits(&world, &view, &image);
    assert!(c.hits * 2 > c.pixels && c.mismatches * 200 <= c.pixels, "{c:?}");

    let pool_len = renderer.app_mut().world().resource::<LightPool>().len() as u32;
    assert!(pool_len > 1, "the new lamps are lights");
    assert_eq!(gpu_light_state(renderer.app_mut()), (pool_len, true));

    // Clearing every lamp leaves the renderer with no lights: the flag passes use to skip themselves.
    let mut lamps = Vec::new();
    world.grid.for_each_solid(|p, m| {
        if m == lamp {
            lamps.push(p);
        }
    });
    for at in lamps {
        renderer.app_mut().world_mut().write_message(EditRequest::player(Edit::Break { at }));
    }
    renderer.render(1).unwrap();
    assert_eq!(gpu_light_state(renderer.app_mut()), (0, false));
}

/// The occupancy walk starts a camera ray where it enters the box of bricks that may hold a solid voxel. A pillar
/// built up through the top of that box must reach the GPU with the edit's partial upload (the box in the world
/// info), or the rays above the old box would pass over the pillar.
pub fn the_occupancy_walk_sees_a_pillar_built_above_the_occupied_box() {
    let world = generated_world(9, UVec3::new(64, 64, 64)).unwrap();
    let view = world.overview();
    let top_before = world.grid.occupied_box().1.y;
    assert!(top_before <= 48, "the terrain should leave room above its box: top {top_before}");
    let material = world.grid.get(IVec3::new(32, 0, 32));
    assert_ne!(material, 0, "the ground under the pillar is solid");
    let settings =
        RenderSettings::default().with_pairs(&["debug=hit".to_string(), "traversal=occupancy".to_string()]).unwrap();
    let options = HeadlessOptions { width: 96, height: 64, settings, ..Default::default() };
    let mut renderer = common::renderer(world, &view, &options);
    renderer.render(1).unwrap();
    let pillar = Edit::FillBox { min: IVec3::new(28, 0, 28), max: IVec3::new(35, 63, 35), material };
    renderer.app_mut().world_mut().write_message(EditRequest::player(pillar));
    renderer.step();
    let staged = renderer.app_mut().world().resource::<WorldUpload>().clone();
    assert!(staged.full.is_none(), "the pillar travels as a partial upload");
    let image = renderer.render(1).unwrap();
    let world = renderer.app_mut().world().resource::<VoxelWorld>().clone();
    assert_eq!(world.grid.occupied_box().1.y, 64, "the pillar grew the box to the world's top");
    // The CPU's view of the pillar above the old box: the pixels a stale box would lose.
    let transform = view_transform(&view);
    let m = world_from_clip(&transform, view.fov_deg.to_radians(), 96, 64);
    let above = (0..64 * 96)
        .filter(|i| {
            let ray = camera_ray(m, transform.translation, UVec2::new(i % 96, i / 96), 96, 64);
            trace(&world.grid, &ray, f32::INFINITY).is_some_and(|h| h.voxel.y >= top_before)
        })
        .count();
    assert!(above >= 50, "the view should show the pillar above the old box: {above} pixels");
    let c = compare_hits(&world, &view, &image);
    assert!(c.mismatches * 200 <= c.pixels, "{c:?}");
}
