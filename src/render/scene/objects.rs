//! Moving objects on the GPU: each frame the main world lists the objects (position, size, id, where their
//! voxels start), the render world writes them into two fixed-size buffers that group 0 binds next to the brick
//! grid (`shaders/lib/world.wgsl`: `objects`, `object_voxels`), and their count into the world's uniform.

use crate::dynamic::model::MAX_MODEL_EDGE;
use crate::dynamic::{DynamicObject, MAX_OBJECTS};
use crate::render::gpu_types::GpuObject;
use crate::render::interface::GpuBinding;
use bevy::prelude::*;
use bevy::render::extract_resource::{ExtractResource, ExtractResourcePlugin};
use bevy::render::render_resource::{Buffer, BufferDescriptor, BufferUsages};
use bevy::render::renderer::{RenderDevice, RenderQueue};
use bevy::render::{RenderApp, RenderStartup};
use std::sync::Arc;

/// Group 0's moving-objects part (`shaders/lib/world.wgsl`): the objects and their voxels.
pub const OBJECT_BINDINGS: [GpuBinding; 2] = [GpuBinding::read("objects"), GpuBinding::read("object_voxels")];

/// Voxel slots the GPU holds: every object at the largest model size.
const VOXEL_CAPACITY: usize = MAX_OBJECTS * (MAX_MODEL_EDGE * MAX_MODEL_EDGE * MAX_MODEL_EDGE) as usize;

/// This frame's objects for the render world; `voxels` is rebuilt only when the set of objects changes.
#[derive(Resource, ExtractResource, Clone, Default)]
pub struct ObjectsUpload {
    pub objects: Vec<GpuObject>,
    pub voxels: Arc<Vec<u32>>,
    /// Ids the voxels were packed for, in order.
    packed_ids: Vec<u32>,
}

/// Lists the objects (sorted by id, so the packing is stable) after this frame's motion (PostUpdate).
pub fn stage_objects(mut upload: ResMut<ObjectsUpload>, objects: Query<(&DynamicObject, &Transform)>) {
    let mut list: Vec<(&DynamicObject, &Transform)> = objects.iter().take(MAX_OBJECTS).collect();
    list.sort_by_key(|(o, _)| o.id);
    let ids: Vec<u32> = list.iter().map(|(o, _)| o.id).collect();
    let repack = ids != upload.packed_ids;
    let mut voxels = Vec::new();
    let mut offset = 0u32;
    let previous = std::mem::take(&mut upload.objects);
    upload.objects = list
        .iter()
        .map(|(object, transform)| {
            let m = &object.model;
            if repack {
                voxels.extend(m.voxels.iter().map(|&v| v as u32));
            }
            let min = transform.translation.to_array();
            let previous_min = previous.iter().find(|p| p.id == object.id).map_or(min, |p| p.min);
            let gpu = GpuObject { min, id: object.id, size: m.size.to_array(), offset, previous_min, _pad: 0 };
            offset += m.voxels.len() as u32;
            gpu
        })
        .collect();
    if repack {
        upload.voxels = Arc::new(voxels);
        upload.packed_ids = ids;
    }
}

/// The render world's object buffers (fixed size, created once) and what they hold.
#[derive(Resource)]
pub struct GpuObjects {
    pub objects: Buffer,
    pub voxels: Buffer,
    pub count: u32,
    /// Whether any object moved, appeared or went this frame (restarts accumulation).
    pub changed: bool,
    /// Whether an object appeared or went this frame (a change of light: the GI cache restarts its blends).
    pub set_changed: bool,
    last_objects: Vec<GpuObject>,
    last_voxels: Option<Arc<Vec<u32>>>,
}

fn init_gpu_objects(mut commands: Commands, device: Res<RenderDevice>) {
    let buffer = |label: &'static str, size: usize| {
        device.create_buffer(&BufferDescriptor {
            label: Some(label),
            size: size as u64,
            usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    };
    commands.insert_resource(GpuObjects {
        objects: buffer("glowbrick_objects", MAX_OBJECTS * size_of::<GpuObject>()),
        voxels: buffer("glowbrick_object_voxels", VOXEL_CAPACITY * 4),
        count: 0,
        changed: false,
        set_changed: false,
        last_objects: Vec::new(),
        last_voxels: None,
    });
}

/// Writes this frame's objects (Render, PrepareResources, after the world upload; the world then writes their
/// count into its uniform).
pub fn prepare_gpu_objects(upload: Option<Res<ObjectsUpload>>, mut gpu: ResMut<GpuObjects>, queue: Res<RenderQueue>) {
    let Some(upload) = upload else { return };
    gpu.changed = upload.objects != gpu.last_objects;
    if gpu.changed && !upload.objects.is_empty() {
        queue.write_buffer(&gpu.objects, 0, bytemuck::cast_slice(&upload.objects));
    }
    gpu.set_changed = !upload.objects.iter().map(|o| o.id).eq(gpu.last_objects.iter().map(|o| o.id));
    if gpu.last_voxels.as_ref().is_none_or(|v| !Arc::ptr_eq(v, &upload.voxels)) && !upload.voxels.is_empty() {
        let n = upload.voxels.len().min(VOXEL_CAPACITY);
        queue.write_buffer(&gpu.voxels, 0, bytemuck::cast_slice(&upload.voxels[..n]));
        gpu.last_voxels = Some(upload.voxels.clone());
    }
    gpu.count = upload.objects.len() as u32;
    gpu.last_objects = upload.objects.clone();
}

/// Lists the moving objects (main world) and keeps their GPU copy (render world).
pub struct ObjectUploadPlugin;

impl Plugin for ObjectUploadPlugin {
    fn build(&self, app: &mut App) {
        add(app);
    }
}

fn add(app: &mut App) {
    app.init_resource::<ObjectsUpload>()
        .add_plugins(ExtractResourcePlugin::<ObjectsUpload>::default())
        .add_systems(PostUpdate, stage_objects);
    let Some(render_app) = app.get_sub_app_mut(RenderApp) else { return };
    render_app.add_systems(RenderStartup, init_gpu_objects);
}
