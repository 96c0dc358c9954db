// GI cache work lists, one thread per slot of both tables, first of the GI passes: ages each entry (frees one
// unused for MAX_AGE frames, whose moving object is gone or whose face was lost; clears a tombstone that ends its
// chain) and appends every entry due this frame to its table's list. The refresh, update and filter passes then
// run one thread per listed entry by indirect dispatch, so their SIMD lanes all hold work (live entries are a
// minority of the slots, at hash-random places). Counts are summed per workgroup and added to memory once per workgroup.

#import glowbrick::world::{object_index, object_count}
#import glowbrick::counters::counters
#import glowbrick::constants::{GI_RESTART, COUNT_GI_LIVE, COUNT_GI_EVICTED, COUNT_GI_UPDATED,
    COUNT_GI_FREED_TOTAL}
#import glowbrick::gi::cache::{gi, gi_keys, gi_entries, gi_direct, gi_work, gi_list, used_within, is_live_key, next_slot, forget_value,
    UPDATE_AGE, MAX_AGE, settled, settled_turn, LOST_FACE, FREED_KEY, EMPTY_KEY, WORK_STATIC, WORK_DYNAMIC, WORK_COUNT}

var<workgroup> due_in_group: atomic<u32>;
var<workgroup> live_in_group: atomic<u32>;
var<workgroup> evicted_in_group: atomic<u32>;
var<workgroup> list_start: u32;

// A freed slot followed by an empty one ends every chain through it anyway: make it empty, so misses stop
// early again. Safe here: no pass inserts while this runs, and a lookup that sees either word ends at the next
// slot at the latest. A run of freed slots clears from its end, one slot a frame.
fn clear_tombstone(slot: u32) {
    if atomicLoad(&gi_keys[slot]) == FREED_KEY && atomicLoad(&gi_keys[next_slot(slot)]) == EMPTY_KEY {
        atomicStore(&gi_keys[slot], EMPTY_KEY);
    }
}

// Ages the entry in `slot`; whether it is due this frame (used within UPDATE_AGE frames).
fn age_entry(slot: u32) -> bool {
    if !is_live_key(atomicLoad(&gi_keys[slot])) {
        clear_tombstone(slot);
        return false;
    }
    let e = gi_entries[slot];
    // Only a moving object's entry looks its object up (a scan of the object list).
    let gone = e.object != 0u && object_index(e.object) == object_count();
    // A coarse entry whose inserting face went (marked by refresh.wgsl, which reads the grid: reading it here
    // leaked host memory on lavapipe every frame, see docs/bench/stress.md).
    let lost_face = e.traced_epoch == LOST_FACE;
    if !used_within(e.last_used, MAX_AGE) || gone || lost_face {
        // A tombstone, not an empty slot: entries inserted further along the chain stay reachable.
        atomicStore(&gi_keys[slot], FREED_KEY);
        forget_value(slot);
        atomicAdd(&evicted_in_group, 1u);
        return false;
    }
    atomicAdd(&live_in_group, 1u);
    // A settled static entry updates one frame in gi.period (GiSettings::period).
    let due = used_within(e.last_used, UPDATE_AGE) && (e.object != 0u || !settled(e.samples) || settled_turn(slot));
    // After a change of light an entry that is not updated this frame (unused for UPDATE_AGE frames) still holds
    // the old light: it has no value until it is due again, so the filter and the rays that find it skip it
    // rather than read the old light until it is freed.
    if !due && (gi.flags & GI_RESTART) != 0u && e.samples != 0u {
        forget_value(slot);
        gi_direct[slot].light = vec4(0.0);
    }
    return due;
}

@compute @workgroup_size(64, 1, 1)
fn compact(@builtin(global_invocation_id) id: vec3<u32>, @builtin(local_invocation_index) local: u32) {
    let slot = id.x;
    let slots = gi.static_capacity + gi.dynamic_capacity;
    // Both capacities are multiples of 64: a workgroup lies in one table.
    let work = select(WORK_STATIC, WORK_DYNAMIC, slot >= gi.static_capacity);
    // Workgroup memory starts undefined (pipelines do not ask for it zeroed).
    if local == 0u {
        atomicStore(&due_in_group, 0u);
        atomicStore(&live_in_group, 0u);
        atomicStore(&evicted_in_group, 0u);
    }
    workgroupBarrier();
    var due = false;
    if slot < slots {
        due = age_entry(slot);
    }
    var index = 0u;
    if due {
        index = atomicAdd(&due_in_group, 1u);
    }
    workgroupBarrier();
    if local == 0u {
        let count = atomicLoad(&due_in_group);
        let start = atomicAdd(&gi_work[work + WORK_COUNT], count);
        list_start = start;
        // The dispatch size: counts only grow, so the largest workgroup count any group saw is the final one.
        atomicMax(&gi_work[work], (start + count + 63u) / 64u);
        atomicAdd(&counters[COUNT_GI_LIVE], atomicLoad(&live_in_group));
        let evicted = atomicLoad(&evicted_in_group);
        atomicAdd(&counters[COUNT_GI_EVICTED], evicted);
        atomicAdd(&counters[COUNT_GI_FREED_TOTAL], evicted);
        atomicAdd(&counters[COUNT_GI_UPDATED], count);
    }
    workgroupBarrier();
    if due {
        let base = select(0u, gi.static_capacity, work == WORK_DYNAMIC);
        gi_list[base + list_start + index] = slot;
    }
}
