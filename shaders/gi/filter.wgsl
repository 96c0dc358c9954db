// GI cache filter, one thread per entry due this frame (listed by compact.wgsl): the value shading reads is the
// mean of the entry and its neighbours of the same face orientation and level in the 3x3x3 block of cells
// around it (filter on), or the entry's own value (off).
// Same orientation keeps the two sides of a one-voxel wall apart: the far side faces the other way.

#import glowbrick::gi::cache::{gi_setting, gi, gi_entries, gi_irradiance, gi_filtered, gi_find, cell_of, listed_slot, NOT_FOUND, WORK_STATIC,
    WORK_DYNAMIC}
#import glowbrick::constants::GI_FILTER

fn filter_entry(slot: u32) {
    let e = gi_entries[slot];
    if e.samples == 0u {
        return;
    }
    var filtered = gi_irradiance[slot].rgb;
    // A coarse entry is a cell's average already: a 3x3x3 block of cells would blur light across 3 x 2^level
    // voxels and add bias (docs/bench/why.md).
    if gi_setting(GI_FILTER) && e.level == 0u {
        var sum = vec3(0.0);
        var count = 0.0;
        // One loop over the 27 offsets, the entry itself included.
        for (var i = 0; i < 27; i++) {
            let offset = vec3(i % 3, (i / 3) % 3, i / 9) - vec3(1);
            let neighbour = gi_find((cell_of(e.voxel, e.level) + offset) << vec3(e.level), e.face, e.object, e.level);
            if neighbour != NOT_FOUND && gi_entries[neighbour].samples > 0u {
                sum += gi_irradiance[neighbour].rgb;
                count += 1.0;
            }
        }
        filtered = sum / max(count, 1.0);
    }
    // w holds the entry's estimate variance (update.wgsl, blend_estimate).
    gi_filtered[slot] = vec4(filtered, gi_filtered[slot].a);
}

@compute @workgroup_size(64, 1, 1)
fn filter_static(@builtin(global_invocation_id) id: vec3<u32>) {
    let slot = listed_slot(WORK_STATIC, id.x);
    if slot != NOT_FOUND {
        filter_entry(slot);
    }
}

// The moving objects' table (same orientation, same object), dispatched only while objects exist.
@compute @workgroup_size(64, 1, 1)
fn filter_dynamic(@builtin(global_invocation_id) id: vec3<u32>) {
    let slot = listed_slot(WORK_DYNAMIC, id.x);
    if slot != NOT_FOUND {
        filter_entry(slot);
    }
}
