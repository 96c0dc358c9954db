//! A camera's own buffers and parameters (group 1, `shaders/lib/frame.wgsl`), gathered from the techniques that
//! own them: the view's frame parameters and running average (`ViewState`, here), the G-buffer
//! (`primary::GBuffers`), Voxel ReSTIR's reservoirs (`restir::RestirView`) and the denoiser's buffers
//! (`denoise::DenoiseView`). Each technique decides when its own history restarts; this module only tells them
//! what changed in the scene this frame.

use super::denoise::{self, DenoiseView};
use super::gpu_types::{ACCUMULATION_TEXEL_BYTES, FrameParams};
use super::primary::GBuffers;
use super::restir::{self, RestirParams, RestirView};
use super::scene::lights::GpuLights;
use super::scene::objects::GpuObjects;
use super::scene::world::GpuWorld;
use super::{CameraFramesRendered, Highlight, VoxelCamera};
use crate::settings::{RenderSettings, SEED_FRAMES};
use bevy::prelude::*;
use bevy::render::render_resource::binding_types::{
    storage_buffer_sized, texture_storage_2d, uniform_buffer, uniform_buffer_sized,
};
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::view::{ExtractedView, ViewTarget, ViewUniform};
use std::num::NonZeroU64;
use std::sync::Mutex;
use std::sync::atomic::Ordering;

/// Per-view, per-frame parameters for the view's shaders (`FrameParams`), before the view's own history fields.
pub fn frame_params(settings: &RenderSettings, highlight: &Highlight, frame: u32) -> FrameParams {
    let restir = RestirParams::of(settings);
    FrameParams {
        prev_clip_from_world: Mat4::IDENTITY.to_cols_array_2d(),
        prev_camera: [0.0; 4],
        debug_view: settings.debug.shader_index(),
        exposure: settings.exposure,
        frame: frame.wrapping_add(settings.seed.wrapping_mul(SEED_FRAMES)),
        accumulated: 1,
        highlight_target: highlight.target.map_or([0; 4], |(v, face)| [v.x, v.y, v.z, face as i32 + 1]),
        selection_min: highlight.selection.map_or([0; 4], |(a, _)| [a.x, a.y, a.z, 1]),
        selection_max: highlight.selection.map_or([0; 4], |(_, b)| [b.x, b.y, b.z, 1]),
        candidates: restir.candidates,
        taps: restir.taps,
        radius: restir.radius,
        restir_flags: restir.flags,
        denoise: 0,
        _pad: [0; 3],
    }
}

/// Everything that must stay the same for frames to be averaged.
#[derive(Clone, Debug, PartialEq)]
struct AccumulationKey {
    clip_from_world: Mat4,
    settings: RenderSettings,
    highlight: Highlight,
}

/// The view's own part of group 1: its frame parameters (binding 2), the running sum of accumulated frames
/// (binding 3), and what the next frame needs of this one (the camera, for reprojection).
pub struct ViewState {
    frame_params: Buffer,
    accumulation: Buffer,
    /// What the average so far was rendered with; any difference restarts it.
    last_key: Option<AccumulationKey>,
    accumulated: u32,
    prev_clip_from_world: Mat4,
    prev_camera: Vec3,
}

impl ViewState {
    fn new(device: &RenderDevice, pixels: u64) -> Self {
        let buffer = |label: &'static str, size: u64, usage: BufferUsages| {
            device.create_buffer(&BufferDescriptor { label: Some(label), size, usage, mapped_at_creation: false })
        };
        ViewState {
            frame_params: buffer(
                "glowbrick_frame_params",
                size_of::<FrameParams>() as u64,
                BufferUsages::UNIFORM | BufferUsages::COPY_DST,
            ),
            accumulation: buffer("glowbrick_accumulation", pixels * ACCUMULATION_TEXEL_BYTES, BufferUsages::STORAGE),
            last_key: None,
            accumulated: 0,
            prev_clip_from_world: Mat4::IDENTITY,
            prev_camera: Vec3::ZERO,
        }
    }

    /// Counts this frame into the average (or restarts it) and hands over last frame's camera.
    fn begin_frame(&mut self, key: AccumulationKey, accumulate: bool, camera: Vec3, params: &mut FrameParams) {
        let same = accumulate && self.last_key.as_ref() == Some(&key);
        self.accumulated = if same { self.accumulated.saturating_add(1) } else { 1 };
        params.accumulated = self.accumulated;
        params.prev_clip_from_world = self.prev_clip_from_world.to_cols_array_2d();
        let p = self.prev_camera;
        params.prev_camera = [p.x, p.y, p.z, 0.0];
        self.prev_clip_from_world = key.clip_from_world;
        self.prev_camera = camera;
        self.last_key = Some(key);
    }
}

/// A view's buffers, each part owned by its technique; lives on the camera's render-world entity.
#[derive(Component)]
pub struct ViewResources {
    size: UVec2,
    pub view: ViewState,
    pub gbuffers: GBuffers,
    pub restir: RestirView,
    pub denoise: DenoiseView,
    /// The view's bind groups made so far, by what can change between frames (`ViewBindKey`): a handful, made
    /// once each instead of every frame.
    bind_groups: Mutex<Vec<(ViewBindKey, BindGroup)>>,
}

/// What the view's bind group binds that can change from frame to frame: the output texture (Bevy's main
/// textures), the view uniforms' buffer (grown by Bevy), and the two ping-pong parities.
#[derive(Clone, Copy, PartialEq, Eq)]
struct ViewBindKey {
    target: TextureId,
    view_uniforms: BufferId,
    gbuffer: usize,
    history: usize,
}

/// More keys than a view meets in practice (2 textures x 2 x 2 parities); past it the cache starts over.
const MAX_VIEW_BIND_GROUPS: usize = 16;

impl ViewResources {
    fn new(device: &RenderDevice, size: UVec2) -> Self {
        let pixels = (size.x.max(1) * size.y.max(1)) as u64;
        ViewResources {
            size,
            view: ViewState::new(device, pixels),
            gbuffers: GBuffers::new(device, pixels),
            restir: RestirView::new(device, pixels),
            denoise: DenoiseView::new(device, pixels),
            bind_groups: Mutex::new(Vec::new()),
        }
    }

    /// The view's bind group (group 1) for this frame's output texture and view uniform: made the first time
    /// this combination of texture, uniform buffer and ping-pong parities is met, then reused.
    pub fn bind_group(
        &self,
        device: &RenderDevice,
        layout: &BindGroupLayout,
        target: &ViewTarget,
        view_uniforms: &Buffer,
        view_uniform: BindingResource,
    ) -> BindGroup {
        let output = target.get_unsampled_color_attachment().view;
        let key = ViewBindKey {
            target: target.main_texture().id(),
            view_uniforms: view_uniforms.id(),
            gbuffer: self.gbuffers.parity(),
            history: self.denoise.parity(),
        };
        let mut cached = self.bind_groups.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((_, group)) = cached.iter().find(|(k, _)| *k == key) {
            return group.clone();
        }
        let [gbuffer, prev_gbuffer] = self.gbuffers.bindings();
        let [reservoirs_temporal, reservoirs_final] = self.restir.bindings();
        let [noisy, history, prev_history, wavelet] = self.denoise.bindings();
        let group = device.create_bind_group(
            "glowbrick_view",
            layout,
            &BindGroupEntries::sequential((
                output,
                view_uniform,
                self.view.frame_params.as_entire_binding(),
                self.view.accumulation.as_entire_binding(),
                gbuffer,
                prev_gbuffer,
                reservoirs_temporal,
                reservoirs_final,
                noisy,
                history,
                prev_history,
                wavelet,
                self.restir.tiles_binding(),
            )),
        );
        if cached.len() >= MAX_VIEW_BIND_GROUPS {
            cached.clear();
        }
        cached.push((key, group.clone()));
        group
    }
}

/// Group 1's layout, in the order of `ViewResources::bind_group` and `shaders/lib/frame.wgsl`.
pub fn view_layout() -> BindGroupLayoutDescriptor {
    let storage = || storage_buffer_sized(false, None);
    BindGroupLayoutDescriptor::new(
        "glowbrick_view_layout",
        &BindGroupLayoutEntries::sequential(
            ShaderStages::COMPUTE,
            (
                texture_storage_2d(TextureFormat::Rgba16Float, StorageTextureAccess::WriteOnly),
                uniform_buffer::<ViewUniform>(true),
                uniform_buffer_sized(false, NonZeroU64::new(size_of::<FrameParams>() as u64)),
                // The accumulation, the G-buffers (primary), the reservoirs (restir).
                storage(),
                storage(),
                storage(),
                storage(),
                storage(),
                // The denoiser: noisy frame, history, last frame's history, wavelet ping-pong.
                storage(),
                storage(),
                storage(),
                storage(),
                // ReSTIR's light tiles.
                storage(),
            ),
        ),
    )
}

/// What changed in the scene this frame, as the views' histories see it.
struct SceneChanges {
    /// The light pool changed (a lamp placed or removed).
    lights: bool,
    /// An edit changed the world's voxels or its lights.
    world: bool,
    /// Anything in the image changed without the camera moving, moving objects included.
    anything: bool,
    light_count: u32,
}

impl SceneChanges {
    fn of(world: Option<&GpuWorld>, lights: Option<&GpuLights>, objects: Option<&GpuObjects>) -> Self {
        let lights_changed = lights.is_some_and(|l| l.changed);
        let world_changed = world.is_some_and(|w| w.uploaded_bytes > 0) || lights_changed;
        SceneChanges {
            lights: lights_changed,
            world: world_changed,
            anything: world_changed || objects.is_some_and(|o| o.changed),
            light_count: lights.map_or(0, |l| l.light_count),
        }
    }
}

/// Creates each view's buffers and writes its frame parameters; each technique decides whether it runs and
/// whether its history holds (Render schedule, PrepareResources, after the scene uploads).
#[allow(clippy::too_many_arguments)]
pub fn prepare_view_resources(
    mut commands: Commands,
    mut views: Query<(Entity, &ExtractedView, Option<&mut ViewResources>), With<VoxelCamera>>,
    settings: Option<Res<RenderSettings>>,
    highlight: Option<Res<Highlight>>,
    gpu_world: Option<Res<GpuWorld>>,
    gpu_lights: Option<Res<GpuLights>>,
    objects: Option<Res<GpuObjects>>,
    frames: Res<CameraFramesRendered>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    let settings = settings.map(|s| s.clone()).unwrap_or_default();
    let highlight = highlight.map(|h| *h).unwrap_or_default();
    let changes = SceneChanges::of(gpu_world.as_deref(), gpu_lights.as_deref(), objects.as_deref());
    let restir_passes = restir::RestirPasses {
        shades: restir::shades(&settings),
        samples: restir::samples(&settings, changes.light_count),
        tiles: settings.restir.light_tiles,
    };
    let run_denoise = denoise::runs(&settings);
    for (entity, view, resources) in &mut views {
        let size = view.viewport.zw();
        let clip_from_world = view.clip_from_view * view.world_from_view.to_matrix().inverse();
        let mut created = None;
        let resources: &mut ViewResources = match resources {
            Some(r) if r.size == size => r.into_inner(),
            _ => created.insert(ViewResources::new(&device, size)),
        };
        let mut params = frame_params(&settings, &highlight, frames.0.load(Ordering::Relaxed));
        let key = AccumulationKey { clip_from_world, settings: settings.clone(), highlight };
        let accumulate = settings.accumulate && !changes.anything;
        resources.view.begin_frame(key, accumulate, view.world_from_view.translation(), &mut params);
        let restir_history = resources.restir.begin_frame(restir_passes, changes.lights);
        params.prev_camera[3] = if restir_history { 1.0 } else { 0.0 };
        params.denoise = resources.denoise.begin_frame(run_denoise, changes.world);
        queue.write_buffer(&resources.view.frame_params, 0, bytemuck::bytes_of(&params));
        if let Some(new) = created {
            // A new or resized view: its buffers live on its render-world entity from now on.
            commands.entity(entity).insert(new);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::gpu_types::RESTIR_UNBIASED;
    use crate::render::gpu_types::{
        RESTIR_INITIAL_VISIBILITY, RESTIR_LIGHT_TILES, RESTIR_LOCAL, RESTIR_ONE_RAY, RESTIR_POINT, RESTIR_SPATIAL,
        RESTIR_TEMPORAL,
    };
    use crate::render::scene::lights::scene_lighting;

    /// The named choices reach the GPU as the bits the shaders test.
    #[test]
    fn named_choices_reach_the_gpu_as_flag_bits() {
        let settings = |pairs: &[&str]| {
            RenderSettings::default().with_pairs(&pairs.iter().map(|p| p.to_string()).collect::<Vec<_>>()).unwrap()
        };
        let default = settings(&[]);
        let params = frame_params(&default, &Highlight::default(), 0);
        // Default: temporal, spatial, one ray per neighbour, local candidates, the chosen candidate's visibility.
        let defaults = RESTIR_TEMPORAL
            | RESTIR_SPATIAL
            | RESTIR_ONE_RAY
            | RESTIR_LOCAL
            | RESTIR_INITIAL_VISIBILITY
            | RESTIR_LIGHT_TILES;
        assert_eq!((scene_lighting(&default, 3).power_pick, params.restir_flags), (1, defaults));
        assert_eq!((RESTIR_TEMPORAL, RESTIR_SPATIAL, RESTIR_POINT, RESTIR_UNBIASED), (1, 2, 4, 8));
        assert_eq!((RESTIR_ONE_RAY, RESTIR_LOCAL, RESTIR_INITIAL_VISIBILITY, RESTIR_LIGHT_TILES), (16, 32, 64, 128));
        let biased = frame_params(&settings(&["reuse=biased"]), &Highlight::default(), 0);
        assert_eq!(biased.restir_flags, defaults & !RESTIR_ONE_RAY);
        let changed = settings(&[
            "pick=uniform",
            "sample=point",
            "reuse=unbiased",
            "temporal=off",
            "local_lights=off",
            "initial_visibility=off",
            "light_tiles=off",
        ]);
        let params = frame_params(&changed, &Highlight::default(), 0);
        assert_eq!(
            (scene_lighting(&changed, 3).power_pick, params.restir_flags),
            (0, RESTIR_SPATIAL | RESTIR_POINT | RESTIR_UNBIASED)
        );
        assert_eq!(scene_lighting(&changed, 3).light_count, 3);
    }
}
