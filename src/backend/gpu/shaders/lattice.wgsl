// The light mesh's lattice as `Lattice::node_position` rounds it: node
// (i, j, k) of the lattice of step `h` from `origin`, one product and one
// sum per axis.
fn lattice_position(origin: vec3<f32>, h: f32, node: vec3<i32>) -> vec3<f32> {
    return vec3<f32>(
        origin.x + mul(h, f32(node.x)),
        origin.y + mul(h, f32(node.y)),
        origin.z + mul(h, f32(node.z)),
    );
}

// The node in `slot` (`masks::join`) of `brick`.
fn brick_node(brick: vec3<i32>, slot: u32) -> vec3<i32> {
    let local = vec3<u32>(
        slot % BRICK_EDGE,
        slot / BRICK_EDGE % BRICK_EDGE,
        slot / (BRICK_EDGE * BRICK_EDGE),
    );
    return brick * i32(BRICK_EDGE) + vec3<i32>(local);
}
