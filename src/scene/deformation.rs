//! What lets a mesh change shape: skins (joints and their inverse bind
//! matrices) with per-vertex joint influences, and morph targets. Import
//! fills these; [`crate::anim::deform`] applies them at a pose.

use glam::{DMat4, Vec3};

/// A glTF skin: the joints that move a mesh's vertices.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Skin {
    pub name: Option<String>,
    /// Node indices; the mesh's JOINTS_n values index this list.
    pub joints: Vec<usize>,
    /// One per joint: takes the mesh's bind-space vertices into the joint's
    /// space (identity when the file gives none).
    pub inverse_bind: Vec<DMat4>,
    /// The node the file names as the skeleton's root, if any (informative:
    /// joint matrices use the joints' world transforms, as the spec says).
    pub skeleton: Option<usize>,
}

/// One JOINTS_n / WEIGHTS_n pair: up to four influences per vertex.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointSet {
    /// Indices into the skin's `joints`, one quadruple per vertex.
    pub joints: Vec<[u16; 4]>,
    /// Weights parallel to `joints`. Import normalises them so that every
    /// vertex's weights over all sets sum to 1; a vertex whose weights sum
    /// to 0 is bound wholly to the joint in its first JOINTS_0 slot, so it
    /// follows the skeleton instead of collapsing to the origin.
    pub weights: Vec<[f32; 4]>,
}

/// One morph target: offsets added to the base mesh, scaled by the
/// target's weight.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    /// POSITION offsets, parallel to `Mesh::positions`.
    pub positions: Vec<Vec3>,
    /// NORMAL offsets, parallel to `Mesh::normals`, or empty when the
    /// target leaves normals alone.
    pub normals: Vec<Vec3>,
}
