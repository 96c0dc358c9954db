//! The scene's lighting on the GPU (group 2 of every voxel pass, `shaders/lib/lights.wgsl`): the light pool's
//! changed slots, its alias table and light index (with the light bricks) when they changed, and this frame's `SceneLighting` (sun, sky, mode, light
//! count). Staged in the main world (PostUpdate), written to GPU buffers in the render world (PrepareResources).

use super::staging::{Fit, Mirrored, Staging, sync, upload};
use crate::lights::daylight::Daylight;
use crate::lights::{AliasEntry, Light, LightBricks, LightPool};
use crate::render::gpu_types::{GpuLight, LIGHT_FACES_SHIFT, SceneLighting};
use crate::render::interface::{GpuBinding, GroupInterface};
use crate::settings::{LightPick, RenderSettings};
use bevy::prelude::*;
use bevy::render::render_resource::{
    BindGroup, BindGroupLayoutDescriptor, Buffer, BufferDescriptor, BufferUsages, PipelineCache,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::{Extract, ExtractSchedule, RenderApp, RenderStartup};
use std::sync::Arc;

/// Stages the light pool's changes (main world) and keeps its GPU copy (render world).
pub struct LightUploadPlugin;

impl Plugin for LightUploadPlugin {
    fn build(&self, app: &mut App) {
        add(app);
    }
}

fn add(app: &mut App) {
    app.init_resource::<LightUpload>()
        .init_resource::<LightUploadState>()
        .add_systems(PostUpdate, stage_light_upload.run_if(resource_exists::<LightPool>));
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
    render_app
        .init_resource::<PendingLightUploads>()
        .init_resource::<LightsLayout>()
        .add_systems(RenderStartup, init_scene_lighting)
        .add_systems(ExtractSchedule, extract_light_upload);
}

/// This frame's sun (or moon), sky and mode (`settings`) with the light count. Emitters-only modes carry the
/// time of day's values too; their shaders ignore them.
pub fn scene_lighting(settings: &RenderSettings, light_count: u32) -> SceneLighting {
    let day = Daylight::at(settings.time, settings.sun);
    let d = day.direction;
    SceneLighting {
        sun: [d.x, d.y, d.z, if day.disk_on() { 1.0 } else { 0.0 }],
        sun_radiance: day.disk.extend(day.cone).to_array(),
        sky_zenith: day.zenith.extend(0.0).to_array(),
        sky_horizon: day.horizon.extend(0.0).to_array(),
        mode: settings.lighting as u32,
        power_pick: (settings.pick == LightPick::Power) as u32,
        light_count,
        shadows: settings.shadows as u32,
    }
}

/// The `SceneLighting` uniform (created once, written every frame).
#[derive(Resource)]
pub struct SceneLightingBuffer(pub Buffer);

fn init_scene_lighting(mut commands: Commands, device: Res<RenderDevice>) {
    commands.insert_resource(SceneLightingBuffer(device.create_buffer(&BufferDescriptor {
        label: Some("glowbrick_scene_lighting"),
        size: size_of::<SceneLighting>() as u64,
        usage: BufferUsages::UNIFORM | BufferUsages::COPY_DST,
        mapped_at_creation: false,
    })));
}

/// A light slot as the shaders read it.
fn gpu_light(light: Option<&Light>, generation: u32) -> GpuLight {
    match light {
        Some(l) => GpuLight {
            min: l.min.to_array(),
            size_faces: l.size | (l.faces as i32) << LIGHT_FACES_SHIFT,
            radiance: l.radiance,
            generation,
        },
        None => GpuLight { generation, ..default() },
    }
}

/// This frame's light changes for the GPU.
#[derive(Resource, Clone, Debug, Default)]
pub struct LightUpload {
    /// Every slot, when the GPU buffer must be (re)created.
    pub full: Option<Arc<Vec<GpuLight>>>,
    /// Changed slots otherwise.
    pub slots: Vec<(u32, GpuLight)>,
    /// The alias table, when it changed.
    pub alias: Option<Arc<Vec<AliasEntry>>>,
    /// The light index (light cube -> alias column) and the light bricks, with the alias table (`gpu_light_index`).
    pub index: Option<Arc<Vec<u32>>>,
    pub light_count: u32,
}

impl LightUpload {
    pub fn is_empty(&self) -> bool {
        self.full.is_none() && self.slots.is_empty() && self.alias.is_none()
    }
}

/// GPU slot capacity already allocated, as the main world knows it.
#[derive(Resource, Default)]
pub struct LightUploadState {
    gpu_slots: Option<u32>,
}

/// Stages changed slots and a rebuilt alias table (PostUpdate, after the pool took this frame's edits).
pub fn stage_light_upload(
    mut pool: ResMut<LightPool>,
    mut state: ResMut<LightUploadState>,
    mut upload: ResMut<LightUpload>,
) {
    *upload = LightUpload { light_count: pool.len() as u32, ..default() };
    let changed = pool.take_changed();
    let slots = pool.slot_count();
    match state.gpu_slots {
        Some(capacity) if slots <= capacity => {
            for slot in changed {
                if let Some((light, generation)) = pool.slot(slot) {
                    upload.slots.push((slot, gpu_light(light, generation)));
                }
            }
        }
        _ => {
            // Headroom so a growing pool rarely reallocates.
            let capacity = (slots + slots / 2).max(64);
            let mut all: Vec<GpuLight> =
                (0..slots).filter_map(|s| pool.slot(s)).map(|(l, g)| gpu_light(l, g)).collect();
            all.resize(capacity as usize, GpuLight::default());
            upload.full = Some(Arc::new(all));
            state.gpu_slots = Some(capacity);
        }
    }
    if pool.alias_is_stale() || upload.full.is_some() {
        let entries = pool.alias().entries.clone();
        upload.alias = Some(Arc::new(entries));
        let index = pool.light_index().entries.clone();
        upload.index = Some(Arc::new(gpu_light_index(&index, pool.light_bricks())));
    }
}

/// Binding 3 of group 2 as `shaders/lib/lights.wgsl` reads it: the light index's capacity, its entries, then the
/// light bricks' words. One buffer rather than a binding of their own: a fifth binding in this group made
/// lavapipe's memory grow every frame while the GI cache ran (docs/bench/why.md).
pub fn gpu_light_index(entries: &[u32], bricks: &LightBricks) -> Vec<u32> {
    let mut words = Vec::with_capacity(1 + entries.len() + bricks.words().len());
    words.push(entries.len() as u32);
    words.extend_from_slice(entries);
    words.extend_from_slice(bricks.words());
    words
}

/// Render-world light buffers. Passes read `light_count` / `has_lights` to skip themselves.
#[derive(Resource)]
pub struct GpuLights {
    pub lights: Buffer,
    pub alias: Buffer,
    pub index: Buffer,
    pub light_count: u32,
    pub has_lights: bool,
    /// Group 2 of the voxel passes: slots, alias table, scene lighting, light index.
    pub bind_group: BindGroup,
    /// Whether the lights changed this frame (accumulation restarts).
    pub changed: bool,
}

/// Layout of the lights bind group.
#[derive(Resource, Clone)]
pub struct LightsLayout(pub BindGroupLayoutDescriptor);

impl Default for LightsLayout {
    fn default() -> Self {
        LightsLayout(lights_interface().layout())
    }
}

/// Group 2 (`shaders/lib/lights.wgsl`): the light pool, its alias table, this frame's scene lighting and the
/// light index.
pub fn lights_interface() -> GroupInterface {
    GroupInterface::new(
        2,
        "glowbrick_lights_layout",
        &[&[
            GpuBinding::read("lights"),
            GpuBinding::read("alias_table"),
            GpuBinding::uniform("scene", size_of::<SceneLighting>()),
            GpuBinding::read("light_index"),
        ]],
    )
}

/// Builds group 2 around the scene lighting uniform.
struct LightsBinding<'a> {
    device: &'a RenderDevice,
    cache: &'a PipelineCache,
    layout: &'a LightsLayout,
    scene: &'a Buffer,
}

impl LightsBinding<'_> {
    fn bind(&self, lights: &Buffer, alias: &Buffer, index: &Buffer) -> BindGroup {
        self.device.create_bind_group(
            "glowbrick_lights",
            &self.cache.get_bind_group_layout(&self.layout.0),
            &lights_interface().entries(vec![
                lights.as_entire_binding(),
                alias.as_entire_binding(),
                self.scene.as_entire_binding(),
                index.as_entire_binding(),
            ]),
        )
    }
}

/// Light uploads not yet written, merged per buffer in the order they were extracted.
#[derive(Resource, Default)]
pub struct PendingLightUploads {
    lights: Staging<GpuLight>,
    alias: Staging<AliasEntry>,
    index: Staging<u32>,
    /// The latest upload's light count (`None`: nothing extracted since the last write).
    light_count: Option<u32>,
    /// Whether any of the queued uploads changed a light.
    changed: bool,
}

impl PendingLightUploads {
    /// Queues one frame's upload behind the ones already pending.
    pub fn push(&mut self, upload: &LightUpload) {
        self.light_count = Some(upload.light_count);
        self.changed |= !upload.is_empty();
        if let Some(all) = &upload.full {
            self.lights.whole(all.clone());
        }
        for (slot, light) in &upload.slots {
            self.lights.range(*slot as u64, std::slice::from_ref(light));
        }
        if let Some(entries) = &upload.alias {
            self.alias.whole(padded_alias(entries));
        }
        if let Some(entries) = &upload.index {
            self.index.whole(padded_index(entries));
        }
    }
}

pub fn extract_light_upload(upload: Extract<Option<Res<LightUpload>>>, mut pending: ResMut<PendingLightUploads>) {
    if let Some(upload) = upload.as_ref() {
        // The count travels every frame so the skip flag is current; buffers only when something changed.
        pending.push(upload);
    }
}

/// Alias entries padded to at least one (storage buffers cannot be empty).
fn padded_alias(entries: &Arc<Vec<AliasEntry>>) -> Arc<Vec<AliasEntry>> {
    if entries.is_empty() { Arc::new(vec![AliasEntry::default()]) } else { entries.clone() }
}

/// The light index, one empty entry and no light brick when there is none yet.
fn padded_index(words: &Arc<Vec<u32>>) -> Arc<Vec<u32>> {
    if words.is_empty() { Arc::new(vec![1, crate::lights::index::NO_COLUMN, 0]) } else { words.clone() }
}

/// The slot buffer is sized by the main world (`arrayLength` bounds reservoir slots), so it is exactly its
/// contents; the alias table and the light index may be larger than what they hold (the index says its capacity).
const LIGHTS: Mirrored = Mirrored { label: "glowbrick_lights", fit: Fit::Exact };
const ALIAS: Mirrored = Mirrored { label: "glowbrick_light_alias", fit: Fit::AtLeast };
const INDEX: Mirrored = Mirrored { label: "glowbrick_light_index", fit: Fit::AtLeast };

/// Applies the queued light uploads and writes this frame's scene lighting.
#[allow(clippy::too_many_arguments)]
pub fn prepare_gpu_lights(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    cache: Res<PipelineCache>,
    layout: Res<LightsLayout>,
    scene: Res<SceneLightingBuffer>,
    settings: Option<Res<RenderSettings>>,
    mut pending: ResMut<PendingLightUploads>,
    mut gpu: Option<ResMut<GpuLights>>,
) {
    let binding = LightsBinding { device: &device, cache: &cache, layout: &layout, scene: &scene.0 };
    let mut batch = std::mem::take(&mut *pending);
    let light_count = batch.light_count.or(gpu.as_deref().map(|g| g.light_count)).unwrap_or(0);
    match gpu.as_deref_mut() {
        Some(gpu) => apply_light_uploads(gpu, &mut batch, &binding, &queue),
        None => {
            if let Some(created) = create_gpu_lights(&mut batch, &binding, &queue) {
                commands.insert_resource(created);
            }
        }
    }
    let settings = settings.map(|s| s.clone()).unwrap_or_default();
    queue.write_buffer(&scene.0, 0, bytemuck::bytes_of(&scene_lighting(&settings, light_count)));
}

/// The light buffers from a batch that holds a full upload (and whatever was queued behind it).
fn create_gpu_lights(
    batch: &mut PendingLightUploads,
    binding: &LightsBinding,
    queue: &RenderQueue,
) -> Option<GpuLights> {
    // Slot changes need the buffer of a full upload; the main world always sends one first.
    if !batch.lights.has_whole() {
        return None;
    }
    if !batch.alias.has_whole() {
        batch.alias.whole(padded_alias(&Arc::default()));
    }
    if !batch.index.has_whole() {
        batch.index.whole(padded_index(&Arc::default()));
    }
    let device = binding.device;
    let lights = upload(&mut batch.lights, None, LIGHTS, device, queue)?;
    let alias = upload(&mut batch.alias, None, ALIAS, device, queue)?;
    let index = upload(&mut batch.index, None, INDEX, device, queue)?;
    let light_count = batch.light_count.unwrap_or(0);
    Some(GpuLights {
        bind_group: binding.bind(&lights, &alias, &index),
        lights,
        alias,
        index,
        light_count,
        has_lights: light_count > 0,
        changed: true,
    })
}

/// Writes a batch into the existing light buffers, recreating (and rebinding) the ones whose size changed.
fn apply_light_uploads(
    gpu: &mut GpuLights,
    batch: &mut PendingLightUploads,
    binding: &LightsBinding,
    queue: &RenderQueue,
) {
    let device = binding.device;
    gpu.changed = batch.changed;
    if let Some(count) = batch.light_count {
        gpu.light_count = count;
        gpu.has_lights = count > 0;
    }
    // Every buffer is brought up to date (no short circuit), then bound again if any was created again.
    let recreated = [
        sync(&mut batch.lights, &mut gpu.lights, LIGHTS, device, queue),
        sync(&mut batch.alias, &mut gpu.alias, ALIAS, device, queue),
        sync(&mut batch.index, &mut gpu.index, INDEX, device, queue),
    ];
    if recreated.contains(&true) {
        gpu.bind_group = binding.bind(&gpu.lights, &gpu.alias, &gpu.index);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lights::index::NO_COLUMN;
    use bevy::math::{IVec3, UVec3};

    #[test]
    fn the_gpu_light_index_is_its_capacity_its_entries_then_the_light_bricks() {
        let bricks = LightBricks::build(UVec3::new(40, 1, 1), [IVec3::new(8 * 33, 0, 0)].into_iter());
        let words = gpu_light_index(&[7, 3, NO_COLUMN, 1], &bricks);
        assert_eq!(words, vec![4, 7, 3, NO_COLUMN, 1, 0, 1 << 1]);
        assert_eq!(*padded_index(&Arc::default()), vec![1, NO_COLUMN, 0]);
    }
}
