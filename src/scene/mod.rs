//! The scene model: plain data that import produces and everything after it
//! reads. Meshes live in object space, nodes form the glTF node tree, and
//! lights and cameras hang off nodes. Nothing here knows about glTF types, so
//! the renderer, the scheduler and the backends never see the file format.
//!
//! World placement is computed by [`pose`] in `f64`, so that scenes far from
//! the origin keep their precision until the renderer subtracts its anchor.
//! Animation clips ([`animation`], with the KHR_animation_pointer paths of
//! their targets in [`pointer`]) and what deforms meshes ([`deformation`])
//! are plain data too; [`crate::anim`] samples them.

pub mod animation;
pub mod deformation;
pub mod pointer;
pub mod pose;

pub use animation::{
    AnimationClip, CameraProperty, Channel, Interpolation, LightProperty, MaterialProperty,
    Sampler, Target, TargetKind,
};
pub use deformation::{JointSet, MorphTarget, Skin};

use glam::{DMat4, Vec2, Vec3, Vec4};

/// Everything one glTF scene holds, after import.
#[derive(Clone, Debug, Default)]
pub struct SceneDesc {
    /// A short name for reports and default output paths (the file stem).
    pub name: String,
    pub nodes: Vec<Node>,
    /// Indices of the nodes at the top of the scene's tree.
    pub roots: Vec<usize>,
    pub meshes: Vec<Mesh>,
    /// Materials; meshes refer to them by index. Import appends a default
    /// material for primitives that name none.
    pub materials: Vec<Material>,
    pub textures: Vec<Texture>,
    pub lights: Vec<Light>,
    pub cameras: Vec<Camera>,
    pub skins: Vec<Skin>,
    /// The file's animations, in file order.
    pub animations: Vec<AnimationClip>,
}

/// One node of the scene tree.
#[derive(Clone, Debug, Default)]
pub struct Node {
    pub name: Option<String>,
    /// Placement relative to the parent node, in `f64` (see [`pose`]).
    pub local: DMat4,
    pub children: Vec<usize>,
    pub mesh: Option<usize>,
    pub light: Option<usize>,
    pub camera: Option<usize>,
    /// An animation channel targets this node's translation, rotation or
    /// scale: the node and everything under it move.
    pub animated: bool,
    /// The node's mesh changes shape over time (a skin or animated morph
    /// weights): its geometry must be refit per frame.
    pub deforms: bool,
    /// The skin that deforms this node's mesh (an index into
    /// `SceneDesc::skins`).
    pub skin: Option<usize>,
    /// The node's own default morph weights, which override its mesh's.
    pub weights: Option<Vec<f32>>,
}

/// A triangle mesh in object space; all glTF primitives of a mesh are merged,
/// each triangle keeping its own material.
#[derive(Clone, Debug, Default)]
pub struct Mesh {
    pub name: Option<String>,
    pub positions: Vec<Vec3>,
    /// Per-vertex shading normals, unit length (generated when the file has
    /// none).
    pub normals: Vec<Vec3>,
    /// Per-vertex texture coordinates (set 0); empty when the file has none.
    pub uvs: Vec<Vec2>,
    pub triangles: Vec<[u32; 3]>,
    /// Material index of each triangle, parallel to `triangles`.
    pub triangle_materials: Vec<u32>,
    /// Skin influences: JOINTS_0/WEIGHTS_0, JOINTS_1/WEIGHTS_1…, each
    /// parallel to `positions`; empty for a mesh no skin moves.
    pub joint_sets: Vec<JointSet>,
    pub morph_targets: Vec<MorphTarget>,
    /// Default morph weights, one per morph target.
    pub morph_weights: Vec<f32>,
}

/// glTF metallic-roughness material, with the extensions lmanim honours.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    pub name: Option<String>,
    /// Linear RGBA base colour factor.
    pub base_color: Vec4,
    pub base_color_texture: Option<TextureRef>,
    pub metallic: f32,
    pub roughness: f32,
    /// KHR_materials_specular `specularFactor`: weight of the dielectric
    /// specular lobe (1 when absent; 0 makes a purely Lambertian surface).
    pub specular: f32,
    /// Linear RGB emitted radiance factor.
    pub emissive: Vec3,
    pub emissive_texture: Option<TextureRef>,
    pub double_sided: bool,
    /// KHR_materials_transmission factor: the share of light refracted
    /// through the surface.
    pub transmission: f32,
    /// KHR_materials_ior (1.5 when absent, as the spec says).
    pub ior: f32,
}

impl Default for Material {
    fn default() -> Self {
        Material {
            name: None,
            base_color: Vec4::ONE,
            base_color_texture: None,
            metallic: 1.0,
            roughness: 1.0,
            specular: 1.0,
            emissive: Vec3::ZERO,
            emissive_texture: None,
            double_sided: false,
            transmission: 0.0,
            ior: 1.5,
        }
    }
}

/// A material's use of a texture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TextureRef {
    pub texture: usize,
    /// Which TEXCOORD_n set; only set 0 is imported, others fall back to it.
    pub tex_coord: u32,
}

/// A decoded texture in linear RGBA (sRGB-encoded images are decoded at
/// import), with the sampler's wrap modes.
#[derive(Clone, Debug)]
pub struct Texture {
    pub width: u32,
    pub height: u32,
    /// Row-major texels, top row first, `width * height` of them.
    pub texels: Vec<Vec4>,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Wrap {
    Repeat,
    MirroredRepeat,
    ClampToEdge,
}

/// A KHR_lights_punctual light in its node's space: it sits at the node's
/// origin and points down the node's −Z.
#[derive(Clone, Debug, PartialEq)]
pub struct Light {
    pub name: Option<String>,
    pub kind: LightKind,
    /// Linear RGB colour.
    pub color: Vec3,
    /// Radiant intensity in W/sr for point and spot lights (1 cd is taken as
    /// 1 W/sr, see ARCHITECTURE.md, "Conventions"), irradiance in W/m² for directional lights.
    pub intensity: f32,
    /// Distance beyond which the light has no effect (None: unbounded).
    pub range: Option<f32>,
    /// Radius of the physical lamp this point light stands for (`extras.radius`
    /// in metres); sets the soft-shadow size in the light-mesh methods.
    pub radius: Option<f32>,
    /// The light's group for compositing (`extras.group`): the lights of a
    /// group share one layer of the `light` AOV.
    pub group: Option<String>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightKind {
    Point,
    /// Cone angles in radians from the spot's axis.
    Spot {
        inner_cone: f32,
        outer_cone: f32,
    },
    Directional,
}

/// A glTF camera in its node's space: at the origin, looking down −Z, +Y up.
#[derive(Clone, Debug)]
pub struct Camera {
    pub name: Option<String>,
    pub projection: Projection,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Projection {
    Perspective {
        /// Vertical field of view in radians.
        yfov: f32,
        /// Width / height; None means the output image's aspect.
        aspect_ratio: Option<f32>,
        znear: f32,
        zfar: Option<f32>,
    },
    Orthographic {
        /// Half the view's width and height in metres.
        xmag: f32,
        ymag: f32,
        znear: f32,
        zfar: f32,
    },
}

impl SceneDesc {
    /// The camera a user means by `name`, or the first camera node in the
    /// tree when no name is given. Returns the node index.
    pub fn camera_node(&self, name: Option<&str>) -> Option<usize> {
        self.nodes.iter().enumerate().find_map(|(index, node)| {
            let camera = node.camera?;
            let wanted = match name {
                None => true,
                Some(name) => {
                    node.name.as_deref() == Some(name)
                        || self.cameras[camera].name.as_deref() == Some(name)
                }
            };
            wanted.then_some(index)
        })
    }

    /// Names of all cameras, for error messages.
    pub fn camera_names(&self) -> Vec<String> {
        self.nodes
            .iter()
            .filter_map(|node| {
                let camera = node.camera?;
                node.name
                    .clone()
                    .or_else(|| self.cameras[camera].name.clone())
            })
            .collect()
    }
}
