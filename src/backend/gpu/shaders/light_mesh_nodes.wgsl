// The light mesh's nodes as the GPU holds them: the lattice and the
// interpolation radius (the directory's header), the half-ball around a
// point (`Lattice::half_ball`, rounding as its rows of eight lanes do),
// and each node's mask and enclosure flag, found through the directory in
// the pool (`mask_pool.rs`), read as `NodeMask` reads them.

struct MeshHeader {
    origin: vec3<f32>,
    h: f32,
    radius: f32,
    // u32 words of lights per group of a node's mask.
    light_words: u32,
    entry_mask: u32,
    point_to_node_tests: u32,
    // The kernel's 1/r² (`kernel::Weights`), and the kernel: KERNEL_BOX
    // or KERNEL_SMOOTH.
    inverse_radius_squared: f32,
    kernel: u32,
    // How lamps' sets are sized (`lightmesh/penumbra.rs`): PENUMBRA_FIXED,
    // PENUMBRA_BLOCKER, or PENUMBRA_WIDE where the wide set is also asked.
    penumbra: u32,
    // The faint lamps' budget, ε in steps of 2^-FAINT_BUDGET_BITS
    // (`faint.wgsl`); 0 sizes every lamp's penumbra.
    faint_parts: u32,
}

struct Directory {
    header: MeshHeader,
    // (brick x, y, z, slot); slot -1: empty.
    entries: array<vec4<i32>>,
}

@group(0) @binding(DIRECTORY) var<storage, read> directory: Directory;
@group(0) @binding(POOL) var<storage, read> pool: array<u32>;
// A slot holds BRICK_NODES nodes, each a pair of words (GROUPS) per light
// word: the lights the node sees (VISIBLE), and which of those bits are
// valid (VALID). A half-ball's box spans at most MAX_SPAN nodes on each
// axis.
// 8 f32 epsilons, 2^-20.
const ON_PLANE_EPSILONS: f32 = 9.5367431640625e-7;

// The nodes within `radius` of `p` on the side `n` faces, as
// `Lattice::half_ball` bounds and tests them, on the mesh's lattice or one
// of its levels (the same origin, step `h`: `lightmesh/penumbra.rs`).
struct HalfBall {
    p: vec3<f32>,
    n: vec3<f32>,
    h: f32,
    // Mesh steps per step of its lattice: the walk gives mesh nodes.
    steps: i32,
    low: vec3<i32>,
    span: vec3<i32>,
    radius_squared: f32,
    on_plane: f32,
}

// The mesh's own half-ball: radius kI·h.
fn half_ball(p: vec3<f32>, n: vec3<f32>) -> HalfBall {
    return half_ball_at(p, n, 1);
}

// The half-ball on the level of `steps` mesh steps (the mesh's origin,
// step steps·h, radius steps·kI·h): the mesh's own for 1, the wide set's
// for 2 (`lightmesh/wide.rs`). Scaling by a power of two is exact, so its
// step and radius are the CPU's to the bit.
fn half_ball_at(p: vec3<f32>, n: vec3<f32>, steps: i32) -> HalfBall {
    let h = mul(directory.header.h, f32(steps));
    let radius = mul(directory.header.radius, f32(steps));
    let origin = directory.header.origin;
    let local = lattice_local(p, h);
    let reach_steps = div(radius, h);
    let low = vec3<i32>(ceil(local - vec3<f32>(reach_steps)));
    let high = vec3<i32>(floor(local + vec3<f32>(reach_steps)));
    let span = clamp(high - low + vec3<i32>(1), vec3<i32>(0), vec3<i32>(MAX_SPAN));
    // `Lattice::on_plane_tolerance`: 8 epsilon times the magnitudes.
    let magnitude = (max_abs(p) + max_abs(origin)) + radius;
    let on_plane = mul(ON_PLANE_EPSILONS, magnitude);
    return HalfBall(p, n, h, steps, low, span, mul(radius, radius), on_plane);
}

// `lightmesh/wide.rs`: a point also asks the half-ball of radius 2·kI·h on
// the lattice of step 2h about the lamps its own set agrees on; where that
// wide set disagrees on one, the lamp's share is sized by its blocker.
// Its lattice has WIDE_STEPS mesh steps per step.

fn asks_wide_set() -> bool {
    return directory.header.penumbra == PENUMBRA_WIDE;
}

// `Penumbra::probes_grazing_lamps`.
fn probes_grazing_lamps() -> bool {
    return directory.header.penumbra == PENUMBRA_WIDE;
}

// Whether `light` has a lamp to size a penumbra by (`wide::lamps`).
fn is_lamp(light: Light) -> bool {
    return light.directional == 0u && light.lamp_radius > 0.0;
}

// `wide::lamps`, word `word` (32 lights); none where penumbrae are fixed.
fn lamp_bits(word: u32) -> u32 {
    if directory.header.penumbra == PENUMBRA_FIXED {
        return 0u;
    }
    var bits = 0u;
    for (var bit = 0u; bit < 32u; bit++) {
        let index = word * 32u + bit;
        if index < params.light_count && is_lamp(lights[index]) {
            bits |= 1u << bit;
        }
    }
    return bits;
}

// `Lattice::local`: `p` in steps `h` from the origin, fractional.
fn lattice_local(p: vec3<f32>, h: f32) -> vec3<f32> {
    let from_origin = p - directory.header.origin;
    return vec3<f32>(div(from_origin.x, h), div(from_origin.y, h), div(from_origin.z, h));
}

fn max_abs(v: vec3<f32>) -> f32 {
    return max(abs(v.x), max(abs(v.y), abs(v.z)));
}

// `node_position(node)[axis] - p[axis]` as the CPU rounds it, on the
// lattice of step `h`.
fn node_offset(origin: f32, h: f32, index: i32, p: f32) -> f32 {
    return (origin + mul(h, f32(index))) - p;
}

fn node_position(node: vec3<i32>) -> vec3<f32> {
    return node_position_at(node, directory.header.h);
}

// Where `node` of the lattice of step `h` lies.
fn node_position_at(node: vec3<i32>, h: f32) -> vec3<f32> {
    return lattice_position(directory.header.origin, h, node);
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
// (`known`, then `enclosed`, FLAG_WORDS each).
fn slot_size() -> u32 {
    return BRICK_NODES * GROUPS * directory.header.light_words + 2u * FLAG_WORDS;
}

// Where one node's mask is in the pool, and whether the node lies inside
// closed geometry; `found` is false where its brick is not in the pool
// (no bit of it was ever needed: it sees nothing).
struct NodeMask {
    found: bool,
    base: u32,
    // Whether the enclosure flag is known, and its value.
    settled: bool,
    enclosed: bool,
}

// The last brick looked up: a row of nodes mostly stays in one.
var<private> cached_brick: vec3<i32>;
var<private> cached_slot: i32 = -2;

fn node_mask(node: vec3<i32>) -> NodeMask {
    let brick = node >> vec3<u32>(BRICK_SHIFT);
    if cached_slot == -2 || any(brick != cached_brick) {
        cached_brick = brick;
        cached_slot = brick_slot(brick);
    }
    if cached_slot < 0 {
        return NodeMask(false, 0u, false, false);
    }
    let local = vec3<u32>(node & vec3<i32>(i32(BRICK_EDGE) - 1));
    let in_brick = (local.z * BRICK_EDGE + local.y) * BRICK_EDGE + local.x;
    let slot_base = u32(cached_slot) * slot_size();
    let words = directory.header.light_words;
    let known = slot_base + BRICK_NODES * GROUPS * words + in_brick / 32u;
    let bit = in_brick % 32u;
    let settled = (pool[known] >> bit & 1u) == 1u;
    let enclosed = (pool[known + FLAG_WORDS] >> bit & 1u) == 1u;
    return NodeMask(true, slot_base + in_brick * GROUPS * words, settled, enclosed);
}

fn group_word(mask: NodeMask, group: u32, word: u32) -> u32 {
    if !mask.found {
        return 0u;
    }
    return pool[mask.base + word * GROUPS + group];
}

// `NodeMask::visible`: the static bit set and no dynamic blocker.
fn visible(mask: NodeMask, word: u32) -> u32 {
    return group_word(mask, VISIBLE, word);
}

// `NodeMask::valid`: known in both layers.
fn valid(mask: NodeMask, word: u32) -> u32 {
    return group_word(mask, VALID, word);
}


// A walk over the half-ball's nodes in the CPU's order (k, j, i), one
// node per `next_node`: rows whose centre misses the ball are skipped as
// the CPU skips them, and each node is tested as its lanes test it.
struct BallWalk {
    ball: HalfBall,
    // The next node's offsets from `ball.low`; x past the span: the row
    // is done.
    at: vec3<i32>,
    // The current row's squared offsets along y and z, and the normal's
    // terms along them.
    dy2: f32,
    dz2: f32,
    n_yz: vec2<f32>,
    // The node `next_node` found, and its squared distance to the point.
    node: vec3<i32>,
    distance_squared: f32,
}

fn walk(ball: HalfBall) -> BallWalk {
    return BallWalk(ball, vec3<i32>(ball.span.x, -1, 0), 0.0, 0.0, vec2<f32>(0.0), vec3<i32>(0), 0.0);
}

// Moves `w` to the next node of the half-ball; false when none is left.
fn next_node(w: ptr<function, BallWalk>) -> bool {
    let ball = (*w).ball;
    let origin = directory.header.origin;
    loop {
        if (*w).at.x >= ball.span.x {
            (*w).at.y += 1;
            if (*w).at.y >= ball.span.y {
                (*w).at.y = 0;
                (*w).at.z += 1;
            }
            if (*w).at.z >= ball.span.z {
                return false;
            }
            let dy = node_offset(origin.y, ball.h, ball.low.y + (*w).at.y, ball.p.y);
            let dz = node_offset(origin.z, ball.h, ball.low.z + (*w).at.z, ball.p.z);
            (*w).dy2 = mul(dy, dy);
            (*w).dz2 = mul(dz, dz);
            (*w).n_yz = vec2<f32>(mul(ball.n.y, dy), mul(ball.n.z, dz));
            // (x² + y²) + z² ≥ y² + z² rounded too: no node of a row
            // whose centre misses the ball is in it.
            (*w).at.x = select(0, ball.span.x, (*w).dy2 + (*w).dz2 > ball.radius_squared);
            continue;
        }
        let i = (*w).at.x;
        (*w).at.x += 1;
        let dx = node_offset(origin.x, ball.h, ball.low.x + i, ball.p.x);
        let distance_squared = (mul(dx, dx) + (*w).dy2) + (*w).dz2;
        if distance_squared <= ball.radius_squared
            && (mul(ball.n.x, dx) + (*w).n_yz.x) + (*w).n_yz.y > ball.on_plane {
            (*w).node = (ball.low + vec3<i32>(i, (*w).at.y, (*w).at.z)) * ball.steps;
            (*w).distance_squared = distance_squared;
            return true;
        }
    }
    return false;
}
