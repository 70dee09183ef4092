// Compaction, step 1: each workgroup's counts (one per lane) scanned in
// workgroup memory into exclusive offsets within the workgroup, and the
// group's total. Integer sums: the order of the additions cannot change them.

@group(0) @binding(ITEMS) var<storage, read> counts: array<u32>;
@group(0) @binding(ANSWERS) var<storage, read_write> local_offsets: array<u32>;
@group(0) @binding(SECOND_OUTPUT) var<storage, read_write> block_totals: array<u32>;

var<workgroup> scanned: array<u32, WORKGROUP>;

@compute @workgroup_size(WORKGROUP)
fn scan_blocks(
    @builtin(global_invocation_id) id: vec3<u32>,
    @builtin(local_invocation_index) lane: u32,
    @builtin(workgroup_id) group: vec3<u32>,
) {
    var count = 0u;
    if id.x < params.item_count {
        count = counts[id.x];
    }
    scanned[lane] = count;
    workgroupBarrier();
    // Hillis–Steele: after the step of width w each lane holds the sum
    // of the 2w lanes ending at it.
    for (var width = 1u; width < WORKGROUP; width *= 2u) {
        var add = 0u;
        if lane >= width {
            add = scanned[lane - width];
        }
        workgroupBarrier();
        scanned[lane] += add;
        workgroupBarrier();
    }
    if id.x < params.item_count {
        local_offsets[id.x] = scanned[lane] - count;
    }
    if lane == WORKGROUP - 1u {
        block_totals[group.x] = scanned[WORKGROUP - 1u];
    }
}
