//! The one error type of the authoring boundary: what was wrong with the
//! scene being built, or which file could not be written.

use lmanim::output::OutputError;

/// Why a glTF file could not be built or written.
#[derive(Debug, thiserror::Error)]
pub enum AuthoringError {
    #[error("geometry #{index}: {fault}")]
    Geometry { index: usize, fault: String },
    #[error("mesh `{name}`: {fault}")]
    Mesh { name: String, fault: String },
    #[error("material `{name}`: {fault}")]
    Material { name: String, fault: String },
    #[error("light `{name}`: {fault}")]
    Light { name: String, fault: String },
    #[error("camera `{name}`: {fault}")]
    Camera { name: String, fault: String },
    #[error("node `{name}`: {fault}")]
    Node { name: String, fault: String },
    #[error("skin `{name}`: {fault}")]
    Skin { name: String, fault: String },
    #[error("animation `{name}`: {fault}")]
    Animation { name: String, fault: String },
    #[error(transparent)]
    Write(#[from] OutputError),
}
