//! Animation at run time: sampling clips' channels ([`sample`]), posing the
//! scene at a time ([`pose`]: local TRS, world transforms, skin matrices,
//! morph weights, and through [`property`] the animated lights, cameras
//! and materials), deforming meshes at a pose ([`deform`]), and the
//! `lmanim inspect` report of poses ([`inspect`]). It sits between import,
//! which produces the clips as plain data, and the frame scheduler, which
//! compares consecutive poses.

pub mod deform;
pub mod inspect;
pub mod pose;
pub mod property;
pub mod sample;

pub use deform::{deform, deformed_mesh, DeformedMesh};
pub use pose::{ClipSelection, LocalPose, Trs};
