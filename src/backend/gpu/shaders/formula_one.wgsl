// Formula (1) at a shading point: for each light in light order whose
// `shading` has the asked-for integrator's bit, Omega(i, P) (`omega.wgsl`)
// and, where it brings light, the shadow segment's any-hit test (not for
// an unshadowed light: nothing can block it); the visible terms summed in
// that order onto a running sum, and each handed to `keep_term` (the
// `light` AOV's, or nothing). A point gets the CPU backend's bits wherever
// its shadow segments get its answers.

// One point's direct light, and the segments it took: those of no
// light's class (LMM's point-to-node tests, the blockers' rays), and
// formula (1)'s by the plan's class of their light.
struct DirectLight {
    radiance: vec3<f32>,
    other_rays: u32,
    class_rays: vec4<u32>,
}

fn no_direct_light() -> DirectLight {
    return DirectLight(vec3<f32>(0.0), 0u, vec4<u32>(0u));
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
// `t_max`.
fn segment_blocked(origin: vec3<f32>, direction: vec3<f32>, t_max: f32) -> bool {
    return trace_segment(origin, direction, t_max, true).mesh != NO_MESH;
}

// The ray from `origin` along `direction` before `t_max`: its closest hit,
// or with `any` the first found (the dynamic part, the small one, goes
// first then, as in `World::occluded`; the closest hit walks the static
// part first). Both walks are written once, so a caller that traces from
// one place holds one copy of the traversal: drivers inline every call,
// and a copy per call site is what made formula (2)'s shader take minutes
// to compile on lavapipe.
fn trace_segment(origin: vec3<f32>, direction: vec3<f32>, t_max: f32, any: bool) -> Closest {
    var best = no_hit();
    for (var part = 0u; part < 2u; part++) {
        if (part == 0u) == any {
            walk_dynamic(origin, direction, t_max, any, &best);
        } else {
            walk_static(origin, direction, t_max, any, &best);
        }
        if any && best.mesh != NO_MESH {
            break;
        }
    }
    return best;
}

// Lights are taken 32 at a time: first which of them bring light (Omega
// only, the same work in every invocation), then a segment for each of
// those. Invocations that run side by side then trace their own k-th
// segment together instead of waiting on each other's lights, and the
// visible terms are still summed in light order. Omega is evaluated again
// for a visible light rather than kept from the first loop: 32 colours per
// invocation would cost registers on every adapter, a second evaluation
// only arithmetic.
//
// The terms of the lights `shading` selects (`SHADED_BY_FORMULA_ONE` or
// `SHADED_BY_LIGHT_MESH`) are added to `sum` in light order, as the CPU
// adds a point's terms one after the other: `auto` adds its formula-(1)
// lights' first and formula (2)'s after them.
fn formula_one(point: ShadePoint, shading: u32, sum: DirectLight) -> DirectLight {
    let origin = offset_ray_origin(point.position, point.geometric_normal);
    var radiance = sum.radiance;
    var class_rays = sum.class_rays;
    for (var first = 0u; first < params.light_count; first += 32u) {
        let count = min(params.light_count - first, 32u);
        var bringing = 0u;
        var tested = 0u;
        for (var i = 0u; i < count; i++) {
            let light = lights[first + i];
            if (light.shading & shading) != 0u && any(omega(point, light) != vec3<f32>(0.0)) {
                bringing |= 1u << i;
                if (light.shading & TESTS_SEGMENT) != 0u {
                    tested |= 1u << i;
                }
            }
        }
        while bringing != 0u {
            let bit = firstTrailingBit(bringing);
            let light = lights[first + bit];
            bringing &= bringing - 1u;
            let tests = (tested >> bit & 1u) != 0u;
            if tests {
                class_rays[class_of(light)] += 1u;
            }
            if !tests || !shadowed(origin, light) {
                let term = omega(point, light);
                radiance += term;
                keep_term(light, term);
            }
        }
    }
    return DirectLight(radiance, sum.other_rays, class_rays);
}
