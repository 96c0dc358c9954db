//! Pipelines compiled per `PassKey` (`src/render/pass_key.rs`): one running renderer switched through settings
//! that each need a pipeline set of its own, every set compiled and run on this adapter. A key whose shaders the
//! driver cannot compile or run fails here by name, not in whichever test first meets it (Mesa 22.3's lavapipe
//! crashed on the primary pass compiled for `lighting=sun` until that pass read its `nee` test from the uniform).

use crate::common;
use glowbrick::settings::RenderSettings;
use glowbrick::world::recipe::load_scene;

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
