//! Pipelines compiled per `PassKey` (`src/render/pass_key.rs`): one running renderer switched through settings
//! that each need a pipeline set of its own, every set compiled and run on this adapter. A key whose shaders the
//! driver cannot compile or run fails here by name, not in whichever test first meets it (Mesa 22.3's lavapipe
//! crashed on the primary pass compiled for `lighting=sun` until that pass read its `nee` test from the uniform).

use crate::common;
use bevy::math::IVec3;
use glowbrick::image_io::LinearImage;
use glowbrick::lights::daylight::Daylight;
use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::settings::RenderSettings;
use glowbrick::world::events::EditRequest;
use glowbrick::world::recipe::load_scene;
use glowbrick::world::{Edit, VoxelWorld};

/// Settings that each change the key, on top of the default game frame (`debug=` views included).
const KEYED: [&[&str]; 12] = [
    &[],
    &["lighting=sun"],
    &["lighting=sun", "gi=on", "gi_bounces=off", "gi_qmc=off"],
    &["lighting=nee"],
    &["lighting=emitters", "gi=off", "shadows=off"],
    &["reuse=unbiased", "light_tiles=off", "local_lights=off"],
    &["sample=point", "temporal=off", "spatial=off"],
    &["gi_cached_hits=on", "pick=uniform"],
    &["debug=albedo"],
    &["debug=reservoir"],
    &["debug=variance", "denoise=on"],
    &["traversal=occupancy"],
];

pub fn every_specialised_pipeline_set_compiles_and_renders() {
    let world = load_scene("cornell").unwrap();
    let view = world.view(Some("front")).unwrap().clone();
    let mut renderer = common::renderer_with(&world, &view, 32, 24, KEYED[0]);
    let mut means = vec![];
    for pairs in KEYED {
        *renderer.app_mut().world_mut().resource_mut::<RenderSettings>() = common::settings(pairs);
        // `render` counts frames the voxel passes ran: a new key's first frame waits for its pipelines.
        let image = renderer.render(2).unwrap_or_else(|e| panic!("{pairs:?}: {e}"));
        let mean = image.mean_luminance();
        eprintln!("{pairs:?}: mean {mean:.5}");
        assert_eq!(image.non_finite_pixels(), 0, "{pairs:?}");
        means.push(mean);
    }
    // Each lit frame shows the box's light (the lamp's emission at least); the debug views show something.
    for (pairs, mean) in KEYED.iter().zip(&means) {
        assert!(*mean > 0.01, "{pairs:?}: mean luminance {mean}");
    }
    // Switched back, the default frame is the one it was (its set kept, not recompiled wrong).
    *renderer.app_mut().world_mut().resource_mut::<RenderSettings>() = common::settings(KEYED[0]);
    let again = renderer.render(2).unwrap().mean_luminance();
    assert!((again - means[0]).abs() < 0.25 * means[0], "default frame {} then {again}", means[0]);
}

/// The key follows the light pool (`KEY_LIGHTS`): with the room's lamp broken the primary pass shades the frame
/// itself (the sun and sky through the ceiling's window: the CPU reference's light), and with the lamp placed
/// again it leaves the frame to Voxel ReSTIR, whose pipelines then hold none of the primary pass's shading. In one
/// running renderer each frame matches a renderer started on that world, so a key left behind by the light pool
/// (a pass that returns for every pixel, or shades twice) fails.
pub fn the_primary_pass_follows_the_light_pool_through_its_key() {
    const W: u32 = 48;
    const H: u32 = 32;
    let world = load_scene("test-room").unwrap();
    let view = world.view(Some("inside")).unwrap().clone();
    let pairs = ["time=12", "gi=off"];
    let lamp_voxels = [IVec3::new(24, 1, 24), IVec3::new(24, 2, 24)];
    let lamp = world.palette.id_of("lamp").unwrap();
    let mut lampless = world.clone();
    for at in lamp_voxels {
        lampless.apply(Edit::Break { at }).unwrap();
    }
    let keep = common::comparable_pixels(&lampless, &view, W, H);
    let mean = |image: &LinearImage| common::masked(image, &keep).mean_luminance();
    let fresh_mean = |world: &VoxelWorld| mean(&common::renderer_with(world, &view, W, H, &pairs).render(8).unwrap());
    let (fresh_lit, fresh_dark) = (fresh_mean(&world), fresh_mean(&lampless));
    let options = ReferenceOptions {
        width: W,
        height: H,
        spp: 256,
        daylight: Some(Daylight::at(12.0, true)),
        ..Default::default()
    };
    let sunlit = mean(&render_reference(&lampless, &view, &options).unwrap().image);
    eprintln!(
        "fresh renderers: with the lamp {fresh_lit:.5}, without {fresh_dark:.5}; the CPU's sun and sky {sunlit:.5}"
    );
    assert!((fresh_dark - sunlit).abs() <= 0.1 * sunlit, "the lampless room: {fresh_dark} against {sunlit}");
    assert!(fresh_lit > 1.2 * fresh_dark, "the lamp must light the room beyond the sun");

    let mut renderer = common::renderer_with(&world, &view, W, H, &pairs);
    renderer.render(8).unwrap();
    let mut edit_and_render = |edits: [Edit; 2]| {
        for edit in edits {
            renderer.app_mut().world_mut().write_message(EditRequest::player(edit));
        }
        renderer.render(8).unwrap()
    };
    let dark = edit_and_render(lamp_voxels.map(|at| Edit::Break { at }));
    assert_eq!(dark.non_finite_pixels(), 0);
    let dark = mean(&dark);
    let lit = mean(&edit_and_render(lamp_voxels.map(|at| Edit::Place { at, material: lamp })));
    eprintln!("one renderer: lamp broken {dark:.5}, placed again {lit:.5}");
    assert!((dark - fresh_dark).abs() <= 0.1 * fresh_dark, "lamp broken: {dark} against {fresh_dark}");
    assert!((lit - fresh_lit).abs() <= 0.1 * fresh_lit, "lamp placed again: {lit} against {fresh_lit}");
}
