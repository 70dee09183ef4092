// The light mesh's fill as a batch of node-to-light segments
// (`lightmesh/segments.rs`): where the static bit is missing, the segment
// against the static structure; then, where the node is open (its static
// bit known visible or just found so) and the dynamic bit is missing,
// against the dynamic objects. The segments are the CPU's shadow rays
// from the node (`RenderLight::shadow_ray`) and the traversal is the
// CPU's test, so every bit is the CPU fill's.

struct FillSegment {
    origin: array<f32, 3>,
    // The light's index above FILL_FLAG_BITS bits of TEST_STATIC |
    // KNOWN_VISIBLE | TEST_DYNAMIC (`contract.rs`); the answer has
    // STATIC_BLOCKED | DYNAMIC_TESTED | DYNAMIC_BLOCKED.
    light_flags: u32,
}

@group(0) @binding(ITEMS) var<storage, read> segments: array<FillSegment>;
// ANSWERS_PER_WORD answers a word, each ANSWER_BITS bits.
@group(0) @binding(ANSWERS) var<storage, read_write> answers: array<atomic<u32>>;

@compute @workgroup_size(WORKGROUP)
fn fill_segments(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let segment = segments[index];
    let origin = vec3<f32>(segment.origin[0], segment.origin[1], segment.origin[2]);
    let flags = segment.light_flags & ((1u << FILL_FLAG_BITS) - 1u);
    let light = lights[segment.light_flags >> FILL_FLAG_BITS];
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
    if (flags & TEST_DYNAMIC) != 0u && open {
        var found = no_hit();
        walk_dynamic(origin, direction, t_max, true, &found);
        answer |= DYNAMIC_TESTED | select(0u, DYNAMIC_BLOCKED, found.mesh != NO_MESH);
    }
    let shift = ANSWER_BITS * (index % ANSWERS_PER_WORD);
    atomicOr(&answers[index / ANSWERS_PER_WORD], answer << shift);
}
