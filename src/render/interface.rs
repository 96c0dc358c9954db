//! Each bind group's GPU interface, declared once: the name of every WGSL global it binds and how the shaders
//! access it, in binding order. The layouts are built from these declarations and the bind groups are checked
//! against their length; `tests/cpu/shaders_validate.rs` checks every `@group/@binding var<..>` of `shaders/`
//! against them, so a wrong binding number or access mode fails on the CPU, not in wgpu's validation on a GPU.

use bevy::render::render_resource::binding_types::{
    storage_buffer_read_only_sized, storage_buffer_sized, texture_storage_2d, uniform_buffer, uniform_buffer_sized,
};
use bevy::render::render_resource::{
    BindGroupEntry, BindGroupLayoutDescriptor, BindGroupLayoutEntry, BindingResource, ShaderStages,
    StorageTextureAccess, TextureFormat,
};
use bevy::render::view::ViewUniform;
use std::num::NonZeroU64;

/// How the shaders see one binding.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Access {
    /// `var<uniform>` of a struct this many bytes long.
    Uniform(u64),
    /// `var<uniform> view: View`, Bevy's view uniform at a dynamic offset.
    ViewUniform,
    /// `var<storage, read>`.
    Read,
    /// `var<storage, read_write>`.
    ReadWrite,
    /// `texture_storage_2d<rgba16float, write>`: the view's output.
    OutputTexture,
}

/// One binding: the WGSL global's name and its access.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct GpuBinding {
    pub name: &'static str,
    pub access: Access,
}

impl GpuBinding {
    pub const fn read(name: &'static str) -> Self {
        GpuBinding { name, access: Access::Read }
    }

    pub const fn read_write(name: &'static str) -> Self {
        GpuBinding { name, access: Access::ReadWrite }
    }

    pub const fn uniform(name: &'static str, bytes: usize) -> Self {
        GpuBinding { name, access: Access::Uniform(bytes as u64) }
    }

    fn layout_entry(&self, binding: u32) -> BindGroupLayoutEntry {
        let builder = match self.access {
            Access::Uniform(bytes) => uniform_buffer_sized(false, NonZeroU64::new(bytes)),
            Access::ViewUniform => uniform_buffer::<ViewUniform>(true),
            Access::Read => storage_buffer_read_only_sized(false, None),
            Access::ReadWrite => storage_buffer_sized(false, None),
            Access::OutputTexture => texture_storage_2d(TextureFormat::Rgba16Float, StorageTextureAccess::WriteOnly),
        };
        builder.build(binding, ShaderStages::COMPUTE)
    }
}

/// A bind group's interface: its group index and its bindings, numbered by position from 0.
#[derive(Clone, Debug)]
pub struct GroupInterface {
    pub group: u32,
    pub label: &'static str,
    pub bindings: Vec<GpuBinding>,
}

impl GroupInterface {
    pub fn new(group: u32, label: &'static str, parts: &[&[GpuBinding]]) -> Self {
        GroupInterface { group, label, bindings: parts.concat() }
    }

    /// The binding number of the global `name`.
    pub fn binding(&self, name: &str) -> u32 {
        let index = self.bindings.iter().position(|b| b.name == name);
        index.unwrap_or_else(|| panic!("{} declares no binding {name}", self.label)) as u32
    }

    /// The bind group layout, binding `i` from declaration `i`.
    pub fn layout(&self) -> BindGroupLayoutDescriptor {
        let entries: Vec<BindGroupLayoutEntry> =
            self.bindings.iter().enumerate().map(|(i, b)| b.layout_entry(i as u32)).collect();
        BindGroupLayoutDescriptor::new(self.label, &entries)
    }

    /// The bind group's entries, resource `i` at binding `i`; one resource for each declared binding.
    pub fn entries<'a>(&self, resources: Vec<BindingResource<'a>>) -> Vec<BindGroupEntry<'a>> {
        assert_eq!(resources.len(), self.bindings.len(), "{}: one resource for each declared binding", self.label);
        resources.into_iter().enumerate().map(|(i, resource)| BindGroupEntry { binding: i as u32, resource }).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each declaration becomes the layout entry its access says, at its position.
    #[test]
    fn a_layout_follows_its_declarations_in_order() {
        let group = GroupInterface::new(
            5,
            "test",
            &[&[GpuBinding::uniform("a", 16)], &[GpuBinding::read("b"), GpuBinding::read_write("c")]],
        );
        let layout = group.layout();
        let types: Vec<_> = layout.entries.iter().map(|e| (e.binding, e.ty)).collect();
        use bevy::render::render_resource::{BindingType, BufferBindingType};
        let buffer = |ty, min| BindingType::Buffer { ty, has_dynamic_offset: false, min_binding_size: min };
        assert_eq!(
            types,
            [
                (0, buffer(BufferBindingType::Uniform, NonZeroU64::new(16))),
                (1, buffer(BufferBindingType::Storage { read_only: true }, None)),
                (2, buffer(BufferBindingType::Storage { read_only: false }, None)),
            ]
        );
    }
}
