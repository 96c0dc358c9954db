//! The GI cache's GPU tables: the two hash tables (the static world's, sized by `gi_table`, and the moving
//! objects') in one set of buffers, and the work buffer the compaction pass fills with this frame's dispatches.

use crate::render::gpu_types::{
    GI_EMPTY_WORK, GI_KEY_BYTES, GI_NO_VALUE, GI_RADIANCE_BYTES, GI_RAY_BYTES, GI_WORK_DYNAMIC_WORD,
    GI_WORK_STATIC_WORD, GI_WORK_WORDS, GiDirect, GiEntry,
};
use crate::settings::GiSettings;
use bevy::render::render_resource::{Buffer, BufferDescriptor, BufferInitDescriptor, BufferUsages};
use bevy::render::renderer::RenderDevice;

/// Entries in the moving objects' table (a power of two; the static world's is the `gi_table` setting).
pub const DYNAMIC_CAPACITY: u32 = 1 << 12;
/// GPU bytes per entry besides its rays: key, payload, blended and filtered radiance, direct light and its light
/// reservoir, its place in the work list.
pub const ENTRY_BYTES: u64 =
    GI_KEY_BYTES + size_of::<GiEntry>() as u64 + 2 * GI_RADIANCE_BYTES + size_of::<GiDirect>() as u64 + 4;
/// Bytes per cached ray (face and distance packed in a u32).
pub const RAY_BYTES: u64 = GI_RAY_BYTES;
/// Where the static and the dynamic table's dispatch sizes lie in the work buffer (x, y, z, then the count).
pub const WORK_STATIC: u64 = 4 * GI_WORK_STATIC_WORD as u64;
pub const WORK_DYNAMIC: u64 = 4 * GI_WORK_DYNAMIC_WORD as u64;

/// What the table buffers were sized for: nothing (GI off) or the static table's entries (the `gi_table` setting,
/// a power of two) and K rays per entry; the dynamic table follows the static one in the same buffers.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Shape {
    pub static_entries: u32,
    pub dynamic_entries: u32,
    pub rays: u32,
}

impl Shape {
    /// The shape for `settings` on a device whose storage bindings hold at most `max_binding` bytes: the static
    /// table halves (down to 4,096 slots) until its rays buffer, the largest, fits (`gi_table` at 262,144 with
    /// `gi_cached_rays=128` needs 136 MB; lavapipe binds 128 MiB).
    pub fn of(settings: &GiSettings, max_binding: u64) -> Shape {
        if settings.enabled {
            // Without the static visibility cache no hit is kept: one placeholder ray per entry.
            let rays = if settings.cache { settings.rays } else { 1 };
            let bytes = |entries: u32| (entries + DYNAMIC_CAPACITY) as u64 * rays as u64 * RAY_BYTES;
            let mut static_entries = static_capacity(settings);
            while bytes(static_entries) > max_binding && static_entries > 4096 {
                static_entries /= 2;
            }
            Shape { static_entries, dynamic_entries: DYNAMIC_CAPACITY, rays }
        } else {
            // Bindings need a non-empty buffer: one entry, one ray and the work buffers cost 252 bytes.
            Shape { static_entries: 1, dynamic_entries: 0, rays: 1 }
        }
    }

    pub fn entries(&self) -> u32 {
        self.static_entries + self.dynamic_entries
    }

    /// Whether the device's binding limit cut the static table below the `gi_table` asked for (never with GI
    /// off, whose placeholder holds one slot whatever the setting).
    pub fn halved(&self, settings: &GiSettings) -> bool {
        settings.enabled && self.static_entries < static_capacity(settings)
    }
}

/// The static table's slots for `settings`: the `gi_table` setting rounded up to a power of two (the probe
/// sequence masks with it), at least 64 (a compaction workgroup lies in one table).
pub fn static_capacity(settings: &GiSettings) -> u32 {
    settings.table.clamp(64, 1 << 30).next_power_of_two()
}

/// GPU bytes the cache holds for `settings` (with GI off a 252-byte placeholder), on a device that binds
/// buffers of any size (a smaller limit halves the table: `Shape::of`).
pub fn cache_bytes(settings: &GiSettings) -> u64 {
    let shape = Shape::of(settings, u64::MAX);
    shape.entries() as u64 * (ENTRY_BYTES + shape.rays as u64 * RAY_BYTES) + 2 * WORK_BYTES
}

/// The cache's buffers: each holds both tables, the moving objects' slots after the static world's.
pub struct Tables {
    pub keys: Buffer,
    pub entries: Buffer,
    pub irradiance: Buffer,
    pub filtered: Buffer,
    pub rays: Buffer,
    /// Each entry's direct light and light reservoir (`gi_direct`).
    pub direct: Buffer,
    /// This frame's work: dispatch sizes and counts (`gi_work`), and the listed slots (`gi_list`).
    pub work: Buffer,
    pub list: Buffer,
    /// The work buffer's copy the listed passes take their dispatch sizes from (a buffer bound for writing
    /// cannot also be a dispatch's indirect argument).
    pub arguments: Buffer,
}

impl Tables {
    pub fn new(device: &RenderDevice, shape: Shape) -> Tables {
        let buffer = |label: &'static str, bytes: u64, usage: BufferUsages| {
            device.create_buffer(&BufferDescriptor {
                label: Some(label),
                size: bytes.max(16),
                usage: usage | BufferUsages::STORAGE | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            })
        };
        let storage = |label: &'static str, bytes: u64| buffer(label, bytes, BufferUsages::empty());
        let n = shape.entries() as u64;
        Tables {
            keys: storage("glowbrick_gi_keys", n * GI_KEY_BYTES),
            entries: storage("glowbrick_gi_entries", n * size_of::<GiEntry>() as u64),
            irradiance: storage("glowbrick_gi_irradiance", n * GI_RADIANCE_BYTES),
            filtered: no_values(device, n),
            rays: storage("glowbrick_gi_rays", n * shape.rays as u64 * RAY_BYTES),
            direct: storage("glowbrick_gi_direct", n * size_of::<GiDirect>() as u64),
            work: buffer("glowbrick_gi_work", WORK_BYTES, BufferUsages::COPY_SRC),
            list: storage("glowbrick_gi_list", n * 4),
            arguments: device.create_buffer(&BufferDescriptor {
                label: Some("glowbrick_gi_arguments"),
                size: WORK_BYTES,
                usage: BufferUsages::INDIRECT | BufferUsages::COPY_DST,
                mapped_at_creation: false,
            }),
        }
    }
}

/// The filtered radiance of `n` entries, none of which holds a value yet (`GI_NO_VALUE`): every slot starts as `forget_value`
/// leaves one (a zeroed buffer would read as black light to a ray that finds an entry before its claim's
/// writes are seen).
fn no_values(device: &RenderDevice, n: u64) -> Buffer {
    let none = GI_NO_VALUE as f32;
    let colours = vec![[none, none, none, 0.0f32]; (n * GI_RADIANCE_BYTES).max(16) as usize / 16];
    device.create_buffer_with_data(&BufferInitDescriptor {
        label: Some("glowbrick_gi_filtered"),
        contents: bytemuck::cast_slice(&colours),
        usage: BufferUsages::STORAGE | BufferUsages::COPY_DST,
    })
}

/// The work buffer: per table three dispatch sizes and a count.
pub const WORK_BYTES: u64 = 4 * GI_WORK_WORDS as u64;
/// What the work buffer holds before compaction: no workgroups (y = z = 1) and no entries listed.
pub const EMPTY_WORK: [u32; GI_WORK_WORDS as usize] = GI_EMPTY_WORK;

#[cfg(test)]
mod tests {
    use super::*;

    /// A table whose rays would not fit one binding halves until they do; one that fits keeps its setting.
    #[test]
    fn the_table_shrinks_to_what_the_device_binds() {
        let settings = |rays: u32| GiSettings { enabled: true, rays, cache: true, ..GiSettings::default() };
        let lavapipe = 128 << 20;
        assert_eq!(Shape::of(&settings(64), lavapipe).static_entries, 1 << 18);
        let shrunk = Shape::of(&settings(128), lavapipe);
        assert_eq!(shrunk.static_entries, 1 << 17);
        assert!((shrunk.entries() as u64) * 128 * RAY_BYTES <= lavapipe);
        assert_eq!(Shape::of(&settings(128), 1 << 10).static_entries, 4096, "never below 4,096 slots");
        assert!(shrunk.halved(&settings(128)) && !Shape::of(&settings(64), lavapipe).halved(&settings(64)));
        // Without the visibility cache no hits are kept: the whole table fits whatever K.
        let fresh = GiSettings { enabled: true, rays: 128, cache: false, ..GiSettings::default() };
        assert_eq!(Shape::of(&fresh, lavapipe).static_entries, 1 << 18);
        assert_eq!(Shape::of(&fresh, lavapipe).rays, 1);
        // GI off holds a one-slot placeholder: not a table cut to fit (the soak warned "holds 1 slots").
        let off = GiSettings { enabled: false, ..GiSettings::default() };
        assert!(!Shape::of(&off, lavapipe).halved(&off));
    }
}
