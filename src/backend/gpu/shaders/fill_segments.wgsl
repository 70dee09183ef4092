// The light mesh's fill as a batch of node-to-light segments
// (`lightmesh/segments.rs`): where the static bit is missing, the segment
// against the static structure; then, where the node is open (its static
// bit known visible or just found so) and the dynamic bit is missing,
// against the dynamic objects. The segments are the CPU's shadow rays
// from the node (`RenderLight::shadow_ray`) and the traversal is the
// CPU's test, so every bit is the CPU fill's.
//
// Each answer goes to two places: into the mask pool, where the bit's
// pair of words is (so the level's shading reads it without the CPU), and
// into `answers`, which the CPU merges into its store at its next wait.

struct FillSegment {
    // The node, as `level_bricks.wgsl`'s `table_entry` and `table_slot`
    // read it.
    brick_node: u32,
    // The light's index above FILL_FLAG_BITS bits of TEST_STATIC |
    // KNOWN_VISIBLE | TEST_DYNAMIC | KNOWN_OCCLUDED (`contract.rs`); the
    // answer has STATIC_BLOCKED | DYNAMIC_TESTED | DYNAMIC_BLOCKED.
    light_flags: u32,
}

@group(0) @binding(ITEMS) var<storage, read> segments: array<FillSegment>;
// ANSWERS_PER_WORD answers a word, each ANSWER_BITS bits.
@group(0) @binding(ANSWERS) var<storage, read_write> answers: array<atomic<u32>>;
// The mask pool's slots (`mask_pool.rs`). Each segment owns its bit, so
// the atomics only keep the bits of one word from overwriting each other.
@group(0) @binding(POOL) var<storage, read_write> pool: array<atomic<u32>>;

@compute @workgroup_size(WORKGROUP)
fn fill_segments(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let segment = segments[index];
    let entry = table_entry(segment.brick_node);
    let slot = table_slot(segment.brick_node);
    let origin = table_node_position(entry, slot);
    let light_index = segment.light_flags >> FILL_FLAG_BITS;
    let flags = segment.light_flags & ((1u << FILL_FLAG_BITS) - 1u);
    let light = lights[light_index];
    let directional = light.directional != 0u;
    let direction = select(light.origin - origin, light.origin, directional);
    let t_max = select(SHADOW_SEGMENT_END, bitcast<f32>(0x7f800000u), directional);
    var answer = 0u;
    var open = (flags & KNOWN_VISIBLE) != 0u;
    if (flags & TEST_STATIC) != 0u {
        var found = no_hit();
        walk_static(origin, direction, t_max, true, &found);
        open = found.mesh == NO_MESH;
        answer |= select(STATIC_BLOCKED, 0u, open);
    }
    var occluded = (flags & KNOWN_OCCLUDED) != 0u;
    if (flags & TEST_DYNAMIC) != 0u && open {
        var found = no_hit();
        walk_dynamic(origin, direction, t_max, true, &found);
        occluded = found.mesh != NO_MESH;
        answer |= DYNAMIC_TESTED | select(0u, DYNAMIC_BLOCKED, occluded);
    }
    let shift = ANSWER_BITS * (index % ANSWERS_PER_WORD);
    atomicOr(&answers[index / ANSWERS_PER_WORD], answer << shift);
    // `Segment::sees`: the bit as the CPU's store will fold it, in the
    // node's pair of words for its light's word (`mask_pool.rs`).
    let pair = entry.slot_start + (slot * table.header.light_words + light_index / 32u) * GROUPS;
    let bit = 1u << (light_index % 32u);
    if open && !occluded {
        atomicOr(&pool[pair + VISIBLE], bit);
    } else {
        atomicAnd(&pool[pair + VISIBLE], ~bit);
    }
    atomicOr(&pool[pair + VALID], bit);
}
