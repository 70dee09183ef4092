//! Ray tracing core: rays, the watertight triangle test, self-intersection
//! offsets, BVHs (built by obvhs, traversed by our own code) and the
//! two-level [`World`] of one static structure plus one structure per dynamic
//! object. Everything here works in *render space*: world space minus the
//! scene's anchor (see `render::frame`), so coordinates stay small and f32
//! precise near the camera.
//!
//! Robustness without a global epsilon: the triangle test is watertight
//! ([`triangle`]), BVH box tests are widened by their own rounding-error bound
//! ([`node_test`]), and rays leaving a surface start from an origin offset in
//! integer ULPs ([`offset_ray_origin`]). Shadow segments whose end lies on a
//! surface must offset that end the same way (towards the start).

pub mod bounds;
pub mod clusters;
pub mod flat;
mod instance;
pub mod mesh_bvh;
pub(crate) mod node_test;
pub mod offset;
pub mod ray;
pub mod shaft;
mod traverse;
pub mod triangle;
mod wide;
pub mod world;

pub use bounds::Bounds;
pub use instance::cofactor_map;
pub use offset::offset_ray_origin;
pub use ray::Ray;
pub use world::{Hit, MeshId, StaticTriangle, World, WorldError, WorldObject};

use mesh_bvh::Layout;
use obvhs::BvhBuildParams;

/// Layout of the merged static BVH: the faster one to trace on the 1M
/// triangle city (see BENCHMARKS.md, "Ray tracing core").
const STATIC_LAYOUT: Layout = Layout::Wide;

/// obvhs build preset for every mesh BVH (see BENCHMARKS.md).
const BUILD_PARAMS: BvhBuildParams = BvhBuildParams::medium_build();
