// Which of a level's shading points the masks on the GPU already serve:
// for each point, the lights that can reach it (the demand's reaching
// lights, `Arrival::reaching`), and whether every node of its half-ball
// holds a valid bit for each of them in the pool, with its enclosure flag
// settled where LMM1 will ask for it (a node blocked from one of them).
// Only the points it leaves out go to the CPU for demand and fill: where
// the masks are reused, a frame reads back a few points instead of all.

@group(0) @binding(ITEMS) var<storage, read> points: array<SurfacePoint>;
// Per point, `light_words` u32 of reaching-light bits, then as many of
// the lamps among them that are not faint (`faint.wgsl`).
@group(0) @binding(ANSWERS) var<storage, read_write> reach: array<u32>;
// A bit per point, set where the pool does not serve it yet; then a bit
// per pool slot, set where a point read the slot's brick (the CPU then
// keeps those bricks when it must evict); last, how many points the pool
// does not serve.
@group(0) @binding(FLAGS) var<storage, read_write> flags: array<atomic<u32>>;
// Copies of the points the pool does not serve, as many as there is room
// for, in no order (each carries its index): the CPU's demand takes them
// from the wait that brings the flags back.
@group(0) @binding(GATHERED) var<storage, read_write> gathered: array<SurfacePoint>;

// Whether the pool holds every bit of `reach` (from `base`) that formula
// (2) will read at `node`.
fn serves(mask: NodeMask, base: u32, light_words: u32) -> bool {
    for (var word = 0u; word < light_words; word++) {
        if !serves_word(mask, reach[base + word], word) {
            return false;
        }
    }
    return mask.found;
}

// Whether the pool holds the bits of the lights `wanted` of word `word`,
// with the node's enclosure flag settled where LMM1 will ask for it (the
// node is blocked from one of them).
fn serves_word(mask: NodeMask, wanted: u32, word: u32) -> bool {
    if !mask.found || (valid(mask, word) & wanted) != wanted {
        return false;
    }
    let blocked = wanted & ~visible(mask, word);
    return directory.header.point_to_node_tests != 0u || blocked == 0u || mask.settled;
}

// Whether `light` reaches `point` and is one the light mesh shades (the
// demand's lanes hold the others unpowered).
fn reaches_by_light_mesh(point: ShadePoint, light: Light) -> bool {
    return (light.shading & SHADED_BY_LIGHT_MESH) != 0u && arrival(point, light).reaches;
}

@compute @workgroup_size(WORKGROUP)
fn light_mesh_coverage(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let light_words = directory.header.light_words;
    let base = index * 2u * light_words;
    let surface = points[index];
    var any_light = 0u;
    let point = shade_point(surface);
    for (var word = 0u; word < light_words; word++) {
        var bits = 0u;
        for (var bit = 0u; bit < 32u; bit++) {
            let light = word * 32u + bit;
            if surface.hit != 0u && light < params.light_count && reaches_by_light_mesh(point, lights[light]) {
                bits |= 1u << bit;
            }
        }
        reach[base + word] = bits;
        any_light |= bits;
    }
    // Written for every point, so no word of the buffer is stale.
    mark_refined_lamps(point, base);
    if any_light == 0u {
        return;
    }
    var marked = -1;
    var nodes = walk(half_ball(point.position, point.geometric_normal));
    while next_node(&nodes) {
        if !serves(node_mask(nodes.node), base, light_words) {
            mark_unserved(index);
            return;
        }
        mark_read_slot(&marked);
    }
    // The wide set's nodes, for the point's lamps but the faint ones
    // (`light_mesh.wgsl`).
    for (var word = 0u; word < light_words && asks_wide_set(); word++) {
        let lamps = reach[base + light_words + word];
        if lamps == 0u {
            continue;
        }
        var wide_nodes = walk(half_ball_at(point.position, point.geometric_normal, WIDE_STEPS));
        while next_node(&wide_nodes) {
            if !serves_word(node_mask(wide_nodes.node), lamps, word) {
                mark_unserved(index);
                return;
            }
            mark_read_slot(&marked);
        }
    }
}

// Flags point `index` as one the pool does not serve yet, and copies it
// where there is room.
fn mark_unserved(index: u32) {
    atomicOr(&flags[index / 32u], 1u << (index % 32u));
    let at = atomicAdd(&flags[arrayLength(&flags) - 1u], 1u);
    if at < arrayLength(&gathered) {
        var point = points[index];
        point.level_index = index;
        gathered[at] = point;
    }
}

// Flags the pool slot the last `node_mask` read as read by a point, once
// per run of reads from one slot (the last one flagged is `marked`).
fn mark_read_slot(marked: ptr<function, i32>) {
    if cached_slot == *marked {
        return;
    }
    *marked = cached_slot;
    let slot = u32(cached_slot);
    let slot_flags = (params.item_count + 31u) / 32u;
    atomicOr(&flags[slot_flags + slot / 32u], 1u << (slot % 32u));
}
