// Formula (2) at a batch of shading points (`lightmesh/interpolate.rs`,
// `lightmesh/lattice.rs`): the half-ball of lattice nodes around the
// point (steps 1–2), the nodes kept (LMM: those the point sees, one
// segment each; LMM1: all but the enclosed ones blocked from a light the
// point asks for), then for each light in light order its Omega times
// the share of kept nodes that see it. An empty set falls back to
// formula (1). Node masks come from the pool (`mask_pool.rs`), found
// through the directory. Under `auto` a frame may also hold lights that
// formula (1) shades (hard and unshadowed ones): their terms come first,
// in light order, then formula (2)'s, as the CPU backend sums them.
//
// The half-ball's tests round as the CPU's rows of eight lanes do, and
// the shares are integer sums of the kernel's integer weights
// (`lightmesh/kernel.rs`: 1 per node for the box kernel) divided once,
// so a point gets the CPU backend's bits wherever its segments get the
// CPU's answers. Lights are taken 32 at a time (one u32 of each mask
// group): the set is walked once per 32 lights, summing for each light
// the weights of the kept nodes that see it in bit-sliced counters, so
// no per-light array is needed. Each term also goes to `keep_term` (the
// `light` AOV's, or nothing).

@group(0) @binding(1) var<storage, read> points: array<SurfacePoint>;
@group(0) @binding(7) var<storage, read_write> direct: array<DirectLight>;
// Per point, a bit per light that can reach it (`light_mesh_coverage.wgsl`).
@group(0) @binding(11) var<storage, read> reach: array<u32>;
// Candidates, interpolation-set sizes, point-to-node segments and
// fallback points, each as a (low, high) pair of u32.
@group(0) @binding(14) var<storage, read_write> counts: array<atomic<u32>, 8>;

// Whether the point keeps `node` in its interpolation set: LMM's step 3
// (the segment from the point to the node is clear), or LMM1's stand-in
// (`enclosure::blocks_some`: not an enclosed node blocked from a light
// the point asks for).
fn kept(node: vec3<i32>, mask: NodeMask, origin: vec3<f32>, reach_base: u32) -> bool {
    if directory.header.point_to_node_tests != 0u {
        return !segment_blocked(origin, node_position(node) - origin, 1.0);
    }
    if !mask.enclosed {
        return true;
    }
    for (var word = 0u; word < directory.header.light_words; word++) {
        if (reach[reach_base + word] & valid(mask, word) & ~visible(mask, word)) != 0u {
            return false;
        }
    }
    return true;
}

// Bits of the per-light counters: a half-ball of at most `MAX_KI` steps
// holds fewer than 2^12 nodes, each weighing less than 2^12.
const COUNTER_BITS: u32 = 24u;
// Bits of a node's weight (`kernel::SMOOTH_WEIGHT_SCALE`).
const WEIGHT_BITS: u32 = 12u;

// `Weights::weight`: the kernel's weight of a node at squared distance
// `distance_squared`, one rounded operation per step as the CPU does.
fn node_weight(distance_squared: f32) -> u32 {
    if directory.header.smooth_kernel == 0u {
        return 1u;
    }
    let falloff = max(1.0 - mul(distance_squared, directory.header.inverse_radius_squared), 0.0);
    return u32(floor(mul(mul(falloff, falloff), 4095.0)));
}

// One walk of the set for 32 lights: how many nodes it keeps, of how many
// candidates, their total weight, which lights all and any of them see,
// and per light the weight of those that see it (bit-sliced: bit b of
// `counters[k]` is bit k of light b's sum).
struct Tally {
    candidates: u32,
    kept: u32,
    total: u32,
    all: u32,
    any: u32,
    counters: array<u32, COUNTER_BITS>,
}

fn tally(ball: HalfBall, origin: vec3<f32>, reach_base: u32, word: u32) -> Tally {
    let wanted = reach[reach_base + word];
    var t = Tally(0u, 0u, 0u, wanted, 0u, array<u32, COUNTER_BITS>());
    var nodes = walk(ball);
    while next_node(&nodes) {
        t.candidates += 1u;
        let node = nodes.node;
        let mask = node_mask(node);
        if !kept(node, mask, origin, reach_base) {
            continue;
        }
        t.kept += 1u;
        let weight = node_weight(nodes.distance_squared);
        t.total += weight;
        let seen = visible(mask, word) & wanted;
        t.all &= seen;
        t.any |= seen;
        // Add `weight` to the counters of the lights in `seen`: each set
        // bit of it adds `seen` at that bit's place, carrying upwards.
        for (var place = 0u; place < WEIGHT_BITS; place++) {
            if (weight >> place & 1u) == 0u {
                continue;
            }
            var carry = seen;
            for (var bit = place; bit < COUNTER_BITS && carry != 0u; bit++) {
                let next = t.counters[bit] & carry;
                t.counters[bit] ^= carry;
                carry = next;
            }
        }
    }
    return t;
}

fn count_of(t: Tally, light: u32) -> u32 {
    var count = 0u;
    for (var bit = 0u; bit < COUNTER_BITS; bit++) {
        count |= (t.counters[bit] >> light & 1u) << bit;
    }
    return count;
}

// Adds `amount` to the 64-bit counter `which`.
fn add_count(which: u32, amount: u32) {
    let low = atomicAdd(&counts[2u * which], amount);
    if low + amount < low {
        atomicAdd(&counts[2u * which + 1u], 1u);
    }
}

@compute @workgroup_size(64)
fn light_mesh(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    let surface = points[index];
    if surface.hit == 0u {
        direct[index] = DirectLight(vec3<f32>(0.0), 0u);
        return;
    }
    begin_terms(index);
    let point = shade_point(surface);
    let ball = half_ball(point.position, point.geometric_normal);
    let origin = offset_ray_origin(point.position, point.geometric_normal);
    let light_words = directory.header.light_words;
    let reach_base = index * light_words;
    let first = formula_one(point, SHADED_BY_FORMULA_ONE, DirectLight(vec3<f32>(0.0), 0u));
    var radiance = first.radiance;
    var total = 0u;
    for (var word = 0u; word < light_words; word++) {
        let t = tally(ball, origin, reach_base, word);
        if word == 0u {
            total = t.total;
            add_count(0u, t.candidates);
            add_count(1u, t.kept);
            let tests = t.candidates * directory.header.point_to_node_tests;
            add_count(2u, tests);
            if total == 0u {
                add_count(3u, 1u);
                let fallback = formula_one(point, SHADED_BY_LIGHT_MESH, first);
                direct[index] = DirectLight(fallback.radiance, fallback.shadow_rays + tests);
                return;
            }
            direct[index].shadow_rays = first.shadow_rays + tests;
        }
        var lit = t.any;
        while lit != 0u {
            let bit = firstTrailingBit(lit);
            lit &= lit - 1u;
            let light = lights[word * 32u + bit];
            let value = omega(point, light);
            if all(value == vec3<f32>(0.0)) {
                continue;
            }
            var term = value;
            if (t.all >> bit & 1u) == 0u {
                term = scale3(value, div(f32(count_of(t, bit)), f32(total)));
            }
            radiance += term;
            keep_term(light, term);
        }
    }
    direct[index].radiance = radiance;
}
