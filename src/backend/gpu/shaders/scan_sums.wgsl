// Compaction, step 2: one workgroup turns the groups' totals into each
// group's exclusive offset, with the grand total after the last.

@group(0) @binding(ITEMS) var<storage, read> block_totals: array<u32>;
@group(0) @binding(ANSWERS) var<storage, read_write> block_offsets: array<u32>;

var<workgroup> lane_sums: array<u32, WORKGROUP>;

@compute @workgroup_size(WORKGROUP)
fn scan_sums(@builtin(local_invocation_index) lane: u32) {
    let blocks = arrayLength(&block_offsets) - 1u;
    let per_lane = (blocks + WORKGROUP - 1u) / WORKGROUP;
    let first = lane * per_lane;
    let last = min(first + per_lane, blocks);
    var sum = 0u;
    for (var b = first; b < last; b++) {
        sum += block_totals[b];
    }
    lane_sums[lane] = sum;
    workgroupBarrier();
    if lane == 0u {
        var running = 0u;
        for (var l = 0u; l < WORKGROUP; l++) {
            let own = lane_sums[l];
            lane_sums[l] = running;
            running += own;
        }
        block_offsets[blocks] = running;
    }
    workgroupBarrier();
    var offset = lane_sums[lane];
    for (var b = first; b < last; b++) {
        block_offsets[b] = offset;
        offset += block_totals[b];
    }
}
