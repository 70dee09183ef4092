// Compaction, step 3: each point's rays from its slots to their place in
// the next level, in point order.

@group(0) @binding(ITEMS) var<storage, read> counts: array<u32>;
@group(0) @binding(SLOTS) var<storage, read> slots: array<PathRay>;
@group(0) @binding(LOCAL_OFFSETS) var<storage, read> local_offsets: array<u32>;
@group(0) @binding(BLOCK_OFFSETS) var<storage, read> block_offsets: array<u32>;
@group(0) @binding(ANSWERS) var<storage, read_write> next_paths: array<PathRay>;

@compute @workgroup_size(WORKGROUP)
fn compact(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let start = block_offsets[index / WORKGROUP] + local_offsets[index];
    for (var k = 0u; k < counts[index]; k++) {
        next_paths[start + k] = slots[2u * index + k];
    }
}
