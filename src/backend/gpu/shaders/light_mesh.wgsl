// Formula (2) at a batch of shading points (`lightmesh/interpolate.rs`,
// `lightmesh/lattice.rs`): the half-ball of lattice nodes around the
// point (steps 1–2), the nodes kept (LMM: those the point sees, one
// segment each; LMM1: all but the enclosed ones blocked from a light the
// point asks for), then for each light in light order its Omega times
// the share of kept nodes that see it. An empty set falls back to
// formula (1). Node masks come from the pool (`mask_pool.rs`), found
// through the directory.
//
// The half-ball's tests round as the CPU's rows of eight lanes do, and
// the shares are integer counts divided once, so a point gets the CPU
// backend's bits wherever its segments get the CPU's answers. Lights are
// taken 32 at a time (one u32 of each mask group): the set is walked once
// per 32 lights, counting for each light the kept nodes that see it in
// bit-sliced counters, so no per-light array is needed.

struct MeshHeader {
    origin: vec3<f32>,
    h: f32,
    radius: f32,
    // u64 words per group of a node's mask.
    words: u32,
    entry_mask: u32,
    point_to_node_tests: u32,
}

struct Directory {
    header: MeshHeader,
    // (brick x, y, z, slot); slot -1: empty.
    entries: array<vec4<i32>>,
}

@group(0) @binding(11) var<storage, read> reach: array<u32>;
@group(0) @binding(12) var<storage, read> directory: Directory;
@group(0) @binding(13) var<storage, read> pool: array<u32>;
// Candidates, interpolation-set sizes, point-to-node segments and
// fallback points, each as a (low, high) pair of u32.
@group(0) @binding(14) var<storage, read_write> counts: array<atomic<u32>, 8>;

const BRICK_NODES: u32 = 512u;
const GROUPS: u32 = 4u;
const STATIC_VISIBLE: u32 = 0u;
const STATIC_VALID: u32 = 1u;
const DYNAMIC_OCCLUDED: u32 = 2u;
const DYNAMIC_VALID: u32 = 3u;
// `MAX_KI` steps either side of the point and the point's own row.
const MAX_SPAN: i32 = 17;
// Bits of the per-light counters: a half-ball of at most `MAX_KI` steps
// holds fewer than 2^13 nodes.
const COUNTER_BITS: u32 = 13u;
// 8 f32 epsilons, 2^-20.
const ON_PLANE_EPSILONS: f32 = 9.5367431640625e-7;

// The nodes within `radius` of `p` on the side `n` faces, as
// `Lattice::half_ball` bounds and tests them.
struct HalfBall {
    p: vec3<f32>,
    n: vec3<f32>,
    low: vec3<i32>,
    span: vec3<i32>,
    radius_squared: f32,
    on_plane: f32,
}

fn half_ball(p: vec3<f32>, n: vec3<f32>) -> HalfBall {
    let mesh = directory.header;
    let h = mesh.h;
    let from_origin = p - mesh.origin;
    let local = vec3<f32>(div(from_origin.x, h), div(from_origin.y, h), div(from_origin.z, h));
    let reach_steps = div(mesh.radius, h);
    let low = vec3<i32>(ceil(local - vec3<f32>(reach_steps)));
    let high = vec3<i32>(floor(local + vec3<f32>(reach_steps)));
    let span = clamp(high - low + vec3<i32>(1), vec3<i32>(0), vec3<i32>(MAX_SPAN));
    // `Lattice::on_plane_tolerance`: 8 epsilon times the magnitudes.
    let magnitude = (max_abs(p) + max_abs(mesh.origin)) + mesh.radius;
    let on_plane = mul(ON_PLANE_EPSILONS, magnitude);
    return HalfBall(p, n, low, span, mul(mesh.radius, mesh.radius), on_plane);
}

fn max_abs(v: vec3<f32>) -> f32 {
    return max(abs(v.x), max(abs(v.y), abs(v.z)));
}

// `node_position(node)[axis] - p[axis]` as the CPU rounds it.
fn node_offset(origin: f32, index: i32, p: f32) -> f32 {
    return (origin + mul(directory.header.h, f32(index))) - p;
}

fn node_position(node: vec3<i32>) -> vec3<f32> {
    let mesh = directory.header;
    return vec3<f32>(
        mesh.origin.x + mul(mesh.h, f32(node.x)),
        mesh.origin.y + mul(mesh.h, f32(node.y)),
        mesh.origin.z + mul(mesh.h, f32(node.z)),
    );
}

fn directory_hash(brick: vec3<i32>) -> u32 {
    return (bitcast<u32>(brick.x) * 0x8da6b343u)
        ^ (bitcast<u32>(brick.y) * 0xd8163841u)
        ^ (bitcast<u32>(brick.z) * 0xcb1ab31fu);
}

// The pool slot of `brick`, or -1 where the pool holds none.
fn brick_slot(brick: vec3<i32>) -> i32 {
    let mask = directory.header.entry_mask;
    var at = directory_hash(brick) & mask;
    loop {
        let entry = directory.entries[at];
        if entry.w < 0 || all(entry.xyz == brick) {
            return entry.w;
        }
        at = (at + 1u) & mask;
    }
    return -1;
}

// u32 words of a slot: the nodes' groups, then the enclosure flags
// (`known`, then `enclosed`, 8 u64 each).
fn slot_size() -> u32 {
    return (BRICK_NODES * GROUPS * directory.header.words + 16u) * 2u;
}

// Where one node's mask is in the pool, and whether the node lies inside
// closed geometry; `found` is false where its brick is not in the pool
// (no bit of it was ever needed: it sees nothing).
struct NodeMask {
    found: bool,
    base: u32,
    enclosed: bool,
}

// The last brick looked up: a row of nodes mostly stays in one.
var<private> cached_brick: vec3<i32>;
var<private> cached_slot: i32 = -2;

fn node_mask(node: vec3<i32>) -> NodeMask {
    let brick = node >> vec3<u32>(3u);
    if cached_slot == -2 || any(brick != cached_brick) {
        cached_brick = brick;
        cached_slot = brick_slot(brick);
    }
    if cached_slot < 0 {
        return NodeMask(false, 0u, false);
    }
    let local = vec3<u32>(node & vec3<i32>(7));
    let in_brick = (local.z * 8u + local.y) * 8u + local.x;
    let slot_base = u32(cached_slot) * slot_size();
    let words32 = 2u * directory.header.words;
    let flags = slot_base + BRICK_NODES * GROUPS * words32 + 16u + in_brick / 32u;
    let enclosed = (pool[flags] >> (in_brick % 32u) & 1u) == 1u;
    return NodeMask(true, slot_base + in_brick * GROUPS * words32, enclosed);
}

fn group_word(mask: NodeMask, group: u32, word: u32) -> u32 {
    if !mask.found {
        return 0u;
    }
    return pool[mask.base + group * 2u * directory.header.words + word];
}

// `NodeMask::visible`: the static bit set and no dynamic blocker.
fn visible(mask: NodeMask, word: u32) -> u32 {
    return group_word(mask, STATIC_VISIBLE, word) & ~group_word(mask, DYNAMIC_OCCLUDED, word);
}

// `NodeMask::valid`.
fn valid(mask: NodeMask, word: u32) -> u32 {
    let static_visible = group_word(mask, STATIC_VISIBLE, word);
    return group_word(mask, STATIC_VALID, word) & (~static_visible | group_word(mask, DYNAMIC_VALID, word));
}

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
    for (var word = 0u; word < 2u * directory.header.words; word++) {
        if (reach[reach_base + word] & valid(mask, word) & ~visible(mask, word)) != 0u {
            return false;
        }
    }
    return true;
}

// One walk of the set for 32 lights: how many nodes it keeps, of how many
// candidates, which lights all and any of them see, and per light how
// many see it (bit-sliced: bit b of `counters[k]` is bit k of light b's
// count).
struct Tally {
    candidates: u32,
    kept: u32,
    all: u32,
    any: u32,
    counters: array<u32, COUNTER_BITS>,
}

fn tally(ball: HalfBall, origin: vec3<f32>, reach_base: u32, word: u32) -> Tally {
    let mesh = directory.header;
    let wanted = reach[reach_base + word];
    var t = Tally(0u, 0u, wanted, 0u, array<u32, COUNTER_BITS>());
    for (var k = 0; k < ball.span.z; k++) {
        let dz = node_offset(mesh.origin.z, ball.low.z + k, ball.p.z);
        for (var j = 0; j < ball.span.y; j++) {
            let dy = node_offset(mesh.origin.y, ball.low.y + j, ball.p.y);
            let dy2 = mul(dy, dy);
            let dz2 = mul(dz, dz);
            if dy2 + dz2 > ball.radius_squared {
                continue;
            }
            let n_yz = vec2<f32>(mul(ball.n.y, dy), mul(ball.n.z, dz));
            for (var i = 0; i < ball.span.x; i++) {
                let dx = node_offset(mesh.origin.x, ball.low.x + i, ball.p.x);
                let inside = (mul(dx, dx) + dy2) + dz2 <= ball.radius_squared
                    && (mul(ball.n.x, dx) + n_yz.x) + n_yz.y > ball.on_plane;
                if !inside {
                    continue;
                }
                t.candidates += 1u;
                let node = ball.low + vec3<i32>(i, j, k);
                let mask = node_mask(node);
                if !kept(node, mask, origin, reach_base) {
                    continue;
                }
                t.kept += 1u;
                let seen = visible(mask, word) & wanted;
                t.all &= seen;
                t.any |= seen;
                // Add `seen` to the counters, carrying bit by bit.
                var carry = seen;
                for (var bit = 0u; bit < COUNTER_BITS && carry != 0u; bit++) {
                    let next = t.counters[bit] & carry;
                    t.counters[bit] ^= carry;
                    carry = next;
                }
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
    let point = shade_point(surface);
    let ball = half_ball(point.position, point.geometric_normal);
    let origin = offset_ray_origin(point.position, point.geometric_normal);
    let words32 = 2u * directory.header.words;
    let reach_base = index * words32;
    var radiance = vec3<f32>(0.0);
    var m = 0u;
    for (var word = 0u; word < words32; word++) {
        let t = tally(ball, origin, reach_base, word);
        if word == 0u {
            m = t.kept;
            add_count(0u, t.candidates);
            add_count(1u, m);
            let tests = t.candidates * directory.header.point_to_node_tests;
            add_count(2u, tests);
            if m == 0u {
                add_count(3u, 1u);
                let fallback = formula_one(point);
                direct[index] = DirectLight(fallback.radiance, fallback.shadow_rays + tests);
                return;
            }
            direct[index].shadow_rays = tests;
        }
        var lit = t.any;
        while lit != 0u {
            let bit = firstTrailingBit(lit);
            lit &= lit - 1u;
            let value = omega(point, lights[word * 32u + bit]);
            if all(value == vec3<f32>(0.0)) {
                continue;
            }
            if (t.all >> bit & 1u) == 1u {
                radiance += value;
            } else {
                radiance += scale3(value, div(f32(count_of(t, bit)), f32(m)));
            }
        }
    }
    direct[index].radiance = radiance;
}
