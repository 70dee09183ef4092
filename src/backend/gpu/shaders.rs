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
}
