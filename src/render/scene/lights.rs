//! The scene's lighting on the GPU (group 2 of every voxel pass, `shaders/lib/lights.wgsl`): the light pool's
//! changed slots, its alias table and light index when they changed, and this frame's `SceneLighting` (sun, sky, mode, light
//! count). Staged in the main world (PostUpdate), written to GPU buffers in the render world (PrepareResources).

use super::storage_buffer;
use crate::lights::daylight::Daylight;
use crate::lights::{AliasEntry, Light, LightPool};
use crate::render::gpu_types::{GpuLight, LIGHT_FACES_SHIFT, SceneLighting};
use crate::settings::{LightPick, RenderSettings};
use bevy::prelude::*;
use bevy::render::render_resource::binding_types::{storage_buffer_read_only_sized, uniform_buffer_sized};
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, Buffer, BufferDescriptor,
    BufferUsages, PipelineCache, ShaderStages,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::{Extract, ExtractSchedule, RenderApp, RenderStartup};
use std::num::NonZeroU64;
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
    /// The light index (light cube -> alias column), with the alias table.
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
        upload.index = Some(Arc::new(pool.light_index().entries.clone()));
    }
}

/// Render-world light buffers. Passes read `light_count` / `has_lights` to skip themselves.
#[derive(Resource)]
pub struct GpuLights {
    pub lights: Buffer,
    pub alias: Buffer,
    pub alias_capacity: u32,
    pub index: Buffer,
    pub index_capacity: u32,
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
        LightsLayout(BindGroupLayoutDescriptor::new(
            "glowbrick_lights_layout",
            &BindGroupLayoutEntries::sequential(
                ShaderStages::COMPUTE,
                (
                    storage_buffer_read_only_sized(false, None),
                    storage_buffer_read_only_sized(false, None),
                    uniform_buffer_sized(false, NonZeroU64::new(size_of::<SceneLighting>() as u64)),
                    storage_buffer_read_only_sized(false, None),
                ),
            ),
        ))
    }
}

fn lights_bind_group(
    device: &RenderDevice,
    cache: &PipelineCache,
    layout: &LightsLayout,
    buffers: [&Buffer; 4],
) -> BindGroup {
    let [lights, alias, scene, index] = buffers;
    device.create_bind_group(
        "glowbrick_lights",
        &cache.get_bind_group_layout(&layout.0),
        &BindGroupEntries::sequential((
            lights.as_entire_binding(),
            alias.as_entire_binding(),
            scene.as_entire_binding(),
            index.as_entire_binding(),
        )),
    )
}

/// Uploads not yet written, in order.
#[derive(Resource, Default)]
pub struct PendingLightUploads(pub Vec<LightUpload>);

pub fn extract_light_upload(upload: Extract<Option<Res<LightUpload>>>, mut pending: ResMut<PendingLightUploads>) {
    if let Some(upload) = upload.as_ref() {
        // The count travels every frame so the skip flag is current; buffers only when something changed.
        pending.0.push((**upload).clone());
    }
}

/// Alias entries padded to at least one (storage buffers cannot be empty).
fn alias_bytes(entries: &[AliasEntry]) -> Vec<u8> {
    let padded: Vec<AliasEntry> = if entries.is_empty() { vec![AliasEntry::default()] } else { entries.to_vec() };
    bytemuck::cast_slice(&padded).to_vec()
}

/// The light index, one empty entry when there is none yet.
fn index_bytes(entries: &[u32]) -> Vec<u8> {
    let padded: &[u32] = if entries.is_empty() { &[crate::lights::index::NO_COLUMN] } else { entries };
    bytemuck::cast_slice(padded).to_vec()
}

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
    if let Some(gpu) = gpu.as_deref_mut() {
        gpu.changed = false;
    }
    // The count after this frame's uploads (a first `GpuLights` is only inserted at the end of the system).
    let mut light_count = gpu.as_deref().map_or(0, |g| g.light_count);
    for upload in pending.0.drain(..) {
        light_count = upload.light_count;
        if let Some(all) = &upload.full {
            let lights = storage_buffer(&device, "glowbrick_lights", bytemuck::cast_slice(all));
            let entries = upload.alias.as_deref().map_or(&[][..], |a| a.as_slice());
            let alias = storage_buffer(&device, "glowbrick_light_alias", &alias_bytes(entries));
            let index_entries = upload.index.as_deref().map_or(&[][..], |i| i.as_slice());
            let index = storage_buffer(&device, "glowbrick_light_index", &index_bytes(index_entries));
            let bind_group = lights_bind_group(&device, &cache, &layout, [&lights, &alias, &scene.0, &index]);
            let fresh = GpuLights {
                lights,
                alias,
                alias_capacity: entries.len().max(1) as u32,
                index,
                index_capacity: index_entries.len().max(1) as u32,
                light_count: upload.light_count,
                has_lights: upload.light_count > 0,
                bind_group,
                changed: true,
            };
            match gpu.as_deref_mut() {
                Some(existing) => *existing = fresh,
                None => commands.insert_resource(fresh),
            }
            continue;
        }
        let Some(gpu) = gpu.as_deref_mut() else { continue };
        gpu.changed |= !upload.is_empty();
        for (slot, light) in &upload.slots {
            queue.write_buffer(&gpu.lights, *slot as u64 * size_of::<GpuLight>() as u64, bytemuck::bytes_of(light));
        }
        let mut rebind = false;
        if let Some(entries) = &upload.alias {
            if entries.len() as u32 > gpu.alias_capacity {
                gpu.alias = storage_buffer(&device, "glowbrick_light_alias", &alias_bytes(entries));
                gpu.alias_capacity = entries.len() as u32;
                rebind = true;
            } else if !entries.is_empty() {
                queue.write_buffer(&gpu.alias, 0, bytemuck::cast_slice(entries));
            }
        }
        if let Some(entries) = &upload.index {
            // The shader masks with arrayLength - 1: the buffer is exactly the table, never larger.
            if entries.len() as u32 != gpu.index_capacity {
                gpu.index = storage_buffer(&device, "glowbrick_light_index", &index_bytes(entries));
                gpu.index_capacity = entries.len().max(1) as u32;
                rebind = true;
            } else {
                queue.write_buffer(&gpu.index, 0, &index_bytes(entries));
            }
        }
        if rebind {
            gpu.bind_group =
                lights_bind_group(&device, &cache, &layout, [&gpu.lights, &gpu.alias, &scene.0, &gpu.index]);
        }
        gpu.light_count = upload.light_count;
        gpu.has_lights = upload.light_count > 0;
    }
    let settings = settings.map(|s| s.clone()).unwrap_or_default();
    queue.write_buffer(&scene.0, 0, bytemuck::bytes_of(&scene_lighting(&settings, light_count)));
}
