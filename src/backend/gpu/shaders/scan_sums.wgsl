// Compaction, step 2: one workgroup turns the groups' totals into each
// group's exclusive offset, with the grand total after the last. The
// grand total is the next level's length: it goes into the level's
// length words (its item count, then the workgroups of an indirect
// dispatch over it) and onto the film's count of secondary
// rays, so the CPU never waits for it.

@group(0) @binding(ITEMS) var<storage, read> block_totals: array<u32>;
@group(0) @binding(ANSWERS) var<storage, read_write> block_offsets: array<u32>;
@group(0) @binding(LEVEL_LENGTH) var<storage, read_write> level_length: array<u32, LEVEL_LENGTH_WORDS>;
@group(0) @binding(COUNTERS) var<storage, read_write> counters: array<atomic<u32>, FILM_COUNTERS>;

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
        // A level holds at most a batch (`scatter.rs`), so its
        // workgroups fit in x.
        level_length[0] = running;
        level_length[1] = (running + WORKGROUP - 1u) / WORKGROUP;
        level_length[2] = 1u;
        level_length[3] = 1u;
        atomicAdd(&counters[COUNTER_SECONDARY_RAYS], running);
    }
    workgroupBarrier();
    var offset = lane_sums[lane];
    for (var b = first; b < last; b++) {
        block_offsets[b] = offset;
        offset += block_totals[b];
    }
}
