// What every pass reads: its parameters. Each pass declares its own items
// (binding ITEMS) and answers (binding ANSWERS). Binding numbers, flag
// bits, counter indices and codes are the prelude's (`contract.rs`);
// layouts are declared on the Rust side as `Pod` structs, and a test
// compares sizes and offsets.

struct Params {
    // Items of the pass: rays, or shading points.
    item_count: u32,
    static_node_count: u32,
    top_node_offset: u32,
    top_node_count: u32,
    top_members_offset: u32,
    // (1 + 2 gamma(3)): how much a slab exit may be understated by rounding.
    binary_scale: f32,
    // Stand-in for 1 / 0 and the largest inverse used.
    inv_limit: f32,
    // Lights of the direct-light pass (0 in ray queries).
    light_count: u32,
    // Light layers of the `light` AOV's passes (0 elsewhere).
    layer_count: u32,
}

// In a storage buffer, not a uniform one: lavapipe compiles a shader
// anew for each set of values its uniforms take (it inlines them as
// constants), and the item and light counts change with every dispatch;
// its first LMM1 frame waited minutes for those compiles.
@group(0) @binding(PARAMS) var<storage, read> params: Params;

