// Closest hits of a batch of path rays: one record per ray (mesh NO_MESH
// where nothing was hit). The static mesh first, then the dynamic
// instances under the distance found, as `World::closest_hit`.

@group(0) @binding(ITEMS) var<storage, read> paths: array<PathRay>;
@group(0) @binding(ANSWERS) var<storage, read_write> hits: array<HitRecord>;

@compute @workgroup_size(WORKGROUP)
fn closest_hit(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let ray = paths[index];
    var best = no_hit();
    walk_static(ray.origin, ray.direction, ray.t_max, false, &best);
    walk_dynamic(ray.origin, ray.direction, ray.t_max, false, &best);
    hits[index] = HitRecord(best.t, best.u, best.v, best.mesh, best.slot, best.object, best.triangle, 0u);
}
