// Traversal of the flat world, as `accel::traverse` and `accel::world` do
// it on the CPU: the same conservative slab tests (Ize 2013) on the same
// boxes, so a ray reaches the same triangles. Closest hits are ordered by
// (t, object, triangle) and any-hit queries stop at the first hit, so
// neither answer depends on the order children are visited in.

// Larger than any slab value a real box gives (|plane - origin| times at
// most 2^64), so it plays the CPU's infinity for rays parallel to a slab
// without relying on the adapter's infinities.
const OUTSIDE: f32 = 1.2676506e30; // 2^100

// Deepest wide tree the stack holds: seven entries a level, plus one.
const WIDE_STACK: u32 = 96u;
const BINARY_STACK: u32 = 64u;

struct TraversalRay {
    origin: vec3<f32>,
    inv_direction: vec3<f32>,
    parallel: vec3<bool>,
    negative: vec3<bool>,
}

struct Closest {
    t: f32,
    u: f32,
    v: f32,
    // 0 for the static mesh, 1 + i for instance i, NO_MESH for no hit.
    mesh: u32,
    slot: u32,
    object: u32,
    triangle: u32,
}

fn inverse_component(d: f32) -> f32 {
    // Both zeros count as positive, as in the CPU's octant order.
    if d == 0.0 {
        return params.inv_limit;
    }
    return clamp(div(1.0, d), -params.inv_limit, params.inv_limit);
}

fn traversal_ray(origin: vec3<f32>, direction: vec3<f32>) -> TraversalRay {
    let inv = vec3<f32>(inverse_component(direction.x), inverse_component(direction.y), inverse_component(direction.z));
    return TraversalRay(origin, inv, direction == vec3<f32>(0.0), direction < vec3<f32>(0.0));
}

// Near and far t of one slab; a ray parallel to it is inside for ever or
// never.
fn slab(ray: TraversalRay, axis: u32, lo: f32, hi: f32) -> vec2<f32> {
    if ray.parallel[axis] {
        let inside = lo <= ray.origin[axis] && ray.origin[axis] <= hi;
        let near = select(OUTSIDE, -OUTSIDE, inside);
        return vec2<f32>(near, -near);
    }
    var near_plane = lo;
    var far_plane = hi;
    if ray.negative[axis] {
        near_plane = hi;
        far_plane = lo;
    }
    let near = (near_plane - ray.origin[axis]) * ray.inv_direction[axis];
    let far = (far_plane - ray.origin[axis]) * ray.inv_direction[axis];
    return vec2<f32>(near, far);
}

// Entry t of the box if the ray meets it in [0, t_cull] (widened by the
// rounding bound), else a negative number.
fn enter_box(ray: TraversalRay, lo: vec3<f32>, hi: vec3<f32>, t_cull: f32) -> f32 {
    var near = 0.0;
    var far = 0.0;
    for (var axis = 0u; axis < 3u; axis++) {
        let s = slab(ray, axis, lo[axis], hi[axis]);
        // min/max of the two, as the CPU's binary test takes them.
        let lower = min(s.x, s.y);
        let upper = max(s.x, s.y);
        if axis == 0u {
            near = lower;
            far = upper;
        } else {
            near = max(near, lower);
            far = min(far, upper);
        }
    }
    let t_near = max(near, 0.0);
    let t_far = far * params.binary_scale;
    if t_near <= t_far && t_near <= t_cull * params.binary_scale {
        return t_near;
    }
    return -1.0;
}

fn wide_plane(node: u32, axis: u32, side: u32, child: u32) -> f32 {
    return wide_nodes[node].planes[(axis * 2u + side) * 8u + child];
}

fn wide_prim_count(node: u32, child: u32) -> u32 {
    return (wide_nodes[node].counts[child / 4u] >> (8u * (child % 4u))) & 0xffu;
}

// Entry t of a wide node's child, as the CPU's eight-wide test computes
// it, or a negative number when the ray misses it within t_cull.
fn enter_child(ray: TraversalRay, node: u32, child: u32, t_cull: f32) -> f32 {
    var near = 0.0;
    var far = 0.0;
    for (var axis = 0u; axis < 3u; axis++) {
        let s = slab(ray, axis, wide_plane(node, axis, 0u, child), wide_plane(node, axis, 1u, child));
        near = max(near, s.x);
        far = select(min(far, s.y), s.y, axis == 0u);
    }
    if near <= min(far * params.binary_scale, t_cull * params.binary_scale) {
        return near;
    }
    return -1.0;
}

fn is_closer(t: f32, object: u32, triangle: u32, best: Closest) -> bool {
    if best.mesh == NO_MESH {
        return true;
    }
    if t != best.t {
        return t < best.t;
    }
    if object != best.object {
        return object < best.object;
    }
    return triangle < best.triangle;
}

// Lowers `best` with one triangle slot: index `slot` in its mesh's
// array, `local` in mesh `mesh`.
fn offer_slot(ray: WatertightRay, mesh: u32, slot: u32, local: u32, best: ptr<function, Closest>) {
    let dynamic = mesh != 0u;
    let hit = intersect_slot(ray, dynamic, slot);
    if !hit.hit {
        return;
    }
    var object: u32;
    var triangle: u32;
    if dynamic {
        object = dynamic_ids[slot * 2u];
        triangle = dynamic_ids[slot * 2u + 1u];
    } else {
        object = static_ids[slot * 2u];
        triangle = static_ids[slot * 2u + 1u];
    }
    if is_closer(hit.t, object, triangle, *best) {
        *best = Closest(hit.t, hit.u, hit.v, mesh, local, object, triangle);
    }
}

fn cull_distance(best: Closest, t_max: f32) -> f32 {
    return select(best.t, t_max, best.mesh == NO_MESH);
}

// The static wide BVH: closest hit when `any` is false, else stops at the
// first hit (reported with t only).
fn walk_static(origin: vec3<f32>, direction: vec3<f32>, t_max: f32, any: bool, best: ptr<function, Closest>) {
    if params.static_node_count == 0u {
        return;
    }
    let exact = watertight_ray(origin, direction, t_max);
    let ray = traversal_ray(origin, direction);
    var stack_ref: array<u32, WIDE_STACK>;
    var stack_t: array<f32, WIDE_STACK>;
    // An entry is (index << 2) | prim_count: a node, or a leaf's slots.
    stack_ref[0] = 0u;
    stack_t[0] = 0.0;
    var len = 1u;
    while len > 0u {
        len -= 1u;
        let entry = stack_ref[len];
        let t_cull = cull_distance(*best, t_max);
        if stack_t[len] > t_cull * params.binary_scale {
            continue;
        }
        let count = entry & 3u;
        let index = entry >> 2u;
        if count > 0u {
            for (var slot = index; slot < index + count; slot++) {
                offer_slot(exact, 0u, slot, slot, best);
                if any && (*best).mesh != NO_MESH {
                    return;
                }
            }
            continue;
        }
        let first = len;
        let valid = wide_nodes[index].valid;
        for (var child = 0u; child < 8u; child++) {
            if (valid & (1u << child)) == 0u {
                continue;
            }
            let t = enter_child(ray, index, child, t_cull);
            if t < 0.0 {
                continue;
            }
            let target_ref = (wide_nodes[index].child[child] << 2u) | wide_prim_count(index, child);
            // Insertion by entry t, far to near, so the nearest pops first.
            var at = len;
            len += 1u;
            while at > first && stack_t[at - 1u] < t {
                stack_ref[at] = stack_ref[at - 1u];
                stack_t[at] = stack_t[at - 1u];
                at -= 1u;
            }
            stack_ref[at] = target_ref;
            stack_t[at] = t;
        }
    }
}

// The instance's map of a point, in glam's order: ((c0 x + c1 y) + c2 z)
// + c3, each product rounded.
fn to_object_point(instance: u32, p: vec3<f32>) -> vec3<f32> {
    return to_object_vector(instance, p) + instances[instance].to_object[3].xyz;
}

fn to_object_vector(instance: u32, v: vec3<f32>) -> vec3<f32> {
    var out: vec3<f32>;
    for (var k = 0u; k < 3u; k++) {
        let m = &instances[instance].to_object;
        out[k] = (mul((*m)[0][k], v.x) + mul((*m)[1][k], v.y)) + mul((*m)[2][k], v.z);
    }
    return out;
}

// Offers a binary leaf's slots; false when an any-hit query is done.
fn offer_leaf(exact: WatertightRay, instance: u32, node: BinaryNode, any: bool, best: ptr<function, Closest>) -> bool {
    let offset = instances[instance].slot_offset;
    for (var s = node.first_index; s < node.first_index + node.prim_count; s++) {
        offer_slot(exact, instance + 1u, offset + s, s, best);
        if any && (*best).mesh != NO_MESH {
            return false;
        }
    }
    return true;
}

// One instance's binary BVH, in its object space, walked as the CPU's
// `traverse_binary`: children tested together, leaves offered at once near
// first, inner children pushed far first.
fn walk_instance(instance: u32, origin: vec3<f32>, direction: vec3<f32>, t_max: f32, any: bool, best: ptr<function, Closest>) {
    if instances[instance].valid == 0u {
        return;
    }
    // The direction is mapped, not normalised, so t means the same point
    // in both spaces.
    let local_origin = to_object_point(instance, origin);
    let local_direction = to_object_vector(instance, direction);
    let exact = watertight_ray(local_origin, local_direction, t_max);
    let ray = traversal_ray(local_origin, local_direction);
    let base = instances[instance].node_offset;
    let root = binary_nodes[base];
    if enter_box(ray, root.min, root.max, cull_distance(*best, t_max)) < 0.0 {
        return;
    }
    if root.prim_count > 0u {
        offer_leaf(exact, instance, root, any, best);
        return;
    }
    var stack: array<u32, BINARY_STACK>;
    stack[0] = root.first_index;
    var len = 1u;
    while len > 0u {
        len -= 1u;
        let first_child = stack[len];
        let t_cull = cull_distance(*best, t_max);
        var near = binary_nodes[base + first_child];
        var far = binary_nodes[base + first_child + 1u];
        var t_near = enter_box(ray, near.min, near.max, t_cull);
        var t_far = enter_box(ray, far.min, far.max, t_cull);
        if t_near >= 0.0 && t_far >= 0.0 && t_far < t_near {
            let node = near;
            near = far;
            far = node;
            let t = t_near;
            t_near = t_far;
            t_far = t;
        }
        if t_near >= 0.0 && near.prim_count > 0u && !offer_leaf(exact, instance, near, any, best) {
            return;
        }
        if t_far >= 0.0 && far.prim_count > 0u && !offer_leaf(exact, instance, far, any, best) {
            return;
        }
        if t_far >= 0.0 && far.prim_count == 0u {
            stack[len] = far.first_index;
            len += 1u;
        }
        if t_near >= 0.0 && near.prim_count == 0u {
            stack[len] = near.first_index;
            len += 1u;
        }
    }
}

// The top level over the dynamic instances: each instance whose bounds
// the ray meets before the current cull distance.
fn walk_dynamic(origin: vec3<f32>, direction: vec3<f32>, t_max: f32, any: bool, best: ptr<function, Closest>) {
    if params.top_node_count == 0u {
        return;
    }
    let ray = traversal_ray(origin, direction);
    let base = params.top_node_offset;
    var stack: array<u32, BINARY_STACK>;
    stack[0] = 0u;
    var len = 1u;
    while len > 0u {
        len -= 1u;
        let node = binary_nodes[base + stack[len]];
        if enter_box(ray, node.min, node.max, cull_distance(*best, t_max)) < 0.0 {
            continue;
        }
        if node.prim_count == 0u {
            stack[len] = node.first_index + 1u;
            stack[len + 1u] = node.first_index;
            len += 2u;
            continue;
        }
        for (var s = node.first_index; s < node.first_index + node.prim_count; s++) {
            walk_instance(dynamic_ids[params.top_members_offset + s], origin, direction, t_max, any, best);
            if any && (*best).mesh != NO_MESH {
                return;
            }
        }
    }
}

fn no_hit() -> Closest {
    return Closest(0.0, 0.0, 0.0, NO_MESH, 0u, 0u, 0u);
}
