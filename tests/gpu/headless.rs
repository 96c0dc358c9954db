//! Headless rendering's failure path on a real adapter: a voxel shader that does not compile.

use bevy::prelude::*;
use bevy::shader::Shader;
use glowbrick::headless::{HeadlessOptions, HeadlessRenderer};
use glowbrick::render::shaders::GlowbrickShaders;
use glowbrick::world::recipe::load_scene;
use std::time::{Duration, Instant};

/// Every wait (a frame, the next frame, a sequence, the GPU counters) fails within seconds with the pass's name and
/// shader when the primary shader does not compile, instead of waiting out the 600 s timeout for frames that never
/// come. The shader is broken by replacing its asset before the first frame, as a bad edit of the WGSL would.
pub fn a_broken_shader_fails_every_wait_at_once_with_its_pass_name() {
    let world = load_scene("test-room").unwrap();
    let view = world.view(Some("inside")).cloned().unwrap();
    let options = HeadlessOptions { width: 32, height: 32, ..Default::default() };
    let mut r = HeadlessRenderer::new(world, &view, &options).unwrap();
    let handle = r.app_mut().world().resource::<GlowbrickShaders>().get("primary.wgsl");
    let broken = Shader::from_wgsl("this is not WGSL", "glowbrick/primary.wgsl");
    r.app_mut().world_mut().resource_mut::<Assets<Shader>>().insert(handle.id(), broken).unwrap();
    type Wait = fn(&mut HeadlessRenderer) -> Result<(), String>;
    let waits: [(&str, Wait); 4] = [
        ("render", |r| r.render(4).map(|_| ())),
        ("render_next", |r| r.render_next().map(|_| ())),
        ("render_sequence", |r| r.render_sequence(4, |_, _| {}).map(|_| ())),
        ("counters", |r| r.counters().map(|_| ())),
    ];
    for (name, wait) in waits {
        let start = Instant::now();
        let error = wait(&mut r).expect_err(name);
        let took = start.elapsed();
        eprintln!("{name}: {error} ({took:.1?})");
        assert!(error.contains("(primary.wgsl) failed to compile"), "{name}: {error}");
        assert!(took < Duration::from_secs(60), "{name} took {took:?}");
    }
}
