//! The WGSL of the compute passes, kept in `shaders/` as files of their own
//! and put together here at build time: WGSL has no includes, so each
//! entry point's module is the contract's constants
//! ([`super::contract::prelude`]), the arithmetic prelude (how products,
//! then quotients and roots, round: [`Arithmetic`]), the shared
//! declarations and its own file, concatenated.

use super::contract;

/// How products, quotients and roots round. The CPU rounds each f32
/// operation once (Rust never fuses), and makes the watertight test's
/// tie-breaker and triangle normals in f64; f64 runs at 1/32 to 1/64 of
/// f32's rate on consumer GPUs, so it is kept to what f32 cannot round as
/// the CPU does (`shaders/f64_work.rs` counts it).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arithmetic {
    /// Our own SPIR-V, every float operation marked `NoContraction`
    /// (Vulkan: [`super::spirv`]), on an adapter with f64: products in
    /// plain f32, which Vulkan rounds correctly and the decoration keeps
    /// from fusing; quotients (WGSL allows 2.5 ULP), roots, the
    /// tie-breaker and normals through f64. Every answer is the CPU's.
    ExactUncontracted,
    /// WGSL to the driver (nothing marks a product unfusable) on an
    /// adapter with f64: products through f64 as well, which most
    /// compilers do not fuse.
    ExactF64,
    /// No f64: plain f32, within a few ULPs of the CPU.
    PlainF32,
}

impl Arithmetic {
    pub const ALL: [Arithmetic; 3] = [
        Arithmetic::ExactUncontracted,
        Arithmetic::ExactF64,
        Arithmetic::PlainF32,
    ];

    /// The arithmetic for an adapter that has f64 or not, whose passes
    /// reach the driver as our own SPIR-V or not.
    pub fn for_adapter(f64: bool, own_spirv: bool) -> Arithmetic {
        match (f64, own_spirv) {
            (true, true) => Arithmetic::ExactUncontracted,
            (true, false) => Arithmetic::ExactF64,
            (false, _) => Arithmetic::PlainF32,
        }
    }

    /// What naga must allow to validate a module with this arithmetic.
    pub fn capabilities(self) -> naga::valid::Capabilities {
        match self {
            Arithmetic::ExactUncontracted | Arithmetic::ExactF64 => {
                naga::valid::Capabilities::FLOAT64
            }
            Arithmetic::PlainF32 => naga::valid::Capabilities::empty(),
        }
    }

    /// The prelude's two files: how products round (`mul`), then
    /// quotients, roots, the tie-breaker and normals.
    fn prelude(self) -> [&'static str; 2] {
        let product_f32 = include_str!("shaders/product_f32.wgsl");
        let exact_f64 = include_str!("shaders/exact_f64.wgsl");
        match self {
            Arithmetic::ExactUncontracted => [product_f32, exact_f64],
            Arithmetic::ExactF64 => [include_str!("shaders/product_f64.wgsl"), exact_f64],
            Arithmetic::PlainF32 => [product_f32, include_str!("shaders/exact_f32.wgsl")],
        }
    }
}

/// The compute entry points: camera rays, the two ray queries, shading
/// points, formula (1), formula (2) with its coverage of the points and
/// the gathering of those it does not cover, the light mesh's fill,
/// enclosure probes and tile summaries, the Whitted recursion's rays and their
/// compaction, and the film; formula (1) and (2) again keeping their
/// terms per light layer, and the AOV film (camera hits, light layers),
/// for `--aovs`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Entry {
    CameraRays,
    ClosestHit,
    AnyHit,
    Surface,
    DirectLight,
    LightMeshCoverage,
    GatherPoints,
    PatchPool,
    FillSegments,
    EnclosureProbes,
    SummariseTiles,
    SummariseAround,
    LightMesh,
    Scatter,
    ScanBlocks,
    ScanSums,
    Compact,
    Accumulate,
    Resolve,
    DirectLightLayers,
    LightMeshLayers,
    FirstHits,
    AccumulateLayers,
}

impl Entry {
    pub const ALL: [Entry; 23] = [
        Entry::CameraRays,
        Entry::ClosestHit,
        Entry::AnyHit,
        Entry::Surface,
        Entry::DirectLight,
        Entry::LightMeshCoverage,
        Entry::GatherPoints,
        Entry::PatchPool,
        Entry::FillSegments,
        Entry::EnclosureProbes,
        Entry::SummariseTiles,
        Entry::SummariseAround,
        Entry::LightMesh,
        Entry::Scatter,
        Entry::ScanBlocks,
        Entry::ScanSums,
        Entry::Compact,
        Entry::Accumulate,
        Entry::Resolve,
        Entry::DirectLightLayers,
        Entry::LightMeshLayers,
        Entry::FirstHits,
        Entry::AccumulateLayers,
    ];

    /// The pipeline's name in stats and in the pipeline cache: the
    /// entry point's, told apart for the light-layer variants that share
    /// one.
    pub fn pipeline_name(self) -> &'static str {
        match self {
            Entry::DirectLightLayers => "direct_light_layers",
            Entry::LightMeshLayers => "light_mesh_layers",
            entry => entry.name(),
        }
    }

    /// The entry point's name in its module.
    pub fn name(self) -> &'static str {
        match self {
            Entry::CameraRays => "camera_rays",
            Entry::ClosestHit => "closest_hit",
            Entry::AnyHit => "any_hit",
            Entry::Surface => "surface",
            Entry::DirectLight | Entry::DirectLightLayers => "direct_light",
            Entry::LightMeshCoverage => "light_mesh_coverage",
            Entry::GatherPoints => "gather_points",
            Entry::PatchPool => "patch_pool",
            Entry::FillSegments => "fill_segments",
            Entry::EnclosureProbes => "enclosure_probes",
            Entry::SummariseTiles => "summarise_tiles",
            Entry::SummariseAround => "summarise_around",
            Entry::LightMesh | Entry::LightMeshLayers => "light_mesh",
            Entry::Scatter => "scatter",
            Entry::ScanBlocks => "scan_blocks",
            Entry::ScanSums => "scan_sums",
            Entry::Compact => "compact",
            Entry::Accumulate => "accumulate",
            Entry::Resolve => "resolve",
            Entry::FirstHits => "first_hits",
            Entry::AccumulateLayers => "accumulate_layers",
        }
    }
}

const COMMON: &str = include_str!("shaders/common.wgsl");
const VECTOR: &str = include_str!("shaders/vector.wgsl");
const PATH: &str = include_str!("shaders/path.wgsl");
const SURFACE_POINT: &str = include_str!("shaders/surface_point.wgsl");
const SCHLICK: &str = include_str!("shaders/schlick.wgsl");
const ENVIRONMENT: &str = include_str!("shaders/environment.wgsl");
const UNLIT: &str = include_str!("shaders/unlit.wgsl");
const SAMPLE_RUNS: &str = include_str!("shaders/sample_runs.wgsl");
/// Where formula (1) and (2) put each light's term besides their sum:
/// nowhere, or the point's light layers (`--aovs light`).
const LIGHT_SUM: &str = include_str!("shaders/light_sum.wgsl");
const LIGHT_LAYERS: &str = include_str!("shaders/light_layers.wgsl");
/// Omega, formula (1) at a point, and the light mesh's nodes.
const OMEGA: &str = include_str!("shaders/omega.wgsl");
const FORMULA_ONE: &str = include_str!("shaders/formula_one.wgsl");
const LATTICE: &str = include_str!("shaders/lattice.wgsl");
const LIGHT_MESH_NODES: &str = include_str!("shaders/light_mesh_nodes.wgsl");
/// Which of a point's lamps are faint: their penumbrae keep the
/// half-ball's answer.
const FAINT: &str = include_str!("shaders/faint.wgsl");
const DIRECT_LIGHT: [&str; 6] = [
    VECTOR,
    SURFACE_POINT,
    SCHLICK,
    OMEGA,
    FORMULA_ONE,
    include_str!("shaders/direct_light.wgsl"),
];
const LIGHT_MESH_COVERAGE: [&str; 8] = [
    VECTOR,
    SURFACE_POINT,
    SCHLICK,
    OMEGA,
    LATTICE,
    LIGHT_MESH_NODES,
    FAINT,
    include_str!("shaders/light_mesh_coverage.wgsl"),
];
/// A level's bricks, which its fill and its enclosure probes write.
const LEVEL_BRICKS: &str = include_str!("shaders/level_bricks.wgsl");
/// The fill's segments, traced as formula (1)'s are.
const FILL_SEGMENTS: [&str; 8] = [
    VECTOR,
    SURFACE_POINT,
    SCHLICK,
    OMEGA,
    FORMULA_ONE,
    LATTICE,
    LEVEL_BRICKS,
    include_str!("shaders/fill_segments.wgsl"),
];
/// LMM1's enclosure probes.
const ENCLOSURE_PROBES: [&str; 4] = [
    VECTOR,
    LATTICE,
    LEVEL_BRICKS,
    include_str!("shaders/enclosure_probes.wgsl"),
];
/// What the nodes around each tile agree on (`lightmesh/agreement.rs`).
const AGREEMENT: &str = include_str!("shaders/agreement.wgsl");
/// The pool's tile summaries, made after each level's fill.
const TILE_SUMMARIES: [&str; 8] = [
    VECTOR,
    SURFACE_POINT,
    SCHLICK,
    OMEGA,
    LATTICE,
    LIGHT_MESH_NODES,
    AGREEMENT,
    include_str!("shaders/tile_summaries.wgsl"),
];
/// Formula (2), which falls back to formula (1).
const LIGHT_MESH: [&str; 9] = [
    VECTOR,
    SURFACE_POINT,
    SCHLICK,
    OMEGA,
    FORMULA_ONE,
    LATTICE,
    LIGHT_MESH_NODES,
    AGREEMENT,
    include_str!("shaders/light_mesh.wgsl"),
];
/// What the passes that trace share: the world and its traversal.
const TRACING: [&str; 3] = [
    include_str!("shaders/scene.wgsl"),
    include_str!("shaders/triangle.wgsl"),
    include_str!("shaders/traverse.wgsl"),
];

/// The whole module for `entry` with `arithmetic`.
pub fn source(entry: Entry, arithmetic: Arithmetic) -> String {
    let [products, rest] = arithmetic.prelude();
    let terms: &[&str] = match entry {
        Entry::DirectLight | Entry::LightMesh | Entry::FillSegments => &[LIGHT_SUM],
        Entry::DirectLightLayers | Entry::LightMeshLayers => &[LIGHT_LAYERS],
        _ => &[],
    };
    let (tracing, own): (&[&str], &[&str]) = match entry {
        Entry::CameraRays => (&[], &[VECTOR, PATH, include_str!("shaders/camera.wgsl")]),
        Entry::ClosestHit => (&TRACING, &[PATH, include_str!("shaders/closest_hit.wgsl")]),
        Entry::AnyHit => (
            &TRACING,
            &[
                include_str!("shaders/rays.wgsl"),
                include_str!("shaders/occluded.wgsl"),
            ],
        ),
        Entry::Surface => (
            &[],
            &[
                VECTOR,
                PATH,
                SURFACE_POINT,
                include_str!("shaders/surface.wgsl"),
            ],
        ),
        Entry::DirectLight | Entry::DirectLightLayers => (&TRACING, &DIRECT_LIGHT),
        Entry::LightMeshCoverage => (&[], &LIGHT_MESH_COVERAGE),
        Entry::GatherPoints => (
            &[],
            &[SURFACE_POINT, include_str!("shaders/gather_points.wgsl")],
        ),
        Entry::PatchPool => (&[], &[include_str!("shaders/patch_pool.wgsl")]),
        Entry::FillSegments => (&TRACING, &FILL_SEGMENTS),
        Entry::EnclosureProbes => (&TRACING, &ENCLOSURE_PROBES),
        Entry::SummariseTiles | Entry::SummariseAround => (&[], &TILE_SUMMARIES),
        Entry::LightMesh | Entry::LightMeshLayers => (&TRACING, &LIGHT_MESH),
        Entry::Scatter => (
            &[],
            &[
                VECTOR,
                PATH,
                SURFACE_POINT,
                SCHLICK,
                include_str!("shaders/scatter.wgsl"),
            ],
        ),
        Entry::ScanBlocks => (&[], &[include_str!("shaders/scan_blocks.wgsl")]),
        Entry::ScanSums => (&[], &[include_str!("shaders/scan_sums.wgsl")]),
        Entry::Compact => (&[], &[PATH, include_str!("shaders/compact.wgsl")]),
        Entry::Accumulate => (
            &[],
            &[
                VECTOR,
                SURFACE_POINT,
                ENVIRONMENT,
                UNLIT,
                SAMPLE_RUNS,
                include_str!("shaders/accumulate.wgsl"),
            ],
        ),
        Entry::Resolve => (&[], &[ENVIRONMENT, include_str!("shaders/resolve.wgsl")]),
        Entry::FirstHits => (
            &[],
            &[
                VECTOR,
                PATH,
                SURFACE_POINT,
                include_str!("shaders/first_hits.wgsl"),
            ],
        ),
        Entry::AccumulateLayers => (
            &[],
            &[
                VECTOR,
                SURFACE_POINT,
                ENVIRONMENT,
                UNLIT,
                SAMPLE_RUNS,
                include_str!("shaders/accumulate_layers.wgsl"),
            ],
        ),
    };
    let contract = contract::prelude();
    [contract.as_str(), products, rest, COMMON]
        .iter()
        .chain(tracing)
        .chain(own)
        .chain(terms)
        .copied()
        .collect::<Vec<_>>()
        .join("\n")
}

#[cfg(test)]
mod f64_work;

#[cfg(test)]
mod tests {
    use super::*;

    /// Every module parses and validates with naga, with and without f64,
    /// on any machine: a WGSL error shows up here, not at a user's first
    /// `--backend gpu` run.
    #[test]
    fn every_module_validates() {
        for entry in Entry::ALL {
            for arithmetic in Arithmetic::ALL {
                let module = naga::front::wgsl::parse_str(&source(entry, arithmetic))
                    .unwrap_or_else(|e| panic!("{entry:?} {arithmetic:?}: {e}"));
                naga::valid::Validator::new(
                    naga::valid::ValidationFlags::all(),
                    arithmetic.capabilities(),
                )
                .validate(&module)
                .unwrap_or_else(|e| panic!("{entry:?} {arithmetic:?}: {e:?}"));
                assert!(module.entry_points.iter().any(|e| e.name == entry.name()));
            }
        }
    }

    /// The f32 vectors of the WGSL array that `shader` declares with
    /// `declaration` (up to its opening parenthesis), as bits.
    fn array_bits(shader: &str, declaration: &str) -> Vec<Vec<u32>> {
        let list = shader
            .split_once(declaration)
            .and_then(|(_, rest)| rest.split_once(");"))
            .unwrap_or_else(|| panic!("no {declaration}"))
            .0;
        (list.split("<f32>(").skip(1))
            .map(|vector| {
                let components = vector.split_once(')').expect("a vector's )").0;
                (components.split(','))
                    .map(|x| x.trim().parse::<f32>().expect("an f32").to_bits())
                    .collect()
            })
            .collect()
    }

    /// The shader's lamp disk is the CPU's, point for point and bit for
    /// bit: both backends ask the same level nodes.
    #[test]
    fn the_shader_samples_the_lamp_disk_at_the_cpus_points() {
        use crate::lightmesh::lamp_disk::DISK;
        let shader = include_str!("shaders/light_mesh.wgsl");
        let points = array_bits(shader, "const DISK = array<vec2<f32>, DISK_SAMPLES>(");
        let cpu: Vec<Vec<u32>> = (DISK.iter())
            .map(|&(x, y)| vec![x.to_bits(), y.to_bits()])
            .collect();
        assert_eq!(points, cpu);
    }

    /// The GPU's enclosure probes go in the CPU's directions, in its
    /// order, bit for bit: both backends settle the same flags.
    #[test]
    fn the_shader_probes_in_the_cpus_directions() {
        use crate::lightmesh::enclosure::PROBES;
        let shader = include_str!("shaders/enclosure_probes.wgsl");
        let directions = array_bits(shader, "const PROBES = array<vec3<f32>, PROBE_COUNT>(");
        let cpu: Vec<Vec<u32>> = (PROBES.iter())
            .map(|direction| direction.to_array().map(f32::to_bits).to_vec())
            .collect();
        assert_eq!(directions, cpu);
    }

    /// The WGSL structs have the sizes of the Rust records uploaded into
    /// them, field offsets included: a layout drift fails here, not as
    /// garbage on the GPU.
    #[test]
    fn wgsl_structs_match_the_uploaded_records() {
        use crate::accel::flat::{FlatBinaryNode, FlatInstance, FlatWideNode};
        use crate::backend::gpu::aov_film::FirstHitRecord;
        use crate::backend::gpu::camera::CameraRecord;
        use crate::backend::gpu::direct::{DirectLight, FlatLight};
        use crate::backend::gpu::fill::{FillBrick, FillHeader, FillSegment};
        use crate::backend::gpu::film::EnvironmentRecord;
        use crate::backend::gpu::mask_pool::MeshHeader;
        use crate::backend::gpu::scene::Params;
        use crate::backend::gpu::surface::{
            MaterialRecord, MeshRecord, ObjectRecord, PathRay, SurfacePoint, TextureRecord,
        };
        use crate::backend::gpu::trace::{GpuRay, HitRecord};
        let modules: Vec<naga::Module> = Entry::ALL
            .iter()
            .map(|&entry| naga::front::wgsl::parse_str(&source(entry, Arithmetic::PlainF32)))
            .collect::<Result<_, _>>()
            .expect("parse");
        let expected = [
            (
                "Params",
                size_of::<Params>(),
                vec![0, 4, 8, 12, 16, 20, 24, 28, 32],
            ),
            (
                "WideNode",
                size_of::<FlatWideNode>(),
                vec![0, 192, 224, 232, 236],
            ),
            (
                "BinaryNode",
                size_of::<FlatBinaryNode>(),
                vec![0, 12, 16, 28],
            ),
            (
                "Instance",
                size_of::<FlatInstance>(),
                vec![0, 64, 68, 72, 76],
            ),
            ("Ray", size_of::<GpuRay>(), vec![0, 12, 16, 28]),
            (
                "HitRecord",
                size_of::<HitRecord>(),
                vec![0, 4, 8, 12, 16, 20, 24, 28],
            ),
            ("PathRay", size_of::<PathRay>(), vec![0, 12, 16, 28, 32, 44]),
            (
                "Camera",
                size_of::<CameraRecord>(),
                vec![0, 12, 16, 28, 32, 44, 48, 60, 64, 68, 72, 76, 80, 88, 92],
            ),
            (
                "SurfacePoint",
                size_of::<SurfacePoint>(),
                vec![
                    0, 12, 16, 28, 32, 44, 48, 60, 64, 76, 80, 92, 96, 108, 112, 116, 120, 124,
                ],
            ),
            (
                "MeshRecord",
                size_of::<MeshRecord>(),
                vec![0, 4, 8, 12, 16, 20, 24, 28, 32, 36, 40, 44],
            ),
            (
                "TextureRecord",
                size_of::<TextureRecord>(),
                vec![0, 4, 8, 12, 16, 20, 24, 28],
            ),
            (
                "ObjectRecord",
                size_of::<ObjectRecord>(),
                vec![0, 64, 112, 160, 164, 168, 172],
            ),
            (
                "MaterialRecord",
                size_of::<MaterialRecord>(),
                vec![0, 16, 28, 32, 36, 40, 44, 48, 52, 56, 60],
            ),
            (
                "Light",
                size_of::<FlatLight>(),
                vec![0, 12, 16, 28, 32, 44, 48, 52, 56, 60],
            ),
            ("DirectLight", size_of::<DirectLight>(), vec![0, 12, 16]),
            ("FirstHit", size_of::<FirstHitRecord>(), vec![0, 12, 16, 28]),
            (
                "Environment",
                size_of::<EnvironmentRecord>(),
                vec![0, 12, 16, 28],
            ),
            ("FillSegment", size_of::<FillSegment>(), vec![0, 4]),
            ("FillHeader", size_of::<FillHeader>(), vec![0, 12, 16, 20]),
            ("FillBrick", size_of::<FillBrick>(), vec![0, 12]),
            (
                "MeshHeader",
                size_of::<MeshHeader>(),
                vec![0, 12, 16, 20, 24, 28, 32, 36, 40, 44],
            ),
        ];
        for (name, size, offsets) in expected {
            let (module, handle, ty) = modules
                .iter()
                .find_map(|module| {
                    let (handle, ty) = module
                        .types
                        .iter()
                        .find(|(_, ty)| ty.name.as_deref() == Some(name))?;
                    Some((module, handle, ty))
                })
                .unwrap_or_else(|| panic!("no struct {name}"));
            let mut layouter = naga::proc::Layouter::default();
            layouter.update(module.to_ctx()).expect("layout");
            assert_eq!(layouter[handle].size as usize, size, "{name}");
            let naga::TypeInner::Struct { members, .. } = &ty.inner else {
                panic!("{name} is not a struct");
            };
            let found: Vec<u32> = members.iter().map(|m| m.offset).collect();
            let offsets: Vec<u32> = offsets.into_iter().map(|o| o as u32).collect();
            assert_eq!(found, offsets, "{name}");
        }
    }
}
