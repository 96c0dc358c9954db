//! The CPU half of the smoke test (`cargo test --release --test cpu --test gpu smoke`): a shipped scene loads
//! from `assets/` and the CPU reference renders it lit and finite. Seconds, to say the build works before the
//! long tests run.

use glowbrick::reference::{ReferenceOptions, render_reference};
use glowbrick::world::recipe::load_scene;

#[test]
fn smoke_a_shipped_scene_loads_and_the_cpu_reference_lights_it() {
    let world = load_scene("cornell").unwrap();
    let view = world.view(Some("front")).unwrap().clone();
    let options = ReferenceOptions { width: 32, height: 24, spp: 16, bounces: 1, ..Default::default() };
    let image = render_reference(&world, &view, &options).unwrap().image;
    assert_eq!(image.non_finite_pixels(), 0);
    let lit = image.pixels.iter().filter(|p| p[..3].iter().any(|c| *c > 0.0)).count();
    // The lit box fills most of the view (two thirds of it); a broken scene or renderer leaves it black.
    assert!(lit * 2 > image.pixels.len(), "{lit} of {} pixels lit", image.pixels.len());
}
