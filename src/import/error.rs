//! The import boundary's error: which file, and what is wrong with it.
//!
//! Every fault names the glTF object it found in the file (accessor 3, node 7,
//! buffer 0…) so that a user can open the file and look; [`ImportError`] adds
//! the file path and keeps the whole message on one line, so that a CLI can
//! print it as is and a batch log stays one line per failed file.

use std::fmt;
use std::path::PathBuf;

/// A file that could not be imported, and why.
#[derive(Debug)]
pub struct ImportError {
    /// The path as the caller gave it.
    pub file: PathBuf,
    pub fault: Fault,
}

impl fmt::Display for ImportError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        // Foreign messages (serde, io, image) are one line today; folding any
        // line break keeps the promise if one of them changes.
        let fault = self.fault.to_string().replace(['\n', '\r'], " ");
        write!(f, "{}: {}", self.file.display(), fault)
    }
}

impl std::error::Error for ImportError {
    fn source(&self) -> Option<&(dyn std::error::Error + 'static)> {
        Some(&self.fault)
    }
}

/// What is wrong with a file. Indices are the file's own glTF indices.
#[derive(Debug, thiserror::Error)]
pub enum Fault {
    #[error("cannot read the file: {0}")]
    Read(#[source] std::io::Error),
    #[error("not a binary glTF: the header's magic is {found:?}, expected \"glTF\"")]
    GlbMagic { found: String },
    #[error("binary glTF {0}")]
    GlbLayout(String),
    #[error("malformed JSON: {0}")]
    Json(#[source] serde_json::Error),
    /// Well-formed JSON that does not have glTF 2.0's shape (a missing
    /// required property, a string where a number belongs).
    #[error("not glTF 2.0 JSON: {0}")]
    Schema(#[source] serde_json::Error),
    /// A rule of the glTF 2.0 spec that the file breaks, at a JSON path
    /// such as `animations[0].channels[2].target.node`.
    #[error("{path}: {rule}")]
    Rule { path: String, rule: String },
    #[error("requires extension {0}, which lmanim does not support")]
    UnsupportedExtension(String),
    /// The glTF crate's schema validation, or a reference check of our own.
    #[error("invalid glTF: {0}")]
    Invalid(String),
    /// Valid glTF (`scenes` is optional), but not a picture: such a file
    /// is a library of nodes, meshes and materials for other files to use.
    #[error("the file holds no scene: it is a library of entities for other files to use, with nothing to render")]
    NoScene,
    #[error("buffers[{buffer}].uri ({uri}) cannot be read: {reason}")]
    BufferSource {
        buffer: usize,
        uri: String,
        reason: String,
    },
    #[error("buffer {buffer} declares {declared} bytes but its data has only {actual}")]
    BufferLength {
        buffer: usize,
        declared: usize,
        actual: usize,
    },
    #[error("buffer view {view} reads bytes {start}..{end} but buffer {buffer} has {length}")]
    ViewOutOfBounds {
        view: usize,
        start: usize,
        end: usize,
        buffer: usize,
        length: usize,
    },
    #[error("accessor {accessor} ({usage}) reads bytes {start}..{end} but buffer view {view} has {length}")]
    AccessorOutOfBounds {
        accessor: usize,
        usage: String,
        start: usize,
        end: usize,
        view: usize,
        length: usize,
    },
    #[error("accessor {accessor} ({usage}) has {found}, expected {expected}")]
    AccessorType {
        accessor: usize,
        usage: String,
        found: String,
        expected: &'static str,
    },
    #[error("accessor {accessor} ({usage}) holds a non-finite value (NaN or infinity) in element {element}")]
    NonFinite {
        accessor: usize,
        usage: String,
        element: usize,
    },
    #[error("accessor {accessor} ({usage}) holds index {index} in element {element}, past the {limit} elements it indexes")]
    IndexOutOfRange {
        accessor: usize,
        usage: String,
        element: usize,
        index: u64,
        limit: usize,
    },
    #[error("mesh {mesh} primitive {primitive}: {problem}")]
    Primitive {
        mesh: usize,
        primitive: usize,
        problem: String,
    },
    #[error("node {node} has a non-finite or degenerate transform ({problem})")]
    NodeTransform { node: usize, problem: &'static str },
    #[error("node {node} has two parents (nodes {first} and {second})")]
    TwoParents {
        node: usize,
        first: usize,
        second: usize,
    },
    #[error("node {node} is its own ancestor (a cycle in the node tree)")]
    NodeCycle { node: usize },
    #[error("scene {scene} lists node {node} as a root, but node {parent} is its parent")]
    RootWithParent {
        scene: usize,
        node: usize,
        parent: usize,
    },
    #[error("scene {scene} lists node {node} twice")]
    RootTwice { scene: usize, node: usize },
    #[error("animation {animation} channel {channel}: {problem}")]
    Animation {
        animation: usize,
        channel: usize,
        problem: String,
    },
    #[error("skin {skin}: {problem}")]
    Skin { skin: usize, problem: String },
    #[error("light {light}: {problem}")]
    Light { light: usize, problem: String },
    #[error("camera {camera}: {problem}")]
    Camera { camera: usize, problem: String },
    #[error("material {material}: {problem}")]
    Material { material: usize, problem: String },
    #[error("images[{image}] cannot be read or decoded: {reason}")]
    Image { image: usize, reason: String },
    /// A panic inside import (ours or a dependency's): a bug, reported as a
    /// fault of this file rather than a crash of a whole batch.
    #[error("internal error while importing (please report it): {0}")]
    Panic(String),
}
