//! lmanim renders glTF animations to EXR image sequences, with soft shadows
//! from point lights by the Light Meshes Method (Debelov, Vasilyeva,
//! Novikov). See DESIGN.md for the data flow of one run.

pub mod accel;
pub mod import;
pub mod output;
pub mod scene;
