//! lmanim renders glTF animations to EXR image sequences, with soft shadows
//! from point lights by the Light Meshes Method (Debelov, Vasilyeva,
//! Novikov). ARCHITECTURE.md describes the data flow of one run.

pub mod accel;
pub mod anim;
pub mod backend;
pub mod bits;
pub mod camera_path;
pub mod import;
pub mod lightmesh;
pub mod output;
pub mod plan;
pub mod render;
pub mod scene;
pub mod schedule;
pub mod sequence;
pub mod settings;
pub mod stats;
pub mod study;
