//! Voxel ReSTIR direct lighting (seed 000, DESIGN.md "Voxel ReSTIR"): five compute passes per camera (`PASSES`)
//! after the primary pass has written the G-buffer. First (`light_tiles=on`, the default) `tiles.wgsl` presamples
//! this frame's light tiles, which the candidates draw their lights from; then four per pixel: candidates
//! (`shaders/restir/initial.wgsl`), their visibility and temporal reuse (`temporal.wgsl`), spatial reuse
//! (`spatial.wgsl`) and shading (`shade.wgsl`); `common.wgsl` holds the reservoir and the resampling steps. The
//! candidates trace no ray: a kernel without the traversal's code keeps more threads in flight
//! (docs/bench/why.md).
//! None of them runs when the scene has no lights (or ReSTIR is not the lighting mode): the primary pass then
//! shows emission alone, and the skipped passes record no GPU time.
//!
//! Its per-view state (`RestirView`, a `view::ViewPart`): the two reservoir buffers, the light tiles, and whether
//! last frame's reservoirs are this frame's temporal history. `frame::view_frame` dispatches the passes.

use super::gpu_types::{
    FrameParams, LIGHT_TILE_SIZE, LIGHT_TILES, RESERVOIR_BYTES, RESTIR_INITIAL_VISIBILITY, RESTIR_LIGHT_TILES,
    RESTIR_LOCAL, RESTIR_ONE_RAY, RESTIR_POINT, RESTIR_SPATIAL, RESTIR_TEMPORAL, RESTIR_UNBIASED, TILE_LIGHT_BYTES,
};
use super::interface::GpuBinding;
use super::pass::{Dispatch, VoxelPass};
use super::plan::{FramePlan, RestirPasses};
use super::view::{ViewPart, ViewPartKind};
use crate::settings::{DebugView, LightSample, RenderSettings, Reuse};
use bevy::render::render_resource::{BindingResource, Buffer, BufferDescriptor, BufferUsages};
use bevy::render::renderer::RenderDevice;

/// The passes in dispatch order: this frame's light tiles (`restir/tiles.wgsl`, one thread per tile light), then
/// the four per-pixel passes.
pub const PASSES: [VoxelPass; 5] = [
    VoxelPass {
        name: "glowbrick_restir_tiles",
        shader: "restir/tiles.wgsl",
        entry_point: "main",
        dispatch: Dispatch::LightTiles,
    },
    VoxelPass {
        name: "glowbrick_restir_initial",
        shader: "restir/initial.wgsl",
        entry_point: "main",
        dispatch: Dispatch::Pixels,
    },
    VoxelPass {
        name: "glowbrick_restir_temporal",
        shader: "restir/temporal.wgsl",
        entry_point: "main",
        dispatch: Dispatch::Pixels,
    },
    VoxelPass {
        name: "glowbrick_restir_spatial",
        shader: "restir/spatial.wgsl",
        entry_point: "main",
        dispatch: Dispatch::Pixels,
    },
    VoxelPass { name: SHADE_PASS, shader: "restir/shade.wgsl", entry_point: "main", dispatch: Dispatch::Pixels },
];

/// The last pass, which shades the image (also without lights to sample).
const SHADE_PASS: &str = "glowbrick_restir_shade";

/// GPU-time names of the passes, in dispatch order.
pub const RESTIR_PASS_NAMES: [&str; 5] =
    [PASSES[0].name, PASSES[1].name, PASSES[2].name, PASSES[3].name, PASSES[4].name];

/// Threads of the light tiles' pass (one per tile light).
pub const TILE_THREADS: u32 = LIGHT_TILES * LIGHT_TILE_SIZE;

/// Whether the shading pass shades this frame's image: in a lighting mode that uses Voxel ReSTIR, for a view
/// that shows light (or the reservoirs themselves), with or without lights to sample. The primary pass then never
/// shades, and its pipeline holds no shading code: software Vulkan runs code under a mask whether a lane takes it
/// or not, so a branch on the light count cost every pixel the whole next-event estimation.
pub fn shades(settings: &RenderSettings) -> bool {
    settings.lighting.uses_restir() && (settings.debug.is_lit() || settings.debug == DebugView::Reservoir)
}

/// Whether the sampling passes (light tiles, candidates and temporal reuse, spatial reuse) run this frame: where
/// the shading pass shades and there is something to sample.
pub fn samples(settings: &RenderSettings, light_count: u32) -> bool {
    shades(settings) && light_count > 0
}

/// Whether a view's frame dispatches `pass`: the shading pass whenever ReSTIR shades, the light tiles only when
/// the candidates read them, the other passes when there is something to sample.
pub fn dispatches(passes: &RestirPasses, pass: &VoxelPass) -> bool {
    match pass.dispatch {
        Dispatch::LightTiles => passes.samples && passes.tiles,
        _ if pass.name == SHADE_PASS => passes.shades,
        _ => passes.samples,
    }
}

/// Whether last frame's reservoirs are this frame's temporal history: last frame ran the passes too, and the
/// light pool did not change. Reservoirs drawn from another pool would be reused with MIS weights that assume
/// last frame could have drawn this frame's samples: a lamp placed now would start at a fraction of its light.
pub fn history_is_valid(ran_last_frame: bool, runs: bool, lights_changed: bool) -> bool {
    ran_last_frame && runs && !lights_changed
}

/// The `FrameParams` fields the passes read: M_init, spatial taps, radius in pixels and the `RESTIR_*` flags.
pub struct RestirParams {
    pub candidates: u32,
    pub taps: u32,
    pub radius: f32,
    pub flags: u32,
}

impl RestirParams {
    pub fn of(settings: &RenderSettings) -> Self {
        let restir = settings.restir.clone().clamped();
        let flag = |on: bool, bit: u32| if on { bit } else { 0 };
        RestirParams {
            candidates: restir.candidates,
            taps: restir.taps,
            radius: restir.radius,
            flags: flag(restir.temporal, RESTIR_TEMPORAL)
                | flag(restir.spatial, RESTIR_SPATIAL)
                | flag(restir.sample == LightSample::Point, RESTIR_POINT)
                | flag(restir.reuse == Reuse::Unbiased, RESTIR_UNBIASED)
                | flag(restir.reuse == Reuse::OneRay, RESTIR_ONE_RAY)
                | flag(restir.local_lights, RESTIR_LOCAL)
                | flag(restir.initial_visibility, RESTIR_INITIAL_VISIBILITY)
                | flag(restir.light_tiles, RESTIR_LIGHT_TILES),
        }
    }
}

/// Its part of group 1 (`shaders/restir/common.wgsl`).
pub const VIEW_BINDINGS: [GpuBinding; 3] = [
    GpuBinding::read_write("reservoirs_temporal"),
    GpuBinding::read_write("reservoirs_final"),
    GpuBinding::read_write("light_tiles"),
];

/// Its view part.
pub const VIEW_PART: ViewPartKind =
    ViewPartKind { bindings: &VIEW_BINDINGS, new: |device, pixels| Box::new(RestirView::new(device, pixels)) };

/// One view's reservoirs (after temporal reuse, and final), their history, and its light tiles (rewritten every
/// frame).
pub struct RestirView {
    reservoirs_temporal: Buffer,
    reservoirs_final: Buffer,
    light_tiles: Buffer,
    /// Whether last frame ran the sampling passes.
    sampled: bool,
}

impl RestirView {
    pub fn new(device: &RenderDevice, pixels: u64) -> Self {
        let buffer = |label: &'static str, size: u64| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size,
                usage: BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        RestirView {
            reservoirs_temporal: buffer("glowbrick_reservoirs_temporal", pixels * RESERVOIR_BYTES),
            reservoirs_final: buffer("glowbrick_reservoirs_final", pixels * RESERVOIR_BYTES),
            light_tiles: buffer("glowbrick_light_tiles", u64::from(TILE_THREADS) * TILE_LIGHT_BYTES),
            sampled: false,
        }
    }
}

impl ViewPart for RestirView {
    fn resources(&self) -> Vec<BindingResource<'_>> {
        vec![
            self.reservoirs_temporal.as_entire_binding(),
            self.reservoirs_final.as_entire_binding(),
            self.light_tiles.as_entire_binding(),
        ]
    }

    /// Its parameters, and whether last frame's reservoirs are this frame's history (`prev_camera.w`; not after
    /// a change of render size, whose pixels they were).
    fn begin_frame(&mut self, plan: &FramePlan, resized: bool, settings: &RenderSettings, params: &mut FrameParams) {
        let restir = RestirParams::of(settings);
        (params.candidates, params.taps, params.radius, params.restir_flags) =
            (restir.candidates, restir.taps, restir.radius, restir.flags);
        let history = history_is_valid(self.sampled && !resized, plan.restir.samples, plan.changes.lights);
        self.sampled = plan.restir.samples;
        params.prev_camera[3] = if history { 1.0 } else { 0.0 };
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The history holds only across consecutive ReSTIR frames with the same light pool.
    #[test]
    fn the_history_restarts_after_a_frame_without_restir_or_a_change_of_lights() {
        assert!(history_is_valid(true, true, false));
        assert!(!history_is_valid(false, true, false), "first frame");
        assert!(!history_is_valid(true, false, false), "not running");
        assert!(!history_is_valid(true, true, true), "the light pool changed");
    }

    /// No lights skip the sampling passes but not the shading; an unlit debug view or a mode without ReSTIR
    /// skip all of them. With lights and tiles on every pass runs.
    #[test]
    fn the_sampling_passes_run_only_where_they_have_lights_to_sample() {
        let settings = |pairs: &[&str]| {
            RenderSettings::default().with_pairs(&pairs.iter().map(|p| p.to_string()).collect::<Vec<_>>()).unwrap()
        };
        assert!(samples(&settings(&[]), 1));
        assert!(!samples(&settings(&[]), 0));
        assert!(shades(&settings(&[])));
        assert!(!shades(&settings(&["debug=normal"])) && !samples(&settings(&["debug=normal"]), 1));
        assert!(shades(&settings(&["debug=reservoir"])) && samples(&settings(&["debug=reservoir"]), 1));
        assert!(!shades(&settings(&["lighting=sun"])) && !samples(&settings(&["lighting=sun"]), 1));
        assert!(!shades(&settings(&["lighting=nee"])));
        let view = |shades: bool, samples: bool, tiles: bool| RestirPasses { shades, samples, tiles };
        let count = |v: &RestirPasses| PASSES.iter().filter(|p| dispatches(v, p)).count();
        assert_eq!(count(&view(true, true, true)), 5);
        assert_eq!(count(&view(true, true, false)), 4, "no tiles");
        let shade_only = view(true, false, true);
        assert_eq!(count(&shade_only), 1);
        assert!(dispatches(&shade_only, &PASSES[4]), "the shading pass shades a world without lights");
        assert_eq!(count(&view(false, false, true)), 0);
    }

    /// The named choices reach the GPU as the bits the shaders test.
    #[test]
    fn named_choices_reach_the_gpu_as_flag_bits() {
        use crate::render::scene::lights::scene_lighting;
        let settings = |pairs: &[&str]| {
            RenderSettings::default().with_pairs(&pairs.iter().map(|p| p.to_string()).collect::<Vec<_>>()).unwrap()
        };
        let default = settings(&[]);
        // Default: temporal, spatial, one ray per neighbour, local candidates, the chosen candidate's visibility.
        let defaults = RESTIR_TEMPORAL
            | RESTIR_SPATIAL
            | RESTIR_ONE_RAY
            | RESTIR_LOCAL
            | RESTIR_INITIAL_VISIBILITY
            | RESTIR_LIGHT_TILES;
        assert_eq!((scene_lighting(&default, 3).power_pick, RestirParams::of(&default).flags), (1, defaults));
        assert_eq!((RESTIR_TEMPORAL, RESTIR_SPATIAL, RESTIR_POINT, RESTIR_UNBIASED), (1, 2, 4, 8));
        assert_eq!((RESTIR_ONE_RAY, RESTIR_LOCAL, RESTIR_INITIAL_VISIBILITY, RESTIR_LIGHT_TILES), (16, 32, 64, 128));
        assert_eq!(RestirParams::of(&settings(&["reuse=biased"])).flags, defaults & !RESTIR_ONE_RAY);
        let changed = settings(&[
            "pick=uniform",
            "sample=point",
            "reuse=unbiased",
            "temporal=off",
            "local_lights=off",
            "initial_visibility=off",
            "light_tiles=off",
        ]);
        assert_eq!(
            (scene_lighting(&changed, 3).power_pick, RestirParams::of(&changed).flags),
            (0, RESTIR_SPATIAL | RESTIR_POINT | RESTIR_UNBIASED)
        );
        assert_eq!(scene_lighting(&changed, 3).light_count, 3);
    }
}
