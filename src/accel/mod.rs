//! Ray tracing core: rays, the watertight triangle test, self-intersection
//! offsets, BVHs (obvhs) and the two-level [`World`] of one static structure
//! plus one structure per dynamic object. Everything here works in *render
//! space*: world space minus the scene's anchor (see `render::frame`).

pub mod ray;
pub mod world;

pub use ray::Ray;
pub use world::{Hit, World, WorldObject};
