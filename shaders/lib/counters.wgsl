// The counters every pass may add to (GpuCounter in src/render/gpu_types.rs; indices COUNT_* in
// glowbrick::constants). Group 0: they belong to the scene, not to a technique. Tests, the bench and the stress
// run read them back.
#define_import_path glowbrick::counters

@group(0) @binding(10) var<storage, read_write> counters: array<atomic<u32>>;

