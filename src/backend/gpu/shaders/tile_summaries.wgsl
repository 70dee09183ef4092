// The tile summaries of every brick the pool holds (`agreement.wgsl`),
// made after a level's fill and enclosure probes wrote the pool and
// before formula (2) reads it, so they hold for the bits it reads. Each
// invocation takes the bricks of some directory entries
// (`params.item_count` apart), all TILES_PER_SLOT tiles of each: first
// `summarise_tiles`, each tile's own nodes, into `made`; then
// `summarise_around`, from those (bound as `summaries`), the nodes around
// each tile.

@group(0) @binding(ANSWERS) var<storage, read_write> made: array<u32>;

// Tile `index` of `brick`, in tile coordinates of its lattice, and that
// lattice's mesh steps.
struct SlotTile {
    tile: vec3<i32>,
    steps: i32,
}

fn slot_tile(brick: vec3<i32>, index: u32) -> SlotTile {
    if index == WIDE_TILE {
        return SlotTile(brick, WIDE_STEPS);
    }
    let edge = i32(BRICK_TILES);
    return SlotTile(brick * edge + tile_offset(i32(index), edge), 1);
}

// `Agreement::own`: the summary of the own nodes of tile `index` of
// `brick`, whose slot is `slot`.
fn summarise_own(brick: vec3<i32>, slot: u32, index: u32) {
    let words = directory.header.light_words;
    let base = summary_base(slot, index);
    let slot_base = slot * slot_size();
    let enclosed_words = slot_base + BRICK_NODES * GROUPS * words + FLAG_WORDS;
    let at = slot_tile(brick, index);
    let steps = u32(at.steps);
    let first = vec3<u32>(at.tile * (TILE_EDGE * at.steps) - brick * i32(BRICK_EDGE));
    let edge = u32(TILE_EDGE);
    var enclosed = 0u;
    for (var word = 0u; word < words; word++) {
        var all = 0xffffffffu;
        var none = 0xffffffffu;
        for (var node = 0u; node < edge * edge * edge; node++) {
            let local = first + steps * vec3<u32>(node % edge, node / edge % edge, node / (edge * edge));
            let in_brick = (local.z * BRICK_EDGE + local.y) * BRICK_EDGE + local.x;
            let at = slot_base + in_brick * GROUPS * words + word * GROUPS;
            let visible = pool[at + VISIBLE];
            let valid = pool[at + VALID];
            all &= visible | ~valid;
            none &= ~visible | ~valid;
            if word == 0u {
                enclosed |= pool[enclosed_words + in_brick / 32u] >> (in_brick % 32u) & 1u;
            }
        }
        made[base + word] = all;
        made[base + words + word] = none;
    }
    made[base + 2u * words] = enclosed;
}

// `Agreement::around`, for every tile of `brick` (whose slot is `slot`) on
// the lattice of `steps` mesh steps: the summary of the nodes around each,
// from the own summaries of the tiles that hold them. The brick's tiles
// share most of those, so each is read once, for every tile of the brick
// whose surroundings hold it; a tile whose brick the pool does not hold
// has no node to count.
fn summarise_around_brick(brick: vec3<i32>, slot: u32, steps: i32) {
    let words = directory.header.light_words;
    // The brick's tiles along each edge, the first of them, and how far
    // around a tile its points' half-balls reach: `Agreement::new`'s
    // margin, the radius in steps rounded down, and one more for the
    // rounding of the half-ball's bounds.
    let edge = select(1, i32(BRICK_TILES), steps == 1);
    let first = brick * edge;
    let h = mul(directory.header.h, f32(steps));
    let radius = mul(directory.header.radius, f32(steps));
    let margin = vec3<i32>(i32(floor(div(radius, h))) + 1);
    for (var index = 0; index < edge * edge * edge; index++) {
        let base = summary_base(slot, tile_place(first + tile_offset(index, edge), steps).index);
        for (var word = 0u; word < 2u * words; word++) {
            made[base + word] = 0xffffffffu;
        }
        made[base + 2u * words] = 0u;
    }
    let low = (first * TILE_EDGE - margin) >> vec3<u32>(TILE_SHIFT);
    let high = ((first + vec3<i32>(edge)) * TILE_EDGE + margin) >> vec3<u32>(TILE_SHIFT);
    var looked_up = vec3<i32>(0);
    var near = -2;
    for (var z = low.z; z <= high.z; z++) {
        for (var y = low.y; y <= high.y; y++) {
            for (var x = low.x; x <= high.x; x++) {
                let near_tile = vec3<i32>(x, y, z);
                let place = tile_place(near_tile, steps);
                if near == -2 || any(place.brick != looked_up) {
                    looked_up = place.brick;
                    near = brick_slot(place.brick);
                }
                if near < 0 {
                    continue;
                }
                let summary = summary_base(u32(near), place.index);
                for (var index = 0; index < edge * edge * edge; index++) {
                    let tile = first + tile_offset(index, edge);
                    let around_low = (tile * TILE_EDGE - margin) >> vec3<u32>(TILE_SHIFT);
                    let around_high = ((tile + vec3<i32>(1)) * TILE_EDGE + margin) >> vec3<u32>(TILE_SHIFT);
                    if any(near_tile < around_low) || any(near_tile > around_high) {
                        continue;
                    }
                    let base = summary_base(slot, tile_place(tile, steps).index);
                    for (var word = 0u; word < 2u * words; word++) {
                        made[base + word] &= summaries[summary + word];
                    }
                    made[base + 2u * words] |= summaries[summary + 2u * words];
                }
            }
        }
    }
}

// Tile `index` of a brick's `edge`³, x first.
fn tile_offset(index: i32, edge: i32) -> vec3<i32> {
    return vec3<i32>(index % edge, index / edge % edge, index / (edge * edge));
}

@compute @workgroup_size(WORKGROUP)
fn summarise_tiles(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.item_count {
        return;
    }
    for (var at = id.x; at < arrayLength(&directory.entries); at += params.item_count) {
        let entry = directory.entries[at];
        for (var index = 0u; index < TILES_PER_SLOT && entry.w >= 0; index++) {
            summarise_own(entry.xyz, u32(entry.w), index);
        }
    }
}

@compute @workgroup_size(WORKGROUP)
fn summarise_around(@builtin(global_invocation_id) id: vec3<u32>) {
    if id.x >= params.item_count {
        return;
    }
    for (var at = id.x; at < arrayLength(&directory.entries); at += params.item_count) {
        let entry = directory.entries[at];
        if entry.w >= 0 {
            summarise_around_brick(entry.xyz, u32(entry.w), 1);
            summarise_around_brick(entry.xyz, u32(entry.w), WIDE_STEPS);
        }
    }
}
