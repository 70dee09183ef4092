// Formula (2) at a batch of shading points (`lightmesh/interpolate.rs`,
// `lightmesh/lattice.rs`): the half-ball of lattice nodes around the
// point (steps 1–2), the nodes kept (LMM: those the point sees, one
// segment each; LMM1: all but the enclosed ones blocked from a light the
// point asks for), then for each light in light order its Omega times
// the share of kept nodes that see it. An empty set falls back to
// formula (1). Node masks come from the pool (`mask_pool.rs`), found
// through the directory; a point whose nodes all agree on its lights
// takes their answer from the tile summaries instead (`agreement.wgsl`).
// Under `auto` a frame may also hold lights that formula (1) shades (hard
// and unshadowed ones): their terms come first, in light order, then
// formula (2)'s, as the CPU backend sums them.
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

@group(0) @binding(ITEMS) var<storage, read> points: array<SurfacePoint>;
@group(0) @binding(ANSWERS) var<storage, read_write> direct: array<DirectLight>;
// Per point, a bit per light that can reach it, then one per lamp among
// them that is not faint (`light_mesh_coverage.wgsl`).
@group(0) @binding(REACH) var<storage, read> reach: array<u32>;
// Candidates, interpolation-set sizes, point-to-node segments, fallback
// points, blocker rays and points settled without a walk, each as a
// (low, high) pair of u32; then the points whose loops the adapter cut
// short (the contract's COUNT_* and LOOPS_CUT_SHORT).
@group(0) @binding(COUNTS) var<storage, read_write> counts: array<atomic<u32>, LIGHT_MESH_COUNTERS>;

// Whether the point keeps `node` (whose mask is `mask`) in its
// interpolation set: LMM's step 3 (the segment from the point to the node
// is clear), or LMM1's stand-in (`enclosure::blocks_some`: not an
// enclosed node blocked from a light the point asks for).
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

// Which of the point's candidates it keeps, a bit per candidate in walk
// order: settled once per point, by its first tally, then read by every
// later walk over its half-ball (one tally per further 32 lights, and the
// blocker's search for the nearest blocked node of each light the set
// disagrees on), so each point-to-node segment is traced once, not once
// per walk. A half-ball has at most MAX_SPAN³ candidates, KEPT_WORDS
// words.
var<private> kept_bits: array<u32, KEPT_WORDS>;

fn set_kept(place: u32, keeps: bool) {
    let bit = 1u << (place % 32u);
    if keeps {
        kept_bits[place / 32u] |= bit;
    } else {
        kept_bits[place / 32u] &= ~bit;
    }
}

// Whether the candidate at `place` in walk order is kept.
fn is_kept(place: u32) -> bool {
    return (kept_bits[place / 32u] >> (place % 32u) & 1u) == 1u;
}

// Whether the wide set keeps the node whose mask is `mask`: not an
// enclosed node blocked from a lamp the set was demanded for (the point's
// reaching lamps but the faint ones).
fn wide_kept(mask: NodeMask, reach_base: u32) -> bool {
    if !mask.enclosed {
        return true;
    }
    let light_words = directory.header.light_words;
    for (var word = 0u; word < light_words; word++) {
        let refined = reach[reach_base + light_words + word];
        if (refined & valid(mask, word) & ~visible(mask, word)) != 0u {
            return false;
        }
    }
    return true;
}

// `WideScratch::look`, word `word`: the lamps of `asked` on which the wide
// set's kept nodes disagree; none where the summary around the point's
// wide tile (`around`) settles them all.
fn wide_disagreements(ball: HalfBall, around: u32, reach_base: u32, word: u32, asked: u32) -> u32 {
    if asked == 0u || (around != NO_SUMMARY && settles(around, word, asked)) {
        return 0u;
    }
    var all = asked;
    var any = 0u;
    var nodes = walk(ball);
    while next_node(&nodes) {
        let mask = node_mask(nodes.node);
        if !wide_kept(mask, reach_base) {
            continue;
        }
        let seen = visible(mask, word) & asked;
        all &= seen;
        any |= seen;
    }
    return any & ~all;
}

// Bits of the per-light counters: a half-ball of at most `MAX_KI` steps
// holds fewer than 2^12 nodes, each weighing less than 2^12.
const COUNTER_BITS: u32 = 24u;
// Bits of a node's weight (`kernel::SMOOTH_WEIGHT_SCALE`).
const WEIGHT_BITS: u32 = 12u;

// `Weights::weight`: the kernel's weight of a node at squared distance
// `distance_squared`, one rounded operation per step as the CPU does.
fn node_weight(distance_squared: f32) -> u32 {
    return node_weight_at(distance_squared, directory.header.inverse_radius_squared);
}

// The same for a radius whose 1/r² is `inverse_radius_squared`.
fn node_weight_at(distance_squared: f32, inverse_radius_squared: f32) -> u32 {
    if directory.header.kernel == KERNEL_BOX {
        return 1u;
    }
    let falloff = max(1.0 - mul(distance_squared, inverse_radius_squared), 0.0);
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

// The point's first tally (`settle`) also settles which candidates it
// keeps (`kept_bits`), in the same walk: one walk fewer per point.
fn tally(ball: HalfBall, origin: vec3<f32>, reach_base: u32, word: u32, settle: bool) -> Tally {
    let wanted = reach[reach_base + word];
    var t = Tally(0u, 0u, 0u, wanted, 0u, array<u32, COUNTER_BITS>());
    var nodes = walk(ball);
    while next_node(&nodes) {
        let place = t.candidates;
        t.candidates += 1u;
        let mask = node_mask(nodes.node);
        if settle {
            set_kept(place, kept(nodes.node, mask, origin, reach_base));
        }
        if !is_kept(place) {
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

// How a point's set is settled without a walk where it asks for no light
// (`settling_summary`): every light it asks for (none) is seen by all of
// its nodes or by none, as a summary would say.
const ASKS_NOTHING: u32 = 0xfffffffeu;

// What a walk of the set for word `word` would find where `settled` (a
// summary around the point's tile, or ASKS_NOTHING) settles every light
// the point asks for: each is seen by all of the set's nodes or by none,
// so no count or weight is read (a weight of 1 stands for the set's,
// which is not empty: `agreement::SMALLEST_KI`).
fn settled_tally(settled: u32, reach_base: u32, word: u32) -> Tally {
    var all = 0u;
    if settled != ASKS_NOTHING {
        all = reach[reach_base + word] & seen_by_all(settled, word);
    }
    return Tally(0u, 0u, 1u, all, all, array<u32, COUNTER_BITS>());
}

// ASKS_NOTHING where the point asks for no light, else the summary around
// its tile where that settles every light of `reach` (from `reach_base`),
// else NO_SUMMARY: its set is walked.
fn settling_summary(p: vec3<f32>, n: vec3<f32>, reach_base: u32) -> u32 {
    var asked = 0u;
    for (var word = 0u; word < directory.header.light_words; word++) {
        asked |= reach[reach_base + word];
    }
    if asked == 0u && summaries_settle() {
        return ASKS_NOTHING;
    }
    let around = summary_around(p, n, 1);
    if around == NO_SUMMARY {
        return NO_SUMMARY;
    }
    for (var word = 0u; word < directory.header.light_words; word++) {
        if !settles(around, word, reach[reach_base + word]) {
            return NO_SUMMARY;
        }
    }
    return around;
}

// The point's tally for word `word`: from `settled` where that settles
// it, else by a walk of its set, the first of which (word 0) also settles
// which candidates it keeps.
fn point_tally(settled: u32, ball: HalfBall, origin: vec3<f32>, reach_base: u32, word: u32) -> Tally {
    if settled != NO_SUMMARY {
        return settled_tally(settled, reach_base, word);
    }
    return tally(ball, origin, reach_base, word, word == 0u);
}

fn count_of(t: Tally, light: u32) -> u32 {
    var count = 0u;
    for (var bit = 0u; bit < COUNTER_BITS; bit++) {
        count |= (t.counters[bit] >> light & 1u) << bit;
    }
    return count;
}

// Adds `amount` to the 64-bit count `which` (a COUNT_*).
fn add_count(which: u32, amount: u32) {
    let low = atomicAdd(&counts[2u * which], amount);
    if low + amount < low {
        atomicAdd(&counts[2u * which + 1u], 1u);
    }
}

// `lightmesh/penumbra.rs`: levels h·2^k for k in [FINEST_LEVEL,
// COARSEST_LEVEL], their boundaries at √2·2^k of the mesh's radius.
const SQRT_2: f32 = 1.41421353816986083984375; // f32::consts::SQRT_2
const MIN_POSITIVE: f32 = 1.17549435082228750797e-38; // f32::MIN_POSITIVE

// What a light the set disagrees on gets (`interpolate.rs`'s `Share`), or
// SHARE_FIXED where nothing sizes its penumbra and the mesh's half-ball
// share stands; and the rays it took.
const SHARE_FIXED: u32 = 0u;
const SHARE_FULL: u32 = 1u;
const SHARE_HIDDEN: u32 = 2u;
const SHARE_PART: u32 = 3u;

struct BlockerShare {
    kind: u32,
    share: f32,
    rays: u32,
}

// The first thing on a sizing ray's segment (from its start along
// `direction`, as far as `trace_segment` found it: `best`): its distance
// from the start, and the segment's length (`blocker_distance`).
struct BlockerHit {
    found: bool,
    z: f32,
    distance: f32,
}

fn blocker_hit(best: Closest, direction: vec3<f32>) -> BlockerHit {
    if best.mesh == NO_MESH {
        return BlockerHit(false, 0.0, 0.0);
    }
    let distance = root(dot3(direction, direction));
    return BlockerHit(true, mul(best.t, distance), distance);
}

// `lamp_disk::DISK`: the same points, written as the same f32 values.
const DISK = array<vec2<f32>, DISK_SAMPLES>(
    vec2<f32>(0.125, 0.0),
    vec2<f32>(-0.15964505, 0.14624794),
    vec2<f32>(0.024436234, -0.27843827),
    vec2<f32>(0.20122224, 0.26245877),
    vec2<f32>(-0.36926755, -0.065318234),
    vec2<f32>(0.34980246, -0.2225157),
    vec2<f32>(-0.11700208, 0.4352419),
    vec2<f32>(-0.22313565, -0.42963412),
    vec2<f32>(0.48411512, 0.17679806),
    vec2<f32>(-0.5036411, 0.20789573),
    vec2<f32>(0.2427883, -0.51882446),
    vec2<f32>(0.17941438, 0.5720013),
    vec2<f32>(-0.540757, -0.31337973),
    vec2<f32>(0.63436955, -0.13946436),
    vec2<f32>(-0.38714585, 0.55067515),
    vec2<f32>(-0.08943965, -0.6901997),
    vec2<f32>(0.5490717, 0.46275827),
    vec2<f32>(-0.7388785, 0.030554945),
    vec2<f32>(0.53895515, -0.5363323),
    vec2<f32>(-0.036058187, 0.77979153),
    vec2<f32>(-0.51281756, -0.6145268),
    vec2<f32>(0.8123596, 0.109301835),
    vec2<f32>(-0.6883106, 0.47890863),
    vec2<f32>(0.18808606, -0.83606136),
    vec2<f32>(0.43503326, 0.75919104),
    vec2<f32>(-0.8504484, -0.27131623),
    vec2<f32>(0.8261024, -0.38168025),
    vec2<f32>(-0.3578882, 0.8551556),
    vec2<f32>(-0.31940734, -0.88803375),
    vec2<f32>(0.84990865, 0.44668815),
    vec2<f32>(-0.94403464, 0.2488445),
    vec2<f32>(0.5365958, -0.83452976),
);

// `lamp_disk::disk_axes`: two unit vectors across `light` and each other.
struct DiskAxes {
    across: vec3<f32>,
    up: vec3<f32>,
}

fn disk_axes(light: vec3<f32>) -> DiskAxes {
    let magnitude = abs(light);
    var axis = vec3<f32>(0.0, 0.0, 1.0);
    if magnitude.x <= magnitude.y && magnitude.x <= magnitude.z {
        axis = vec3<f32>(1.0, 0.0, 0.0);
    } else if magnitude.y <= magnitude.z {
        axis = vec3<f32>(0.0, 1.0, 0.0);
    }
    let across = normalize3(cross3(light, axis));
    return DiskAxes(across, cross3(light, across));
}

// `lamp_disk::disk_nodes`, one sample: the level node (step `h`) nearest
// sample `offset` of the lamp's disk seen from `p`, lifted along its own
// line to the lamp (`to_lamp` from `p`, `lamp_height` above the surface)
// until it stands a step above the surface, at most half the way.
fn disk_node(p: vec3<f32>, n: vec3<f32>, to_lamp: vec3<f32>, lamp_height: f32, offset: vec3<f32>, h: f32) -> vec3<i32> {
    let height = dot3(offset, n);
    let rise = lane_max(lamp_height - height, MIN_POSITIVE);
    var lift = div(h - height, rise);
    lift = select(0.0, lift, lift > 0.0);
    lift = select(lift, 0.5, 0.5 < lift);
    let sample = (p + offset) + scale3(to_lamp - offset, lift);
    return vec3<i32>(floor(lattice_local(sample, h) + vec3<f32>(0.5)));
}

// Whether node `a` comes before `b` in coordinates (x, then y, then z).
fn coordinates_before(a: vec3<i32>, b: vec3<i32>) -> bool {
    if a.x != b.x {
        return a.x < b.x;
    }
    if a.y != b.y {
        return a.y < b.y;
    }
    return a.z < b.z;
}

// Per light of the word being shaded, the set's blocked node nearest the
// point, ties to the least coordinates (`LightMesh::blocker_share`): a
// bit of `nearest_found` per light that has one.
var<private> nearest_found: u32;
var<private> nearest_node: array<vec3<i32>, 32>;
var<private> nearest_distance: array<f32, 32>;

// Finds, in one walk of the set, the nearest blocked node of each light of
// `wanted` (bits of word `word`). The set is the point's own (`ball`'s
// kept nodes) or, with `wide`, its wide set. One walk for all of them
// instead of one per light keeps a point with many lamps in its penumbrae
// within lavapipe's loop budget (`loops_were_cut_short`).
fn find_nearest_blocked(ball: HalfBall, wide: bool, reach_base: u32, word: u32, wanted: u32) {
    if wanted == 0u {
        return;
    }
    var place = 0u;
    var nodes = walk(ball);
    while next_node(&nodes) {
        let here = place;
        place += 1u;
        let mask = node_mask(nodes.node);
        var kept = is_kept(here);
        if wide {
            kept = wide_kept(mask, reach_base);
        }
        if !kept {
            continue;
        }
        var blocked = wanted & ~visible(mask, word);
        while blocked != 0u {
            let bit = firstTrailingBit(blocked);
            blocked &= blocked - 1u;
            let closer = nodes.distance_squared < nearest_distance[bit]
                || (nodes.distance_squared == nearest_distance[bit] && coordinates_before(nodes.node, nearest_node[bit]));
            if (nearest_found >> bit & 1u) == 0u || closer {
                nearest_found |= 1u << bit;
                nearest_node[bit] = nodes.node;
                nearest_distance[bit] = nodes.distance_squared;
            }
        }
    }
}

// How a lamp's share at the point is sized (`lamp_share`): not at all
// (the set's answer stands); from the blocker of the centre ray or of the
// nearest blocked node of the point's own set (`LightMesh::blocker_share`)
// or of its wide set; or, for a lamp every node sees, from a ray grazing
// the surface (`LightMesh::grazing_share`).
const SIZED_BY_NOTHING: u32 = 0u;
const SIZED_BY_BLOCKER: u32 = 1u;
const SIZED_BY_WIDE_BLOCKER: u32 = 2u;
const SIZED_BY_GRAZING_RAY: u32 = 3u;

// `penumbra::GRAZING_COSINE`.
const GRAZING_COSINE: f32 = 0.3;

// The share of `light` (bit `bit` of the word) over the lamp disk of the
// lattice level its penumbra wants at the point, sized as `sizing` says;
// SHARE_FIXED where nothing sizes it. Every ray goes through the one
// `trace_segment` of the loop (see there why): first the sizing rays, at
// most two, then the level's node segments. The sizings:
// - by the blocker: the centre ray, and where it is clear the ray from
//   the set's nearest blocked node (`find_nearest_blocked`);
// - by a grazing ray (`penumbra::grazing_estimate`), for a lamp that
//   grazes the surface: a ray towards the lamp's point nearest the
//   surface, and where it is blocked the centre ray, which decides the
//   hard answer.
fn lamp_share(point: ShadePoint, origin: vec3<f32>, bit: u32, light: Light, sizing: u32) -> BlockerShare {
    if sizing == SIZED_BY_NOTHING || !is_lamp(light) {
        return BlockerShare(SHARE_FIXED, 0.0, 0u);
    }
    let grazing = sizing == SIZED_BY_GRAZING_RAY;
    let wide = sizing == SIZED_BY_WIDE_BLOCKER;
    var first_target = light.origin;
    var second_start = origin;
    if grazing {
        let n = point.geometric_normal;
        let to_lamp = light.origin - origin;
        let height = dot3(to_lamp, n);
        if !(height > 0.0 && height < mul(GRAZING_COSINE, root(dot3(to_lamp, to_lamp)))) {
            return BlockerShare(SHARE_FIXED, 0.0, 0u);
        }
        first_target = light.origin - scale3(n, lane_min(light.lamp_radius, mul(0.5, height)));
    } else if (nearest_found >> bit & 1u) != 0u {
        second_start = node_position(nearest_node[bit]);
    } else {
        second_start = point.position;
    }
    var hits: array<BlockerHit, 2>;
    var rays = 0u;
    // The level's disk (`lamp_disk::disk_nodes`), once the sizing rays
    // have found it, and what its node segments saw.
    var on_level = false;
    var hard = SHARE_FIXED;
    var radius = 0.0;
    var h = 0.0;
    var inverse_radius_squared = 0.0;
    var to_lamp = vec3<f32>(0.0);
    var axes = DiskAxes(vec3<f32>(0.0), vec3<f32>(0.0));
    var lamp_height = 0.0;
    var disk = DISK;
    var sample = 0u;
    var weight = 0u;
    var total = 0u;
    var seen = 0u;
    loop {
        var start = select(origin, second_start, rays == 1u);
        var end = select(light.origin, first_target, rays == 0u);
        if on_level {
            let at = disk[sample];
            let offset = scale3(axes.across, mul(radius, at.x)) + scale3(axes.up, mul(radius, at.y));
            let node = disk_node(point.position, point.geometric_normal, to_lamp, lamp_height, offset, h);
            weight = node_weight_at(dot3(offset, offset), inverse_radius_squared);
            total += weight;
            start = node_position_at(node, h);
            end = light.origin;
        }
        let direction = end - start;
        let best = trace_segment(start, direction, SHADOW_SEGMENT_END, on_level);
        rays += 1u;
        if on_level {
            if best.mesh == NO_MESH {
                seen += weight;
            }
            sample += 1u;
            if sample == DISK_SAMPLES {
                break;
            }
            continue;
        }
        hits[rays - 1u] = blocker_hit(best, direction);
        // The blocker's second ray follows a clear centre ray, the
        // grazing one's follows a blocked probe.
        if rays == 1u && hits[0].found == grazing {
            continue;
        }
        if grazing && !hits[0].found {
            return BlockerShare(SHARE_FIXED, 0.0, 1u);
        }
        // The centre ray is the first or the second; the blocker that
        // sizes the level is the other's where the centre is clear.
        let centre = u32(grazing);
        let centre_visible = !hits[centre].found;
        let blocker = hits[select(centre, 1u - centre, centre_visible)];
        // `LightMesh::share_over_level`: the level whose radius comes
        // nearest the one the blocker sizes, or the centre ray's answer
        // where the penumbra is too narrow for any level; SHARE_FIXED
        // where nothing was found. From the wide set only a penumbra
        // wider than the mesh's level is sized: a narrower one gets
        // SHARE_FIXED, the point's own agreed answer.
        hard = select(SHARE_HIDDEN, SHARE_FULL, centre_visible);
        if !blocker.found {
            return BlockerShare(SHARE_FIXED, 0.0, rays);
        }
        radius = div(mul(light.lamp_radius, blocker.z), max(blocker.distance - blocker.z, MIN_POSITIVE));
        // `penumbra::level`.
        let steps = div(radius, directory.header.radius);
        if !(steps >= mul(SQRT_2, ldexp(1.0, FINEST_LEVEL - 1))) {
            return BlockerShare(select(hard, SHARE_FIXED, wide), 0.0, rays);
        }
        var level = COARSEST_LEVEL;
        for (var k = FINEST_LEVEL; k < COARSEST_LEVEL; k++) {
            if steps < mul(SQRT_2, ldexp(1.0, k)) {
                level = k;
                break;
            }
        }
        if wide && level <= 0 {
            return BlockerShare(SHARE_FIXED, 0.0, rays);
        }
        h = mul(directory.header.h, ldexp(1.0, level));
        inverse_radius_squared = div(1.0, mul(radius, radius));
        to_lamp = light.origin - point.position;
        let distance = root(dot3(to_lamp, to_lamp));
        axes = disk_axes(scale3(to_lamp, div(1.0, distance)));
        lamp_height = dot3(to_lamp, point.geometric_normal);
        on_level = true;
    }
    if total == 0u {
        return BlockerShare(hard, 0.0, rays);
    }
    return BlockerShare(SHARE_PART, div(f32(seen), f32(total)), rays);
}


@compute @workgroup_size(WORKGROUP)
fn light_mesh(@builtin(global_invocation_id) id: vec3<u32>) {
    let index = id.x;
    if index >= params.item_count {
        return;
    }
    shade(index);
    if loops_were_cut_short() {
        atomicAdd(&counts[LOOPS_CUT_SHORT], 1u);
    }
}

// lavapipe (Mesa 22.3's gallivm) ends every loop of an invocation once
// 65,535 loop iterations have run in it (LP_MAX_TGSI_LOOP_ITERATIONS,
// counted over its vector of eight invocations), silently; every loop
// after that runs once. A point's formula (2) with many lamps sized by
// their blockers can pass that. A loop of at least two trips, its count
// unknown to the compiler, runs once only after the budget is spent:
// then the frame is refused instead of shaded wrong.
fn loops_were_cut_short() -> bool {
    let trips = directory.header.light_words + 1u;
    var ran = 0u;
    for (var trip = 0u; trip < trips; trip++) {
        ran += 1u;
    }
    return ran != trips;
}

// Formula (2), or formula (1) where the set is empty, at point `index`.
// Each kind of ray is traced from one place (see `trace_segment`): one
// call of formula (1), for the frame's formula-(1) lights and, where the
// set is empty, its light-mesh lights after them; one of `lamp_share`.
fn shade(index: u32) {
    let surface = points[index];
    if surface.hit == 0u {
        direct[index] = no_direct_light();
        return;
    }
    begin_terms(index);
    let point = shade_point(surface);
    let ball = half_ball(point.position, point.geometric_normal);
    let wide_ball = half_ball_at(point.position, point.geometric_normal, WIDE_STEPS);
    let origin = offset_ray_origin(point.position, point.geometric_normal);
    let light_words = directory.header.light_words;
    let reach_base = index * 2u * light_words;
    // A point whose nodes all agree on its lights takes their answer from
    // the summary around its tile, without walking its set.
    let settled = settling_summary(point.position, point.geometric_normal, reach_base);
    if settled != NO_SUMMARY {
        add_count(COUNT_SETTLED, 1u);
    }
    let first_tally = point_tally(settled, ball, origin, reach_base, 0u);
    // The summary around the point's wide tile, looked up once a word
    // asks the wide set about some lamp.
    var wide_around = NO_SUMMARY;
    var wide_looked_up = false;
    let total = first_tally.total;
    add_count(COUNT_CANDIDATES, first_tally.candidates);
    add_count(COUNT_INTERPOLATION_SET, first_tally.kept);
    let tests = first_tally.candidates * directory.header.point_to_node_tests;
    add_count(COUNT_POINT_TO_NODE_TESTS, tests);
    let falls_back = total == 0u;
    var first = no_direct_light();
    for (var round = 0u; round < 1u + u32(falls_back); round++) {
        let shading = select(SHADED_BY_FORMULA_ONE, SHADED_BY_LIGHT_MESH, round == 1u);
        first = formula_one(point, shading, first);
    }
    if falls_back {
        add_count(COUNT_FALLBACK, 1u);
        direct[index] = DirectLight(first.radiance, tests, first.class_rays);
        return;
    }
    var radiance = first.radiance;
    var blocker_rays = 0u;
    for (var word = 0u; word < light_words; word++) {
        var t = first_tally;
        if word > 0u {
            t = point_tally(settled, ball, origin, reach_base, word);
        }
        // The lamps the set agrees on and the wide set does not; the
        // nearest blocked node of those and of the lamps the set disagrees
        // on.
        let lamps = reach[reach_base + word] & lamp_bits(word);
        let refined = reach[reach_base + light_words + word];
        let agreed = select(0u, refined & (t.all | ~t.any), asks_wide_set());
        if agreed != 0u && !wide_looked_up {
            wide_around = summary_around(point.position, point.geometric_normal, WIDE_STEPS);
            wide_looked_up = true;
        }
        let wide = wide_disagreements(wide_ball, wide_around, reach_base, word, agreed);
        nearest_found = 0u;
        find_nearest_blocked(ball, false, reach_base, word, lamps & t.any & ~t.all);
        find_nearest_blocked(wide_ball, true, reach_base, word, wide);
        var lit = t.any | wide;
        while lit != 0u {
            let bit = firstTrailingBit(lit);
            lit &= lit - 1u;
            let light = lights[word * 32u + bit];
            let value = omega(point, light);
            if all(value == vec3<f32>(0.0)) {
                continue;
            }
            // The wide set disagrees on this lamp; or every node sees this
            // light: where it grazes the surface a ray towards its point
            // nearest the surface may find the point in a wedge of
            // penumbra no node reaches; or the nodes disagree on it. A
            // faint lamp keeps the set's answer (`lightmesh/faint.rs`).
            let sized = ((~lamps | refined) >> bit & 1u) != 0u;
            let in_wide = (wide >> bit & 1u) != 0u;
            let seen_by_all = (t.all >> bit & 1u) != 0u;
            var sizing = SIZED_BY_NOTHING;
            if in_wide {
                sizing = SIZED_BY_WIDE_BLOCKER;
            } else if seen_by_all {
                let probes = probes_grazing_lamps() && sized;
                sizing = select(SIZED_BY_NOTHING, SIZED_BY_GRAZING_RAY, probes);
            } else if directory.header.penumbra != PENUMBRA_FIXED && sized {
                sizing = SIZED_BY_BLOCKER;
            }
            let share = lamp_share(point, origin, bit, light, sizing);
            blocker_rays += share.rays;
            // Where nothing sizes the wide set's lamp, the set's answer
            // stands.
            let agreed_hidden = in_wide && share.kind == SHARE_FIXED && !seen_by_all;
            if share.kind == SHARE_HIDDEN || agreed_hidden {
                continue;
            }
            var term = value;
            if share.kind == SHARE_PART {
                term = scale3(value, share.share);
            } else if share.kind == SHARE_FIXED && !in_wide && !seen_by_all {
                term = scale3(value, div(f32(count_of(t, bit)), f32(total)));
            }
            radiance += term;
            keep_term(light, term);
        }
    }
    direct[index] = DirectLight(radiance, tests + blocker_rays, first.class_rays);
    add_count(COUNT_BLOCKER_RAYS, blocker_rays);
}
