//! The WGSL of the ray queries, kept in `shaders/` as files of their own
//! and put together here at build time: WGSL has no includes, so each
//! entry point's module is the arithmetic prelude, the shared declarations
//! and its own file, concatenated.

/// How products and quotients round: through f64 where the adapter has it
/// (as the CPU rounds), else plain f32.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Arithmetic {
    ExactF64,
    PlainF32,
}

/// The compute entry points.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Query {
    ClosestHit,
    AnyHit,
}

impl Query {
    pub fn entry_point(self) -> &'static str {
        match self {
            Query::ClosestHit => "closest_hit",
            Query::AnyHit => "any_hit",
        }
    }
}

const SHARED: [&str; 3] = [
    include_str!("shaders/scene.wgsl"),
    include_str!("shaders/triangle.wgsl"),
    include_str!("shaders/traverse.wgsl"),
];

/// The whole module for `query` with `arithmetic`.
pub fn source(query: Query, arithmetic: Arithmetic) -> String {
    let prelude = match arithmetic {
        Arithmetic::ExactF64 => include_str!("shaders/exact_f64.wgsl"),
        Arithmetic::PlainF32 => include_str!("shaders/exact_f32.wgsl"),
    };
    let entry = match query {
        Query::ClosestHit => include_str!("shaders/closest_hit.wgsl"),
        Query::AnyHit => include_str!("shaders/occluded.wgsl"),
    };
    [prelude]
        .into_iter()
        .chain(SHARED)
        .chain([entry])
        .collect::<Vec<_>>()
        .join("\n")
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every module parses and validates with naga, with and without f64,
    /// on any machine: a WGSL error shows up here, not at a user's first
    /// `--backend gpu` run.
    #[test]
    fn every_module_validates() {
        for query in [Query::ClosestHit, Query::AnyHit] {
            for (arithmetic, capabilities) in [
                (Arithmetic::ExactF64, naga::valid::Capabilities::FLOAT64),
                (Arithmetic::PlainF32, naga::valid::Capabilities::empty()),
            ] {
                let module = naga::front::wgsl::parse_str(&source(query, arithmetic))
                    .unwrap_or_else(|e| panic!("{query:?} {arithmetic:?}: {e}"));
                naga::valid::Validator::new(naga::valid::ValidationFlags::all(), capabilities)
                    .validate(&module)
                    .unwrap_or_else(|e| panic!("{query:?} {arithmetic:?}: {e:?}"));
                assert!(module
                    .entry_points
                    .iter()
                    .any(|e| e.name == query.entry_point()));
            }
        }
    }

    /// The WGSL structs have the sizes of the Rust records uploaded into
    /// them, field offsets included: a layout drift fails here, not as
    /// garbage on the GPU.
    #[test]
    fn wgsl_structs_match_the_uploaded_records() {
        use crate::accel::flat::{FlatBinaryNode, FlatInstance, FlatWideNode};
        use crate::backend::gpu::scene::Params;
        use crate::backend::gpu::trace::{GpuRay, HitRecord};
        let module = naga::front::wgsl::parse_str(&source(Query::ClosestHit, Arithmetic::PlainF32))
            .expect("parse");
        let mut layouter = naga::proc::Layouter::default();
        layouter.update(module.to_ctx()).expect("layout");
        let expected = [
            (
                "Params",
                size_of::<Params>(),
                vec![0, 4, 8, 12, 16, 20, 24, 28],
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
            ("HitRecord", size_of::<HitRecord>(), vec![0, 4, 8, 12, 16]),
        ];
        for (name, size, offsets) in expected {
            let (handle, ty) = module
                .types
                .iter()
                .find(|(_, ty)| ty.name.as_deref() == Some(name))
                .unwrap_or_else(|| panic!("no struct {name}"));
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
