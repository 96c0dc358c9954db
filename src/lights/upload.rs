//! GPU copy of the light pool: changed slots only, the alias table when it changed, and the light count with a
//! "no lights" flag for passes that can be skipped. Staged in the main world (PostUpdate), written to GPU
//! buffers in the render world (PrepareResources), like the world upload in `render::upload`.

use super::{AliasEntry, Light, LightPool};
use crate::render::gpu_world::storage_buffer;
use bevy::prelude::*;
use bevy::render::Extract;
use bevy::render::render_resource::binding_types::storage_buffer_read_only_sized;
use bevy::render::render_resource::{
    BindGroup, BindGroupEntries, BindGroupLayoutDescriptor, BindGroupLayoutEntries, Buffer, PipelineCache, ShaderStages,
};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use std::sync::Arc;

/// One light slot as shaders read it; `size == 0` marks a free slot.
#[derive(Clone, Copy, Debug, Default, PartialEq, bytemuck::Pod, bytemuck::Zeroable)]
#[repr(C)]
pub struct GpuLight {
    pub min: [i32; 3],
    /// Edge in voxels (bits 0-7; 0 marks a free slot) and the exposed-face mask (bits 8-13).
    pub size_faces: i32,
    pub radiance: [f32; 3],
    pub generation: u32,
}

impl GpuLight {
    pub fn new(light: Option<&Light>, generation: u32) -> Self {
        match light {
            Some(l) => GpuLight {
                min: l.min.to_array(),
                size_faces: l.size | (l.faces as i32) << 8,
                radiance: l.radiance,
                generation,
            },
            None => GpuLight { generation, ..default() },
        }
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
                    upload.slots.push((slot, GpuLight::new(light, generation)));
                }
            }
        }
        _ => {
            // Headroom so a growing pool rarely reallocates.
            let capacity = (slots + slots / 2).max(64);
            let mut all: Vec<GpuLight> =
                (0..slots).filter_map(|s| pool.slot(s)).map(|(l, g)| GpuLight::new(l, g)).collect();
            all.resize(capacity as usize, GpuLight::default());
            upload.full = Some(Arc::new(all));
            state.gpu_slots = Some(capacity);
        }
    }
    if pool.alias_is_stale() || upload.full.is_some() {
        let entries = pool.alias().entries.clone();
        upload.alias = Some(Arc::new(entries));
    }
}

/// Render-world light buffers. Passes read `light_count` / `has_lights` to skip themselves.
#[derive(Resource)]
pub struct GpuLights {
    pub lights: Buffer,
    pub alias: Buffer,
    pub alias_capacity: u32,
    pub light_count: u32,
    pub has_lights: bool,
    /// Group 2 of the lighting passes (`shaders/lights.wgsl`): slots, then alias table.
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
                (storage_buffer_read_only_sized(false, None), storage_buffer_read_only_sized(false, None)),
            ),
        ))
    }
}

fn lights_bind_group(
    device: &RenderDevice,
    cache: &PipelineCache,
    layout: &LightsLayout,
    lights: &Buffer,
    alias: &Buffer,
) -> BindGroup {
    device.create_bind_group(
        "glowbrick_lights",
        &cache.get_bind_group_layout(&layout.0),
        &BindGroupEntries::sequential((lights.as_entire_binding(), alias.as_entire_binding())),
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

pub fn prepare_gpu_lights(
    mut commands: Commands,
    device: Res<RenderDevice>,
    queue: Res<RenderQueue>,
    cache: Res<PipelineCache>,
    layout: Res<LightsLayout>,
    mut pending: ResMut<PendingLightUploads>,
    mut gpu: Option<ResMut<GpuLights>>,
) {
    if let Some(gpu) = gpu.as_deref_mut() {
        gpu.changed = false;
    }
    for upload in pending.0.drain(..) {
        if let Some(all) = &upload.full {
            let lights = storage_buffer(&device, "glowbrick_lights", bytemuck::cast_slice(all));
            let entries = upload.alias.as_deref().map_or(&[][..], |a| a.as_slice());
            let alias = storage_buffer(&device, "glowbrick_light_alias", &alias_bytes(entries));
            let bind_group = lights_bind_group(&device, &cache, &layout, &lights, &alias);
            let fresh = GpuLights {
                lights,
                alias,
                alias_capacity: entries.len().max(1) as u32,
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
        if let Some(entries) = &upload.alias {
            if entries.len() as u32 > gpu.alias_capacity {
                gpu.alias = storage_buffer(&device, "glowbrick_light_alias", &alias_bytes(entries));
                gpu.alias_capacity = entries.len() as u32;
                gpu.bind_group = lights_bind_group(&device, &cache, &layout, &gpu.lights, &gpu.alias);
            } else if !entries.is_empty() {
                queue.write_buffer(&gpu.alias, 0, bytemuck::cast_slice(entries));
            }
        }
        gpu.light_count = upload.light_count;
        gpu.has_lights = upload.light_count > 0;
    }
}
