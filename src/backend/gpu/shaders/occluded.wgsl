// Any-hit queries of a batch of shadow segments: reads `rays`, writes one
// word per ray, 1 where something lies on it in (0, t_max). The dynamic
// part is the small one and goes first, as in `World::occluded`.

@group(0) @binding(ANSWERS) var<storage, read_write> occluded: array<u32>;

@compute @workgroup_size(WORKGROUP)
fn any_hit(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let ray = rays[index];
    var found = no_hit();
    walk_dynamic(ray.origin, ray.direction, ray.t_max, true, &found);
    if found.mesh == NO_MESH {
        walk_static(ray.origin, ray.direction, ray.t_max, true, &found);
    }
    occluded[index] = select(0u, 1u, found.mesh != NO_MESH);
}
