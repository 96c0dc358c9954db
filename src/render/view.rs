//! A camera's own buffers and parameters (group 1, `shaders/lib/frame.wgsl`): the view's frame parameters and
//! running average (`ViewState`, here), then each technique's part (`ViewPart`: its buffers, its bindings and
//! when its history restarts), in the order `ViewParts` lists them. This module names no technique: `frame`
//! lists the parts, and the frame plan tells each one what runs and what changed.

use super::gpu_types::{ACCUMULATION_TEXEL_BYTES, FrameParams};
use super::interface::{Access, GpuBinding, GroupInterface};
use super::plan::{FramePlan, FramePlanned};
use super::{CameraFramesRendered, Highlight, VoxelCamera};
use crate::settings::{RenderSettings, SEED_FRAMES};
use bevy::prelude::*;
use bevy::render::render_resource::*;
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::view::{ExtractedView, ViewTarget};
use std::sync::Mutex;
use std::sync::atomic::Ordering;

/// A technique's per-view state: its buffers in group 1 and its history.
pub trait ViewPart: Send + Sync + 'static {
    /// Its buffers, in the order of its `ViewPartKind::bindings`.
    fn resources(&self) -> Vec<BindingResource<'_>>;
    /// Starts a frame the view prepares: its fields of `params` for `settings`, and whether its history holds
    /// under `plan` (`resized`: the render size changed since last frame, so the render pixels' histories no
    /// longer line up).
    fn begin_frame(&mut self, plan: &FramePlan, resized: bool, settings: &RenderSettings, params: &mut FrameParams);
    /// Starts a frame the view draws: last frame's ping-pong buffers become the previous ones.
    fn swap(&self) {}
    /// Which of its ping-pong buffers is this frame's (the view's bind groups are cached by it).
    fn parity(&self) -> usize {
        0
    }
}

/// A kind of view part: its bindings in group 1 and how to make one for a view of some pixels.
#[derive(Clone, Copy)]
pub struct ViewPartKind {
    pub bindings: &'static [GpuBinding],
    pub new: fn(&RenderDevice, u64) -> Box<dyn ViewPart>,
}

/// The techniques' view parts in binding order (inserted by `frame`).
#[derive(Resource, Clone)]
pub struct ViewParts(pub Vec<ViewPartKind>);

/// The view's own bindings, first in group 1.
pub const VIEW_BINDINGS: [GpuBinding; 4] = [
    GpuBinding { name: "output", access: Access::OutputTexture },
    GpuBinding { name: "view", access: Access::ViewUniform },
    GpuBinding::uniform("frame", size_of::<FrameParams>()),
    GpuBinding::read_write("accumulation"),
];

/// Group 1: the view's own bindings, then each part's.
pub fn view_interface(parts: &ViewParts) -> GroupInterface {
    let mut groups: Vec<&[GpuBinding]> = vec![&VIEW_BINDINGS];
    groups.extend(parts.0.iter().map(|kind| kind.bindings));
    GroupInterface::new(1, "glowbrick_view_layout", &groups)
}

/// Per-view, per-frame parameters for the view's shaders (`FrameParams`), before the view's own history fields
/// and the parts' fields.
pub fn frame_params(settings: &RenderSettings, highlight: &Highlight, frame: u32) -> FrameParams {
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
        candidates: 0,
        taps: 0,
        radius: 0.0,
        restir_flags: 0,
        denoise: 0,
        upscale: 0,
        render_size: [0; 2],
        jitter: [0.0; 2],
        _pad: [0; 2],
    }
}

/// Everything that must stay the same for frames to be averaged.
#[derive(Clone, Debug, PartialEq)]
struct AccumulationKey {
    clip_from_world: Mat4,
    settings: RenderSettings,
    highlight: Highlight,
}

/// The view's own part of group 1 (`VIEW_BINDINGS`): its frame parameters, the running sum of accumulated frames,
/// and what the next frame needs of this one (the camera, for reprojection).
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
    /// The lighting passes' pixels this frame (`FramePlan::render_size`).
    render_size: UVec2,
    pub view: ViewState,
    parts: Vec<Box<dyn ViewPart>>,
    /// The view's bind groups made so far, by what can change between frames (`ViewBindKey`): a handful, made
    /// once each instead of every frame.
    bind_groups: Mutex<Vec<(ViewBindKey, BindGroup)>>,
}

/// What the view's bind group binds that can change from frame to frame: the output texture (Bevy's main
/// textures), the view uniforms' buffer (grown by Bevy), and the parts' ping-pong parities (bit i: part i's).
#[derive(Clone, Copy, PartialEq, Eq)]
struct ViewBindKey {
    target: TextureId,
    view_uniforms: BufferId,
    parities: u64,
}

/// More keys than a view meets in practice (2 textures x 2 x 2 parities); past it the cache starts over.
const MAX_VIEW_BIND_GROUPS: usize = 16;

impl ViewResources {
    fn new(device: &RenderDevice, size: UVec2, parts: &ViewParts) -> Self {
        let pixels = (size.x.max(1) * size.y.max(1)) as u64;
        ViewResources {
            size,
            render_size: size,
            view: ViewState::new(device, pixels),
            parts: parts.0.iter().map(|kind| (kind.new)(device, pixels)).collect(),
            bind_groups: Mutex::new(Vec::new()),
        }
    }

    /// The lighting passes' pixels this frame.
    pub fn render_size(&self) -> UVec2 {
        self.render_size
    }

    /// Starts a frame the view draws: every part's ping-pong buffers swap.
    pub fn swap(&self) {
        self.parts.iter().for_each(|part| part.swap());
    }

    /// The view's bind group (group 1) for this frame's output texture and view uniform: made the first time
    /// this combination of texture, uniform buffer and ping-pong parities is met, then reused.
    pub fn bind_group(
        &self,
        device: &RenderDevice,
        interface: &GroupInterface,
        layout: &BindGroupLayout,
        target: &ViewTarget,
        view_uniforms: &Buffer,
        view_uniform: BindingResource,
    ) -> BindGroup {
        let output = target.get_unsampled_color_attachment().view;
        let parities = self.parts.iter().enumerate().map(|(i, part)| (part.parity() as u64 & 1) << i).sum();
        let key = ViewBindKey { target: target.main_texture().id(), view_uniforms: view_uniforms.id(), parities };
        let mut cached = self.bind_groups.lock().unwrap_or_else(|poisoned| poisoned.into_inner());
        if let Some((_, group)) = cached.iter().find(|(k, _)| *k == key) {
            return group.clone();
        }
        let mut resources = vec![
            output.into_binding(),
            view_uniform,
            self.view.frame_params.as_entire_binding(),
            self.view.accumulation.as_entire_binding(),
        ];
        resources.extend(self.parts.iter().flat_map(|part| part.resources()));
        let group = device.create_bind_group("glowbrick_view", layout, &interface.entries(resources));
        if cached.len() >= MAX_VIEW_BIND_GROUPS {
            cached.clear();
        }
        cached.push((key, group.clone()));
        group
    }
}

/// Creates each view's buffers and writes its frame parameters; each part reads from the frame plan whether its
/// history holds (Render schedule, PrepareResources, after the frame plan).
#[allow(clippy::too_many_arguments)]
pub fn prepare_view_resources(
    mut commands: Commands,
    mut views: Query<(Entity, &ExtractedView, Option<&mut ViewResources>), With<VoxelCamera>>,
    settings: Option<Res<RenderSettings>>,
    highlight: Option<Res<Highlight>>,
    plan: Res<FramePlan>,
    parts: Res<ViewParts>,
    frames: Res<CameraFramesRendered>,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
) {
    let settings = settings.map(|s| s.clone()).unwrap_or_default();
    let highlight = highlight.map(|h| *h).unwrap_or_default();
    for (entity, view, resources) in &mut views {
        let size = view.viewport.zw();
        let clip_from_world = view.clip_from_view * view.world_from_view.to_matrix().inverse();
        let mut created = None;
        let resources: &mut ViewResources = match resources {
            Some(r) if r.size == size => r.into_inner(),
            _ => created.insert(ViewResources::new(&device, size, &parts)),
        };
        let mut params = frame_params(&settings, &highlight, frames.0.load(Ordering::Relaxed));
        let key = AccumulationKey { clip_from_world, settings: settings.clone(), highlight };
        let accumulate = settings.accumulate && !plan.changes.anything;
        resources.view.begin_frame(key, accumulate, view.world_from_view.translation(), &mut params);
        let render_size = plan.render_size(size);
        let resized = render_size != resources.render_size;
        resources.render_size = render_size;
        params.render_size = render_size.max(UVec2::ONE).to_array();
        for part in &mut resources.parts {
            part.begin_frame(&plan, resized, &settings, &mut params);
        }
        queue.write_buffer(&resources.view.frame_params, 0, bytemuck::bytes_of(&params));
        if let Some(new) = created {
            // A new or resized view: its buffers live on its render-world entity from now on.
            commands.entity(entity).insert(new);
        }
    }
}

/// Adds the views' preparation (after the frame plan).
pub fn add(render_app: &mut SubApp) {
    use bevy::render::{Render, RenderSystems};
    render_app.add_systems(Render, prepare_view_resources.after(FramePlanned).in_set(RenderSystems::PrepareResources));
}
