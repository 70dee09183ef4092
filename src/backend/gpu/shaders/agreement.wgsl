// Where every node near a point agrees on every light it asks about,
// formula (2) needs no walk of its set (`lightmesh/agreement.rs`): each
// light is then seen by all of the set's nodes or by none. The lattice is
// cut into tiles of TILE_EDGE³ nodes, and each brick the pool holds has
// TILES_PER_SLOT summaries under its slot: its tiles on the mesh's
// lattice, then its one tile on the wide set's (every other node). A
// summary (`summary_words` words) holds per light word the lights
// every node sees, then those no node sees, then whether some node is
// enclosed. A node's invalid bit counts as both: a point's set holds only
// nodes whose bits for its lights are valid, so a summary that also
// covers other nodes can only make a point walk, never change what it
// gets. `tile_summaries.wgsl` makes them after each level's fill: first
// each tile's own nodes', then, bound here, those of the nodes around
// each tile (every node a half-ball of a point in one of the tile's
// cells may hold).

@group(0) @binding(TILE_SUMMARIES) var<storage, read> summaries: array<u32>;

// Where a point's tile has no summary to settle it by.
const NO_SUMMARY: u32 = 0xffffffffu;

fn summary_words() -> u32 {
    return 2u * directory.header.light_words + 1u;
}

// Where the summary of tile `index` of `slot` starts.
fn summary_base(slot: u32, index: u32) -> u32 {
    return (slot * TILES_PER_SLOT + index) * summary_words();
}

// A tile of the lattice of `steps` mesh steps (1, or WIDE_STEPS for the
// wide set's, whose tiles are whole bricks): its brick, and its summary's
// index under the brick's slot.
struct TilePlace {
    brick: vec3<i32>,
    index: u32,
}

fn tile_place(tile: vec3<i32>, steps: i32) -> TilePlace {
    let first = tile * (TILE_EDGE * steps);
    let brick = first >> vec3<u32>(BRICK_SHIFT);
    if steps != 1 {
        return TilePlace(brick, WIDE_TILE);
    }
    let sub = vec3<u32>(first & vec3<i32>(i32(BRICK_EDGE) - 1)) >> vec3<u32>(TILE_SHIFT);
    return TilePlace(brick, (sub.z * BRICK_TILES + sub.y) * BRICK_TILES + sub.x);
}

// Whether a summary may settle a point's set: not LMM's (what the point
// sees, which no summary knows), nor one of a kI whose half-ball may hold
// no node (`agreement::SMALLEST_KI`), which formula (1) answers instead.
// The wide set's kI is the mesh's.
fn summaries_settle() -> bool {
    let header = directory.header;
    return header.point_to_node_tests == 0u && div(header.radius, header.h) >= f32(SUMMARY_SMALLEST_KI);
}

// The summary of the nodes around a tile that holds the half-balls of
// the point `p` with normal `n` on the lattice of `steps` mesh steps;
// NO_SUMMARY where none may settle it (`summaries_settle`), or for a cell
// beyond node coordinates or a brick the pool does not hold.
//
// The tile is not that of the point's cell, as the CPU takes it, but that
// of the cell's corner the normal faces, which is a node of the point's
// half-ball (within √3 steps, in front of the surface) unless the point
// lies on one of the corner's planes: so its brick is one the pool holds
// for the point, where the cell's own brick often lies behind the
// surface, no node of it ever asked for. The corner is the cell's first
// node or the next on each axis, and the half-ball's nodes lie within
// the radius in steps rounded down of the cell, and one more: within the
// margin of the corner, which a summary around its tile covers.
fn summary_around(p: vec3<f32>, n: vec3<f32>, steps: i32) -> u32 {
    if !summaries_settle() {
        return NO_SUMMARY;
    }
    let h = mul(directory.header.h, f32(steps));
    let cell = floor(lattice_local(p, h));
    // NaN fails the test too.
    if !all(abs(cell) < vec3<f32>(f32(MAX_NODE_COORDINATE))) {
        return NO_SUMMARY;
    }
    let corner = vec3<i32>(cell) + vec3<i32>(n >= vec3<f32>(0.0));
    let place = tile_place(corner >> vec3<u32>(TILE_SHIFT), steps);
    let slot = brick_slot(place.brick);
    if slot < 0 {
        return NO_SUMMARY;
    }
    return summary_base(u32(slot), place.index);
}

// The lights of word `word` that every node of the summary at `base` sees.
fn seen_by_all(base: u32, word: u32) -> u32 {
    return summaries[base + word];
}

// Whether the summary at `base` settles each light of `asked` (word
// `word`): every node sees it, or none does. A node inside closed
// geometry that hides a light leaves the set, which a light hidden from
// every node cannot tell from the summary (a set of such nodes alone
// would be empty), so where some node is enclosed only the first settles.
fn settles(base: u32, word: u32, asked: u32) -> bool {
    let words = directory.header.light_words;
    let enclosed = summaries[base + 2u * words] != 0u;
    let none = select(summaries[base + words + word], 0u, enclosed);
    return (asked & ~(seen_by_all(base, word) | none)) == 0u;
}
