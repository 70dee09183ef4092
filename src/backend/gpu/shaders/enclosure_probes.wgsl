// LMM1's enclosure probes (`lightmesh/enclosure.rs`), one node an
// invocation: short closest-hit rays from the node against the static
// structure, in the CPU's directions and order, each voting by the side
// of the triangle it meets; the node is enclosed where backs outvote
// fronts. The traversal is the CPU's closest hit and the normal its f64
// one rounded once (`triangle_normal`), so on adapters that round as the
// CPU does every flag is the CPU's; others keep the CPU's probes.
//
// Each flag goes to two places: into the node's brick in the mask pool
// (its `known` and `enclosed` words, for the level's shading) and into
// `answers`, a bit per node, which the CPU merges into its store at its
// next wait.

// Each node, as `level_bricks.wgsl`'s `table_entry` and `table_slot`
// read it.
@group(0) @binding(ITEMS) var<storage, read> nodes: array<u32>;
@group(0) @binding(ANSWERS) var<storage, read_write> answers: array<atomic<u32>>;
// The mask pool's slots (`mask_pool.rs`); a slot's flag words are shared
// by its nodes, hence the atomics.
@group(0) @binding(POOL) var<storage, read_write> pool: array<atomic<u32>>;

// `enclosure::PROBES`, the same f32 values in the same order.
const PROBES = array<vec3<f32>, PROBE_COUNT>(
    vec3<f32>(1.0, 0.0, 0.0),
    vec3<f32>(-1.0, 0.0, 0.0),
    vec3<f32>(0.0, 1.0, 0.0),
    vec3<f32>(0.0, -1.0, 0.0),
    vec3<f32>(0.0, 0.0, 1.0),
    vec3<f32>(0.0, 0.0, -1.0),
    vec3<f32>(0.57735026, 0.57735026, 0.57735026),
    vec3<f32>(0.57735026, 0.57735026, -0.57735026),
    vec3<f32>(0.57735026, -0.57735026, 0.57735026),
    vec3<f32>(0.57735026, -0.57735026, -0.57735026),
    vec3<f32>(-0.57735026, 0.57735026, 0.57735026),
    vec3<f32>(-0.57735026, 0.57735026, -0.57735026),
    vec3<f32>(-0.57735026, -0.57735026, 0.57735026),
    vec3<f32>(-0.57735026, -0.57735026, -0.57735026),
);

// `enclosure::is_enclosed`.
fn is_enclosed(at: vec3<f32>, reach: f32) -> bool {
    var backs = 0u;
    var fronts = 0u;
    for (var done = 0u; done < PROBE_COUNT; done++) {
        // Stop once the probes left cannot change the verdict.
        let left = PROBE_COUNT - done;
        if backs > fronts + left || fronts >= backs + left {
            break;
        }
        let direction = PROBES[done];
        var found = no_hit();
        walk_static(at, direction, reach, false, &found);
        if found.mesh != NO_MESH {
            let slot = found.slot;
            let normal = triangle_normal(
                slot_vertex(false, slot, 0u),
                slot_vertex(false, slot, 1u),
                slot_vertex(false, slot, 2u),
            );
            if dot3(normal, direction) > 0.0 {
                backs += 1u;
            } else {
                fronts += 1u;
            }
        }
    }
    return backs > fronts;
}

@compute @workgroup_size(WORKGROUP)
fn enclosure_probes(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let node = nodes[index];
    let entry = table_entry(node);
    let slot = table_slot(node);
    let enclosed = is_enclosed(table_node_position(entry, slot), table.header.probe_reach);
    let bit = 1u << (slot % 32u);
    let known = entry.slot_start + BRICK_NODES * GROUPS * table.header.light_words + slot / 32u;
    atomicOr(&pool[known], bit);
    if enclosed {
        atomicOr(&pool[known + FLAG_WORDS], bit);
        atomicOr(&answers[index / 32u], 1u << (index % 32u));
    }
}
