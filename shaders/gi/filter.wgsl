// GI cache filter, one thread per slot: the value shading reads is the mean of the entry and its neighbours of
// the same face orientation in the 3x3x3 block around its voxel (filter on), or the entry's own value (off).
// Same orientation keeps the two sides of a one-voxel wall apart: the far side faces the other way.

#import glowbrick::gi::cache::{gi, gi_keys, gi_entries, gi_irradiance, gi_filtered, gi_find, used_within, is_live_key,
    next_slot, NOT_FOUND, UPDATE_AGE, EMPTY_KEY, FREED_KEY}
#import glowbrick::constants::GI_FILTER

// A freed slot followed by an empty one ends every chain through it anyway: make it empty, so misses stop
// early again. Safe here: no pass inserts while the filter runs, and a lookup that sees either word ends at the
// next slot at the latest. A run of freed slots clears from its end, one slot a frame.
fn clear_tombstone(slot: u32) {
    if atomicLoad(&gi_keys[next_slot(slot)]) == EMPTY_KEY {
        atomicStore(&gi_keys[slot], EMPTY_KEY);
    }
}

fn filter_entry(slot: u32) {
    let key = atomicLoad(&gi_keys[slot]);
    if key == FREED_KEY {
        clear_tombstone(slot);
        return;
    }
    if !is_live_key(key) {
        return;
    }
    let e = gi_entries[slot];
    if !used_within(e.last_used, UPDATE_AGE) || e.samples == 0u {
        return;
    }
    var filtered = gi_irradiance[slot].rgb;
    if (gi.flags & GI_FILTER) != 0u {
        var sum = vec3(0.0);
        var count = 0.0;
        // One loop over the 27 offsets, the entry itself included.
        for (var i = 0; i < 27; i++) {
            let offset = vec3(i % 3, (i / 3) % 3, i / 9) - vec3(1);
            let neighbour = gi_find(e.voxel + offset, e.face, e.object);
            if neighbour != NOT_FOUND && gi_entries[neighbour].samples > 0u {
                sum += gi_irradiance[neighbour].rgb;
                count += 1.0;
            }
        }
        filtered = sum / max(count, 1.0);
    }
    gi_filtered[slot] = vec4(filtered, 1.0);
}

@compute @workgroup_size(64, 1, 1)
fn filter_static(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < gi.static_capacity {
        filter_entry(id.x);
    }
}

// The moving objects' table (same orientation, same object), dispatched only while objects exist.
@compute @workgroup_size(64, 1, 1)
fn filter_dynamic(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x < gi.dynamic_capacity {
        filter_entry(gi.static_capacity + id.x);
    }
}
