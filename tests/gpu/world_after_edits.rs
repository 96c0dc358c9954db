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
use glowbrick::world::recipe::load_scene;
use glowbrick::world::{Edit, VoxelWorld};

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
    // 13): their top cells, pooled voxels and occupancy masks, and the masks of the one sector and region above.
    renderer.step();
    let staged = renderer.app_mut().world().resource::<WorldUpload>().clone();
    let uploaded = renderer.app_mut().sub_app(RenderApp).world().resource::<GpuWorld>().uploaded_bytes;
    assert!(staged.full.is_none() && staged.top_cells.len() == 5, "bricks touched: {:?}", staged.top_cells);
    assert_eq!(uploaded, staged.bytes());
    assert!(uploaded <= 5 * (4 + 1024 + 8) + 2 * 8, "{uploaded} bytes for five bricks");
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
