// The bricks of a level's fill and enclosure probes (`fill.rs`'s
// `FillTable`): where their nodes lie, and where their slots start in the
// mask pool, which both passes write.

// The lattice, the u32 light words of a node in the pool, and how far a
// node's enclosure probes reach.
struct FillHeader {
    origin: vec3<f32>,
    h: f32,
    light_words: u32,
    probe_reach: f32,
}

// A brick of the level: its coordinates, and the pool's word where its
// slot starts.
struct FillBrick {
    brick: array<i32, 3>,
    slot_start: u32,
}

struct FillTable {
    header: FillHeader,
    bricks: array<FillBrick>,
}

@group(0) @binding(FILL_BRICKS) var<storage, read> table: FillTable;

// A pass's item naming a node of the table: its brick's index in
// `table.bricks` above FILL_NODE_BITS bits of its slot in the brick
// (`fill.rs`'s `table_node`).
fn table_entry(item: u32) -> FillBrick {
    return table.bricks[item >> FILL_NODE_BITS];
}

fn table_slot(item: u32) -> u32 {
    return item & ((1u << FILL_NODE_BITS) - 1u);
}

// Where node `slot` of the table's brick `entry` lies, as the CPU places
// it.
fn table_node_position(entry: FillBrick, slot: u32) -> vec3<f32> {
    let brick = vec3<i32>(entry.brick[0], entry.brick[1], entry.brick[2]);
    return lattice_position(table.header.origin, table.header.h, brick_node(brick, slot));
}
