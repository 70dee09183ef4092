// The world in flat form (Rust side: `accel::flat`), bound for the passes
// that trace: the static wide BVH, the dynamic objects' binary BVHs and
// the top level over them, triangle vertices and ids.

// Eight children: their boxes as planes[(axis * 2 + side) * 8 + child]
// (side 0 the min planes, 1 the max planes), where each leads, and which
// slots hold a child at all (an empty slot's planes are never read).
struct WideNode {
    planes: array<f32, 48>,
    child: array<u32, 8>,
    // Four 8-bit leaf primitive counts per word (0: an inner node).
    counts: array<u32, 2>,
    valid: u32,
    _pad: array<u32, 5>,
}

struct BinaryNode {
    min: vec3<f32>,
    prim_count: u32,
    max: vec3<f32>,
    first_index: u32,
}

// A dynamic object: the affine map from render to object space, by
// columns, and where its nodes and triangles start.
struct Instance {
    to_object: array<vec4<f32>, 4>,
    node_offset: u32,
    slot_offset: u32,
    // 0 while the placement is singular: the instance is hit by nothing.
    valid: u32,
    _pad: u32,
}

@group(0) @binding(WIDE_NODES) var<storage, read> wide_nodes: array<WideNode>;
@group(0) @binding(BINARY_NODES) var<storage, read> binary_nodes: array<BinaryNode>;
// Nine floats per triangle slot, in slot order: the static mesh's in
// render space, and every instance's (from its `slot_offset`) in its
// object space.
@group(0) @binding(STATIC_VERTICES) var<storage, read> static_vertices: array<f32>;
@group(0) @binding(DYNAMIC_VERTICES) var<storage, read> dynamic_vertices: array<f32>;
// Per slot its source (object, triangle), two words. The dynamic array
// ends with the top level's members (the instance index of each of its
// primitive slots), from `params.top_members_offset`.
@group(0) @binding(STATIC_IDS) var<storage, read> static_ids: array<u32>;
@group(0) @binding(DYNAMIC_IDS) var<storage, read> dynamic_ids: array<u32>;
@group(0) @binding(INSTANCES) var<storage, read> instances: array<Instance>;
