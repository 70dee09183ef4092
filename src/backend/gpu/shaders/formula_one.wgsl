// Formula (1) at a shading point: for each light in light order,
// Omega(i, P) (`omega.wgsl`) and, where it brings light, the shadow
// segment's any-hit test; the visible terms summed in that order, and
// each handed to `keep_term` (the `light` AOV's, or nothing). A point
// gets the CPU backend's bits wherever its shadow segments get its
// answers.

struct DirectLight {
    radiance: vec3<f32>,
    shadow_rays: u32,
}

// Where shadow segments stop short of the light (`render/light.rs`).
const SHADOW_SEGMENT_END: f32 = 0.9999847412109375; // 1 - 2^-16

// The segment from `origin` to `light`, tested for anything on it.
fn shadowed(origin: vec3<f32>, light: Light) -> bool {
    let directional = light.directional != 0u;
    let direction = select(light.origin - origin, light.origin, directional);
    // Directional lights' segments never end (the CPU's infinite t_max).
    let t_max = select(SHADOW_SEGMENT_END, bitcast<f32>(0x7f800000u), directional);
    return segment_blocked(origin, direction, t_max);
}

// Whether anything lies on the ray from `origin` along `direction` before
// `t_max`; the dynamic part is the small one and goes first, as in
// `World::occluded`.
fn segment_blocked(origin: vec3<f32>, direction: vec3<f32>, t_max: f32) -> bool {
    var found = no_hit();
    walk_dynamic(origin, direction, t_max, true, &found);
    if found.mesh == NO_MESH {
        walk_static(origin, direction, t_max, true, &found);
    }
    return found.mesh != NO_MESH;
}

// Lights are taken 32 at a time: first which of them bring light (Omega
// only, the same work in every invocation), then a segment for each of
// those. Invocations that run side by side then trace their own k-th
// segment together instead of waiting on each other's lights, and the
// visible terms are still summed in light order. Omega is evaluated again
// for a visible light rather than kept from the first loop: 32 colours per
// invocation would cost registers on every adapter, a second evaluation
// only arithmetic.
fn formula_one(point: ShadePoint) -> DirectLight {
    let origin = offset_ray_origin(point.position, point.geometric_normal);
    var radiance = vec3<f32>(0.0);
    var shadow_rays = 0u;
    for (var first = 0u; first < params.light_count; first += 32u) {
        let count = min(params.light_count - first, 32u);
        var bringing = 0u;
        for (var i = 0u; i < count; i++) {
            if any(omega(point, lights[first + i]) != vec3<f32>(0.0)) {
                bringing |= 1u << i;
            }
        }
        shadow_rays += countOneBits(bringing);
        while bringing != 0u {
            let light = lights[first + firstTrailingBit(bringing)];
            bringing &= bringing - 1u;
            if !shadowed(origin, light) {
                let term = omega(point, light);
                radiance += term;
                keep_term(light, term);
            }
        }
    }
    return DirectLight(radiance, shadow_rays);
}
