//! The report `lmanim inspect` prints: the pose at chosen times, as plain
//! numbers (local TRS, world matrices, morph weights, lights and cameras in
//! world space with their animated values, and material factors when a clip
//! animates them), so that animation can be checked without rendering and
//! compared with other players.

use glam::{DMat4, DVec3};
use serde::Serialize;

use super::pose::{ClipSelection, LocalPose};
use crate::scene::pose::Pose;
use crate::scene::{LightKind, Material, Projection, SceneDesc, Target};

/// Poses at several times.
#[derive(Clone, Debug, Serialize)]
pub struct Inspection {
    pub samples: Vec<PoseReport>,
}

/// The pose at one time.
#[derive(Clone, Debug, Serialize)]
pub struct PoseReport {
    /// Seconds.
    pub time: f64,
    pub nodes: Vec<NodeReport>,
    pub lights: Vec<LightReport>,
    pub cameras: Vec<CameraReport>,
    /// Every material, only when a playing clip animates some material's
    /// factors (KHR_animation_pointer).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub materials: Option<Vec<MaterialReport>>,
}

#[derive(Clone, Debug, Serialize)]
pub struct NodeReport {
    pub index: usize,
    pub name: Option<String>,
    pub translation: [f64; 3],
    /// x, y, z, w.
    pub rotation: [f64; 4],
    pub scale: [f64; 3],
    /// Column-major, as glTF writes matrices.
    pub world: [f64; 16],
    /// Only on nodes whose mesh has morph targets.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub weights: Option<Vec<f32>>,
}

/// A light placed in the world: it shines from `position` along
/// `direction` (its node's −Z).
#[derive(Clone, Debug, Serialize)]
pub struct LightReport {
    pub node: usize,
    /// Index of the light in the file's KHR_lights_punctual list.
    pub light: usize,
    pub name: Option<String>,
    /// "point", "spot" or "directional".
    pub kind: &'static str,
    pub position: [f64; 3],
    pub direction: [f64; 3],
    pub color: [f32; 3],
    pub intensity: f32,
    pub range: Option<f32>,
    /// Cone angles in radians (spot lights only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub inner_cone_angle: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub outer_cone_angle: Option<f32>,
}

/// A camera placed in the world, looking along `direction` with `up`.
#[derive(Clone, Debug, Serialize)]
pub struct CameraReport {
    pub node: usize,
    pub camera: usize,
    pub name: Option<String>,
    pub position: [f64; 3],
    pub direction: [f64; 3],
    pub up: [f64; 3],
    /// "perspective" or "orthographic".
    pub projection: &'static str,
    /// Vertical field of view in radians (perspective only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub yfov: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub aspect_ratio: Option<f32>,
    /// Half width and height in metres (orthographic only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub xmag: Option<f32>,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub ymag: Option<f32>,
    pub znear: f32,
    pub zfar: Option<f32>,
}

/// A material's factors at one time.
#[derive(Clone, Debug, Serialize)]
pub struct MaterialReport {
    pub index: usize,
    pub name: Option<String>,
    /// Linear RGBA.
    pub base_color: [f32; 4],
    pub metallic: f32,
    pub roughness: f32,
    /// Linear RGB.
    pub emissive: [f32; 3],
    pub transmission: f32,
    pub ior: f32,
    pub specular: f32,
}

impl MaterialReport {
    fn of(index: usize, material: &Material) -> MaterialReport {
        MaterialReport {
            index,
            name: material.name.clone(),
            base_color: material.base_color.to_array(),
            metallic: material.metallic,
            roughness: material.roughness,
            emissive: material.emissive.to_array(),
            transmission: material.transmission,
            ior: material.ior,
            specular: material.specular,
        }
    }
}

/// The scene posed by `clips` at each of `times`.
pub fn inspect(scene: &SceneDesc, clips: ClipSelection, times: &[f64]) -> Inspection {
    Inspection {
        samples: times
            .iter()
            .map(|&time| report(scene, clips, time))
            .collect(),
    }
}

fn report(scene: &SceneDesc, clips: ClipSelection, time: f64) -> PoseReport {
    let local = LocalPose::at(scene, clips, time);
    let trs = local.trs.clone();
    let pose = Pose::of_locals(scene, local);
    let nodes = scene
        .nodes
        .iter()
        .enumerate()
        .map(|(index, node)| NodeReport {
            index,
            name: node.name.clone(),
            translation: trs[index].translation.to_array(),
            rotation: trs[index].rotation.to_array(),
            scale: trs[index].scale.to_array(),
            world: pose.world[index].to_cols_array(),
            weights: Some(pose.weights[index].clone()).filter(|weights| !weights.is_empty()),
        })
        .collect();
    let lights = placed(scene, |node| node.light)
        .filter_map(|(node, light)| {
            let desc = pose.properties.lights.get(light)?;
            let (position, direction, _) = frame(&pose.world[node]);
            let cones = match desc.kind {
                LightKind::Spot {
                    inner_cone,
                    outer_cone,
                } => Some((inner_cone, outer_cone)),
                LightKind::Point | LightKind::Directional => None,
            };
            Some(LightReport {
                node,
                light,
                name: desc.name.clone(),
                kind: match desc.kind {
                    LightKind::Point => "point",
                    LightKind::Spot { .. } => "spot",
                    LightKind::Directional => "directional",
                },
                position,
                direction,
                color: desc.color.to_array(),
                intensity: desc.intensity,
                range: desc.range,
                inner_cone_angle: cones.map(|(inner, _)| inner),
                outer_cone_angle: cones.map(|(_, outer)| outer),
            })
        })
        .collect();
    let cameras = placed(scene, |node| node.camera)
        .filter_map(|(node, camera)| {
            let desc = scene.cameras.get(camera)?;
            let projection = *pose.properties.cameras.get(camera)?;
            let (position, direction, up) = frame(&pose.world[node]);
            let mut report = CameraReport {
                node,
                camera,
                name: desc.name.clone(),
                position,
                direction,
                up,
                projection: "perspective",
                yfov: None,
                aspect_ratio: None,
                xmag: None,
                ymag: None,
                znear: 0.0,
                zfar: None,
            };
            match projection {
                Projection::Perspective {
                    yfov,
                    aspect_ratio,
                    znear,
                    zfar,
                } => {
                    report.yfov = Some(yfov);
                    report.aspect_ratio = aspect_ratio;
                    report.znear = znear;
                    report.zfar = zfar;
                }
                Projection::Orthographic {
                    xmag,
                    ymag,
                    znear,
                    zfar,
                } => {
                    report.projection = "orthographic";
                    report.xmag = Some(xmag);
                    report.ymag = Some(ymag);
                    report.znear = znear;
                    report.zfar = Some(zfar);
                }
            }
            Some(report)
        })
        .collect();
    let animates_materials = clips
        .clips(scene)
        .flat_map(|clip| &clip.channels)
        .any(|channel| matches!(channel.target, Target::Material(..)));
    let materials = animates_materials.then(|| {
        (pose.properties.materials.iter().enumerate())
            .map(|(index, material)| MaterialReport::of(index, material))
            .collect()
    });
    PoseReport {
        time,
        nodes,
        lights,
        cameras,
        materials,
    }
}

/// (node, item) for every node that carries the item `of` picks.
fn placed<'a>(
    scene: &'a SceneDesc,
    of: impl Fn(&crate::scene::Node) -> Option<usize> + 'a,
) -> impl Iterator<Item = (usize, usize)> + 'a {
    scene
        .nodes
        .iter()
        .enumerate()
        .filter_map(move |(index, node)| Some((index, of(node)?)))
}

/// A node's world origin, its −Z and its +Y (unit length; zero where the
/// transform collapses them).
fn frame(world: &DMat4) -> ([f64; 3], [f64; 3], [f64; 3]) {
    let position = world.transform_point3(DVec3::ZERO);
    let direction = world.transform_vector3(DVec3::NEG_Z).normalize_or_zero();
    let up = world.transform_vector3(DVec3::Y).normalize_or_zero();
    (position.to_array(), direction.to_array(), up.to_array())
}
