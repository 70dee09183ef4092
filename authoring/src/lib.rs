//! A small glTF 2.0 writer: tests, benchmarks and the sample animations
//! build scenes in code instead of shipping opaque binaries. It sits before
//! the frame's data flow: what it writes, `import` reads. It is a crate of
//! its own, beside the renderer rather than in it: lmanim's tests, benches
//! and example depend on it, the `lmanim` library and binary do not.
//!
//! [`GltfBuilder`] collects geometry, materials (with
//! KHR_materials_transmission and KHR_materials_ior), KHR_lights_punctual
//! lights (lamp radius in `extras.radius`), cameras and a node tree, and
//! writes `.gltf` (embedded base64 buffer or external `.bin`) or `.glb`.
//! Materials, lights and cameras are given as the scene model's own types,
//! so a test can compare an import with what it wrote. [`shapes`] makes the
//! usual test geometry.
//!
//! Animation is written from the scene model's own types too: skins
//! ([`lmanim::scene::Skin`]), JOINTS_n/WEIGHTS_n and morph targets on a
//! [`Geometry`], default morph weights on meshes and nodes, and clips
//! ([`lmanim::scene::AnimationClip`], every interpolation) whose channels
//! name nodes by index, or lights, cameras and materials, which are written
//! as KHR_animation_pointer channels.
//!
//! [`city`] generates a city block of any size, and [`samples`] the scenes
//! under `animations/`.

mod animation;
mod builder;
pub mod city;
mod container;
mod error;
mod json;
pub mod samples;
pub mod shapes;
pub mod study;

pub use builder::GltfBuilder;
pub use error::AuthoringError;

use glam::{Mat3, Quat, Vec2, Vec3};

use lmanim::scene::{JointSet, Material, MorphTarget};

/// Triangle geometry in object space: one glTF primitive's attributes.
/// Triangles wind counter-clockwise seen from their front.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Geometry {
    pub positions: Vec<Vec3>,
    /// Unit normals, one per position.
    pub normals: Vec<Vec3>,
    /// Texture coordinates (TEXCOORD_0), one per position, or none at all.
    pub uvs: Vec<Vec2>,
    /// Three indices per triangle.
    pub indices: Vec<u32>,
    /// JOINTS_n/WEIGHTS_n, each one influence quadruple per position; the
    /// joint indices index the skin of the node that uses the mesh.
    pub joint_sets: Vec<JointSet>,
    /// Morph targets: one POSITION offset per position, and NORMAL offsets
    /// per normal or none.
    pub morph_targets: Vec<MorphTarget>,
}

macro_rules! id_type {
    ($(#[$doc:meta])* $name:ident) => {
        $(#[$doc])*
        #[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
        pub struct $name(pub(crate) usize);

        impl $name {
            /// The index of the item in its glTF array.
            pub fn index(self) -> usize {
                self.0
            }
        }
    };
}

id_type!(
    /// A geometry's accessors, shareable by several meshes.
    GeometryId
);
id_type!(
    /// An index into the glTF `meshes` array.
    MeshId
);
id_type!(
    /// An index into the glTF `materials` array.
    MaterialId
);
id_type!(
    /// An index into the glTF `nodes` array.
    NodeId
);
id_type!(
    /// An index into the KHR_lights_punctual `lights` array.
    LightId
);
id_type!(
    /// An index into the glTF `cameras` array.
    CameraId
);
id_type!(
    /// An index into the glTF `skins` array.
    SkinId
);

/// One primitive of a mesh: geometry drawn with a material (None: the
/// glTF default material).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Primitive {
    pub geometry: GeometryId,
    pub material: Option<MaterialId>,
}

/// A node to add: placement relative to its parent (translation, rotation,
/// scale) and what hangs off it. Children must be added before their
/// parent, which makes cycles impossible.
#[derive(Clone, Debug, PartialEq)]
pub struct NodeDesc {
    pub name: Option<String>,
    pub translation: Vec3,
    /// A unit quaternion.
    pub rotation: Quat,
    pub scale: Vec3,
    pub children: Vec<NodeId>,
    pub mesh: Option<MeshId>,
    pub light: Option<LightId>,
    pub camera: Option<CameraId>,
    /// The skin that deforms the node's mesh.
    pub skin: Option<SkinId>,
    /// The node's own default morph weights, one per morph target.
    pub weights: Option<Vec<f32>>,
}

impl Default for NodeDesc {
    fn default() -> Self {
        NodeDesc {
            name: None,
            translation: Vec3::ZERO,
            rotation: Quat::IDENTITY,
            scale: Vec3::ONE,
            children: Vec::new(),
            mesh: None,
            light: None,
            camera: None,
            skin: None,
            weights: None,
        }
    }
}

impl NodeDesc {
    /// An identity node with a name, to fill in with struct update syntax.
    pub fn named(name: &str) -> NodeDesc {
        NodeDesc {
            name: Some(name.to_owned()),
            ..NodeDesc::default()
        }
    }
}

/// A dielectric (non-metal) material of one colour, for generated scenes.
pub fn matte(name: &str, colour: Vec3, roughness: f32) -> Material {
    Material {
        name: Some(name.into()),
        base_color: colour.extend(1.0),
        metallic: 0.0,
        roughness,
        ..Material::default()
    }
}

/// The rotation that turns a node's −Z (where glTF cameras and spot lights
/// point) from `eye` towards `target`, keeping its +Y as close to `up` as
/// possible. None when `eye == target` or the view is parallel to `up`.
pub fn look_at_rotation(eye: Vec3, target: Vec3, up: Vec3) -> Option<Quat> {
    let forward = (target - eye).try_normalize()?;
    let right = forward.cross(up).try_normalize()?;
    let true_up = right.cross(forward);
    Some(Quat::from_mat3(&Mat3::from_cols(right, true_up, -forward)).normalize())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn look_at_points_minus_z_at_the_target() {
        let eye = Vec3::new(1.0, 3.0, 7.0);
        let target = Vec3::new(-2.0, 0.5, -1.0);
        let rotation = look_at_rotation(eye, target, Vec3::Y).unwrap();
        let forward = (target - eye).normalize();
        assert!((rotation * Vec3::NEG_Z).abs_diff_eq(forward, 1e-5));
        // No roll: the camera's right vector stays horizontal.
        assert!((rotation * Vec3::X).y.abs() < 1e-5);
        assert!((rotation * Vec3::Y).y > 0.0);
        assert!(look_at_rotation(eye, eye, Vec3::Y).is_none());
        assert!(look_at_rotation(Vec3::ZERO, Vec3::Y, Vec3::Y).is_none());
    }
}
