//! The numbers the Rust side and the WGSL must agree on, each written
//! once: binding numbers, the workgroup size, the bits of flag words, the
//! indices of counter arrays, the codes of enums that cross as a `u32`,
//! and the sizes both sides derive from the CPU's own constants.
//!
//! Every constant here is a Rust `pub const` and, under the same name, a
//! WGSL `const` of [`prelude`], which [`super::shaders::source`] puts at
//! the head of every module: a shader writes `@binding(LIGHTS)` or
//! `counters[COUNTER_SHADING_POINTS]`, never the number. naga takes a
//! const-expression in `@binding`, `@workgroup_size` and array sizes and
//! folds it as it parses, so a module compiles to what it did with the
//! literals; generating the declarations instead would take the
//! declarations out of the shader files. The structs' layouts are the
//! other half of the contract, held by `shaders.rs`'s layout test; the
//! tests below fail where a shader writes a number this module names.
//!
//! One binding number may carry several names: passes bind only what
//! they declare, so those that never share a module reuse the numbers
//! beyond the world's arrays (the surface pass's `HITS` and formula (1)'s
//! `LIGHTS` are both 10).

use crate::lightmesh::kernel::Kernel;
use crate::lightmesh::penumbra::{self, Penumbra};
use crate::lightmesh::{agreement, enclosure, faint, lamp_disk, lattice, masks, wide_ball};
use crate::plan::Shadows;

/// Declares each constant once: as a Rust `pub const` and as a line of
/// [`prelude`] with the same name and value.
macro_rules! contract {
    ($($(#[doc = $doc:literal])* $name:ident: $ty:ident = $value:expr;)*) => {
        $($(#[doc = $doc])* pub const $name: $ty = $value;)*

        /// The WGSL `const` of every constant of this module, one a line.
        pub fn prelude() -> String {
            [$(declaration(stringify!($name), $name)),*].concat()
        }
    };
}

contract! {
    /// Invocations per workgroup of every entry point, which is also the
    /// block a compaction scan covers (`scan_blocks.wgsl`).
    WORKGROUP: u32 = 64;

    // Bindings of group 0. Every pass: its uniform, its items (one
    // invocation each), its answers (one per item).
    /// `common.wgsl`'s `Params`.
    PARAMS: u32 = 0;
    /// A pass's items.
    ITEMS: u32 = 1;
    /// A pass's answers.
    ANSWERS: u32 = 7;

    // The world's arrays (`scene.wgsl`), bound by the passes that trace.
    /// The static structure's wide nodes.
    WIDE_NODES: u32 = 2;
    /// The dynamic objects' binary nodes.
    BINARY_NODES: u32 = 3;
    /// The static triangles' vertices.
    STATIC_VERTICES: u32 = 4;
    /// The static triangles' ids.
    STATIC_IDS: u32 = 5;
    /// The dynamic objects' instances.
    INSTANCES: u32 = 6;
    /// The dynamic objects' vertices.
    DYNAMIC_VERTICES: u32 = 8;
    /// The dynamic objects' triangle ids.
    DYNAMIC_IDS: u32 = 9;

    // Further arrays, by pass.
    /// The frame's lights (`omega.wgsl`): formula (1), formula (2), its
    /// coverage, the fill.
    LIGHTS: u32 = 10;
    /// The points' direct light, which the film accumulates.
    DIRECT: u32 = 10;
    /// The camera rays of the points whose first hits the AOV film takes.
    PATHS: u32 = 10;
    /// The points a gather reads from.
    GATHER_SOURCE: u32 = 10;
    /// The surface pass's closest hits.
    HITS: u32 = 10;
    /// Formula (2)'s reaching lights per point, from the coverage pass.
    REACH: u32 = 11;
    /// The surface pass's meshes.
    MESHES: u32 = 11;
    /// The mask pool's directory (`mask_pool.rs`).
    DIRECTORY: u32 = 12;
    /// The surface pass's mesh words.
    MESH_WORDS: u32 = 12;
    /// A level's bricks, which its fill and enclosure probes write: where
    /// their nodes lie and their slots start (`fill.rs`'s `FillTable`).
    FILL_BRICKS: u32 = 12;
    /// The mask pool's slots.
    POOL: u32 = 13;
    /// The surface pass's texture records.
    TEXTURES: u32 = 13;
    /// Formula (2)'s counters ([`LIGHT_MESH_COUNTERS`] words).
    COUNTS: u32 = 14;
    /// The surface pass's texels.
    TEXELS: u32 = 14;
    /// The coverage pass's flags: points served, bricks read.
    FLAGS: u32 = 15;
    /// The surface pass's object records.
    OBJECTS: u32 = 15;
    /// The coverage pass's copies of the points it does not serve.
    GATHERED: u32 = 16;
    /// The pool's tile summaries (`agreement.wgsl`): formula (2) reads
    /// those of the nodes around each tile, which are made from those of
    /// each tile's own nodes.
    TILE_SUMMARIES: u32 = 24;
    /// The points' sums per light layer (`light_layers.wgsl`,
    /// `accumulate_layers.wgsl`).
    POINT_LAYERS: u32 = 16;
    /// The surface pass's material records.
    MATERIALS: u32 = 16;
    /// The surface pass's deformed vertices.
    DEFORMED: u32 = 17;
    /// The film's counters ([`FILM_COUNTERS`] words).
    COUNTERS: u32 = 18;
    /// A compaction pass's second output: the scatter's ray counts, the
    /// block scan's totals.
    SECOND_OUTPUT: u32 = 18;
    /// The scatter's ray slots, which the compaction packs.
    SLOTS: u32 = 19;
    /// Each slot's offset within its block.
    LOCAL_OFFSETS: u32 = 20;
    /// Each block's offset.
    BLOCK_OFFSETS: u32 = 21;
    /// The frame's background and ambient sky (`environment.wgsl`).
    ENVIRONMENT: u32 = 22;
    /// The next level's length, which the compaction writes.
    LEVEL_LENGTH: u32 = 23;
    /// Words of a level's length (`scan_sums.wgsl`): its item count,
    /// which goes into each of its passes' parameters, then the
    /// workgroups in x, y and z, wgpu's indirect dispatch arguments.
    LEVEL_LENGTH_WORDS: u32 = 4;

    // The film's counters (`accumulate.wgsl`, `scan_sums.wgsl`).
    /// Shading points.
    COUNTER_SHADING_POINTS: u32 = 0;
    /// Segments of no light's class.
    COUNTER_OTHER_RAYS: u32 = 1;
    /// Formula (1)'s shadow rays of the first class of [`Shadows::ALL`];
    /// the other classes follow in its order.
    COUNTER_CLASS_RAYS: u32 = 2;
    /// The plan's classes of lights, which rays are counted under.
    SHADOW_CLASSES: u32 = Shadows::ALL.len() as u32;
    /// The rays of the levels after the camera's, which the compaction
    /// counts as it makes them (`scan_sums.wgsl`).
    COUNTER_SECONDARY_RAYS: u32 = COUNTER_CLASS_RAYS + SHADOW_CLASSES;
    /// Words of the film's counters.
    FILM_COUNTERS: u32 = COUNTER_SECONDARY_RAYS + 1;

    // Formula (2)'s counters (`light_mesh.wgsl`): 64-bit counts, count i
    // in words 2i (low) and 2i + 1 (high), then one word.
    /// `PointCounts::candidates`.
    COUNT_CANDIDATES: u32 = 0;
    /// `PointCounts::interp_set`.
    COUNT_INTERPOLATION_SET: u32 = 1;
    /// `PointCounts::p2n_tests`.
    COUNT_POINT_TO_NODE_TESTS: u32 = 2;
    /// `PointCounts::fallback`.
    COUNT_FALLBACK: u32 = 3;
    /// `PointCounts::blocker_rays`.
    COUNT_BLOCKER_RAYS: u32 = 4;
    /// `PointCounts::settled`.
    COUNT_SETTLED: u32 = 5;
    /// The word after the counts: points whose loops the adapter cut
    /// short.
    LOOPS_CUT_SHORT: u32 = 2 * (COUNT_SETTLED + 1);
    /// Words of formula (2)'s counters.
    LIGHT_MESH_COUNTERS: u32 = LOOPS_CUT_SHORT + 1;

    // A light's `shading` bits (`omega.wgsl`, `direct::shading_flags`).
    /// Shaded by formula (1) (`whitted`, `auto`'s hard and unshadowed
    /// lights).
    SHADED_BY_FORMULA_ONE: u32 = 1;
    /// Shaded by formula (2) (`lmm`, `lmm1`, `auto`'s soft lights).
    SHADED_BY_LIGHT_MESH: u32 = 2;
    /// Formula (1) tests the light's shadow segment: every light but an
    /// unshadowed one.
    TESTS_SEGMENT: u32 = 4;
    /// Where the light's class sits (two bits, its index in
    /// [`Shadows::ALL`]), for counting shadow rays by class.
    CLASS_SHIFT: u32 = 3;

    // A fill segment's flags (`fill_segments.wgsl`, `fill.rs`): the low
    // bits of its `light_flags`, the light's index above them.
    /// The bits of `light_flags` that hold the flags.
    FILL_FLAG_BITS: u32 = 4;
    /// The bits of a fill segment's `brick_node` that hold the node's slot
    /// in its brick, below the brick's index in the fill's table.
    FILL_NODE_BITS: u32 = masks::BRICK_NODES.trailing_zeros();
    /// Trace the segment against the static structure.
    TEST_STATIC: u32 = 1;
    /// The node's static bit is known visible.
    KNOWN_VISIBLE: u32 = 2;
    /// Trace the segment against the dynamic objects where it is open.
    TEST_DYNAMIC: u32 = 4;
    /// The node's dynamic bit is known occluded (where it is not traced):
    /// what the fill writes into the pool when the static test finds the
    /// node open.
    KNOWN_OCCLUDED: u32 = 8;
    // A fill segment's answer: ANSWER_BITS bits, ANSWERS_PER_WORD to a
    // word, segment i's at bit ANSWER_BITS * (i % ANSWERS_PER_WORD).
    /// The bits of one segment's answer.
    ANSWER_BITS: u32 = 4;
    /// Answers packed into one u32.
    ANSWERS_PER_WORD: u32 = 32 / ANSWER_BITS;
    // A fill segment's answer bits.
    /// The static structure blocks the segment.
    STATIC_BLOCKED: u32 = 1;
    /// The segment was traced against the dynamic objects.
    DYNAMIC_TESTED: u32 = 2;
    /// A dynamic object blocks the segment.
    DYNAMIC_BLOCKED: u32 = 4;

    // The mask directory's header codes (`mask_pool::MeshHeader`): the
    // enums' own discriminants, so a code cannot name another variant.
    /// [`Penumbra::Fixed`].
    PENUMBRA_FIXED: u32 = Penumbra::Fixed as u32;
    /// [`Penumbra::Blocker`].
    PENUMBRA_BLOCKER: u32 = Penumbra::Blocker as u32;
    /// [`Penumbra::Wide`].
    PENUMBRA_WIDE: u32 = Penumbra::Wide as u32;
    /// [`Kernel::Box`].
    KERNEL_BOX: u32 = Kernel::Box as u32;
    /// [`Kernel::Smooth`].
    KERNEL_SMOOTH: u32 = Kernel::Smooth as u32;

    // Indices that name nothing.
    /// The mesh of a hit record that records no hit (`HitRecord::mesh`).
    NO_MESH: u32 = u32::MAX;
    /// A texture or deformed-vertex index of a surface record that has
    /// none.
    NONE: u32 = u32::MAX;

    // The mask pool's slots (`mask_pool.rs`): per node and light word,
    // GROUPS words side by side, so that the fill writes one pair.
    /// Nodes of a brick.
    BRICK_NODES: u32 = masks::BRICK_NODES as u32;
    /// Nodes along a brick's edge (`masks::split`, `masks::join`), and
    /// its power of two.
    BRICK_EDGE: u32 = masks::BRICK_EDGE as u32;
    BRICK_SHIFT: u32 = BRICK_EDGE.trailing_zeros();
    /// Words per node and light word.
    GROUPS: u32 = 2;
    /// The word of the lights a node sees.
    VISIBLE: u32 = 0;
    /// The word of which of those bits are valid.
    VALID: u32 = 1;
    /// u32 words of a brick's enclosure flags of each kind, after its
    /// nodes' words: `known`, then `enclosed` (`masks::BrickEnclosure`).
    FLAG_WORDS: u32 = 2 * masks::BRICK_WORDS as u32;

    // The light mesh's geometry, as the CPU bounds it.
    /// Nodes along one axis of a half-ball's box, at most.
    MAX_SPAN: i32 = lattice::MAX_SPAN as i32;
    /// u32 words of a bit per candidate of one half-ball.
    KEPT_WORDS: u32 = (MAX_SPAN as u32).pow(3).div_ceil(32);
    /// Mesh steps per step of the wide set's lattice.
    WIDE_STEPS: i32 = wide_ball::STEPS;
    /// Node coordinates stay below this in magnitude.
    MAX_NODE_COORDINATE: i32 = lattice::MAX_NODE_COORDINATE as i32;

    // Tile summaries (`lightmesh/agreement.rs`, `agreement.wgsl`).
    /// Nodes along each edge of a tile.
    TILE_EDGE: i32 = agreement::TILE_EDGE;
    TILE_SHIFT: u32 = TILE_EDGE.trailing_zeros();
    /// Tiles of the mesh's lattice along each edge of a brick.
    BRICK_TILES: u32 = BRICK_EDGE / TILE_EDGE as u32;
    /// A slot's summary of its brick's one tile on the wide set's lattice,
    /// after those of its tiles on the mesh's.
    WIDE_TILE: u32 = BRICK_TILES * BRICK_TILES * BRICK_TILES;
    /// Summaries per pool slot.
    TILES_PER_SLOT: u32 = WIDE_TILE + 1;
    /// The smallest kI whose points a summary may settle.
    SUMMARY_SMALLEST_KI: u32 = agreement::SMALLEST_KI as u32;
    /// The finest lattice level a lamp's penumbra is sized on.
    FINEST_LEVEL: i32 = penumbra::FINEST_LEVEL;
    /// The coarsest.
    COARSEST_LEVEL: i32 = penumbra::COARSEST_LEVEL;
    /// The faint lamps' rule (`faint.wgsl`): its last bucket, the bucket
    /// that marks none faint, and ε's fixed-point bits.
    FAINT_LAST_BUCKET: u32 = faint::LAST_BUCKET;
    FAINT_NONE: u32 = faint::NO_FAINT_BUCKET;
    FAINT_BUDGET_BITS: u32 = faint::BUDGET_BITS;
    /// Samples of the lamp's disk (`lamp_disk::DISK`).
    DISK_SAMPLES: u32 = lamp_disk::DISK.len() as u32;
    /// LMM1's probe directions per node (`enclosure::PROBES`).
    PROBE_COUNT: u32 = enclosure::PROBES.len() as u32;
}

// A slot's wide tile is its whole brick, every other node, and a kI the
// summaries take crosses as the integer it is.
const _: () = assert!(TILE_EDGE * WIDE_STEPS == BRICK_EDGE as i32);
const _: () = assert!(SUMMARY_SMALLEST_KI as f32 == agreement::SMALLEST_KI);

/// A constant as WGSL declares it.
fn declaration(name: &str, value: impl WgslInteger) -> String {
    format!(
        "const {name}: {} = {};\n",
        value.wgsl_type(),
        value.literal()
    )
}

/// The integer types a contract constant may have, as WGSL spells them.
trait WgslInteger {
    fn wgsl_type(&self) -> &'static str;
    fn literal(&self) -> String;
}

impl WgslInteger for u32 {
    fn wgsl_type(&self) -> &'static str {
        "u32"
    }

    fn literal(&self) -> String {
        format!("{self}u")
    }
}

impl WgslInteger for i32 {
    fn wgsl_type(&self) -> &'static str {
        "i32"
    }

    fn literal(&self) -> String {
        format!("{self}i")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Where a shader uses a contract value: the text after each of these
    /// must be a name, never a number.
    const USES: [&str; 13] = [
        "@binding(",
        "@workgroup_size(",
        "array<atomic<u32>, ",
        "atomicAdd(&counters[",
        "atomicAdd(&counts[",
        "add_count(",
        "header.penumbra == ",
        "header.penumbra != ",
        "header.kernel == ",
        "header.kernel != ",
        ".shading & ",
        "(flags & ",
        "answer |= ",
    ];

    /// The WGSL files as they are on disk.
    fn shader_files() -> Vec<(String, String)> {
        let folder = concat!(env!("CARGO_MANIFEST_DIR"), "/src/backend/gpu/shaders");
        let mut files: Vec<(String, String)> = std::fs::read_dir(folder)
            .expect("the shaders folder")
            .map(|entry| entry.expect("a shader file").path())
            .filter(|path| path.extension().is_some_and(|e| e == "wgsl"))
            .map(|path| {
                let text = std::fs::read_to_string(&path).expect("a WGSL file");
                (path.file_name().unwrap().to_string_lossy().into(), text)
            })
            .collect();
        files.sort();
        files
    }

    /// Whether `operand` starts with a literal that is the whole operand
    /// (`10)`, `3u,`, `4u) != 0u`), not a term of arithmetic on a name
    /// (`2u * which`).
    fn is_literal_operand(operand: &str) -> bool {
        let literal = operand.trim_start_matches(|c: char| c.is_ascii_alphanumeric() || c == '-');
        let after = literal.trim_start();
        operand.starts_with(|c: char| c.is_ascii_digit() || c == '-')
            && (after.starts_with([')', ']', ',', ';', '{'])
                || after.starts_with("&&")
                || after.starts_with("||"))
    }

    /// Each place in `wgsl` that writes a number where the contract has a
    /// name: a literal operand after one of [`USES`], or a `const` of a
    /// contract name.
    fn numbers_written(wgsl: &str) -> Vec<String> {
        let literal_uses = USES.iter().flat_map(|usage| {
            wgsl.match_indices(usage)
                .map(move |(at, _)| wgsl[at + usage.len()..].trim_start())
                .filter(|after| is_literal_operand(after))
                .map(move |after| format!("{usage}{}", after.lines().next().unwrap_or("")))
        });
        let prelude = prelude();
        let names = prelude
            .lines()
            .filter_map(|line| line.strip_prefix("const ")?.split(':').next());
        let redeclared = names
            .filter(|name| {
                let declaration = format!("const {name}:");
                wgsl.contains(&declaration) || wgsl.contains(&format!("const {name} ="))
            })
            .map(|name| format!("const {name}"))
            .collect::<Vec<_>>();
        literal_uses.chain(redeclared).collect()
    }

    /// No shader writes a number the contract names: a binding, workgroup
    /// size, counter index, flag or code changed here reaches every
    /// shader, and a literal brought back fails here.
    #[test]
    fn shaders_name_the_contract_constants() {
        let drifted: Vec<(String, Vec<String>)> = shader_files()
            .into_iter()
            .map(|(file, wgsl)| (file, numbers_written(&wgsl)))
            .filter(|(_, numbers)| !numbers.is_empty())
            .collect();
        assert_eq!(drifted, [], "numbers where the contract has names");
    }

    /// The check above finds a literal brought back into a real shader,
    /// at each kind of place it guards.
    #[test]
    fn a_literal_where_a_name_belongs_is_found() {
        let shaders: Vec<(String, String)> = shader_files();
        let file = |name: &str| &shaders.iter().find(|(file, _)| file == name).unwrap().1;
        let cases = [
            ("accumulate.wgsl", "@binding(ITEMS)", "@binding(1)"),
            (
                "accumulate.wgsl",
                "@workgroup_size(WORKGROUP)",
                "@workgroup_size(64)",
            ),
            (
                "accumulate.wgsl",
                "counters[COUNTER_OTHER_RAYS]",
                "counters[1]",
            ),
            (
                "light_mesh.wgsl",
                "add_count(COUNT_FALLBACK",
                "add_count(3u",
            ),
            ("light_mesh_nodes.wgsl", "== PENUMBRA_WIDE", "== 2u"),
            ("formula_one.wgsl", "& TESTS_SEGMENT", "& 4u"),
            ("fill_segments.wgsl", "& TEST_STATIC", "& 1u"),
        ];
        for (name, contract, literal) in cases {
            let wgsl = file(name);
            assert!(wgsl.contains(contract), "{name} has no {contract}");
            let drifted = wgsl.replacen(contract, literal, 1);
            assert_eq!(numbers_written(&drifted).len(), 1, "{name}: {literal}");
        }
        let redeclared = format!("const LIGHTS: u32 = {LIGHTS}u;\n{}", file("omega.wgsl"));
        assert_eq!(numbers_written(&redeclared), ["const LIGHTS"]);
    }

    /// The prelude declares what Rust defines, and parses.
    #[test]
    fn the_prelude_is_the_rust_constants() {
        let prelude = prelude();
        assert!(prelude.contains("const LIGHTS: u32 = 10u;\n"));
        assert!(prelude.contains(&format!("const FINEST_LEVEL: i32 = {FINEST_LEVEL}i;\n")));
        assert!(prelude.contains(&format!("const PENUMBRA_WIDE: u32 = {PENUMBRA_WIDE}u;\n")));
        naga::front::wgsl::parse_str(&prelude).expect("the prelude parses");
    }
}
