//! One pose of the scene placed in *render space*: world space minus an
//! anchor fixed for the whole sequence (the centre of the scene's bounds at
//! rest). Object transforms, lights and the camera are composed in `f64`
//! and only then rounded to `f32`, so a city modelled 100 km from the origin
//! renders exactly like the same city at the origin. Lights, the camera's
//! projection and materials take the pose's (possibly animated) values.

use std::sync::Arc;

use glam::{Affine3A, DMat4, DVec3, Mat3, Vec3};

use super::camera::RenderCamera;
use super::light::RenderLight;
use crate::accel::{World, WorldObject};
use crate::anim::deform::{deformed_mesh, DeformedMesh};
#[cfg(doc)]
use crate::scene::pose::dynamic_nodes;
use crate::scene::pose::Pose;
use crate::scene::{Light, Material, Projection, SceneDesc};
use crate::settings::{LampSettings, Settings};

/// A mesh instance: one node that carries a mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlacedObject {
    pub node: usize,
    pub mesh: usize,
    pub to_render: Affine3A,
    /// Inverse transpose of `to_render`'s linear part, for normals.
    pub normal_to_render: Mat3,
    pub dynamic: bool,
}

/// Everything the integrators need of one frame's pose, in render space.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameScene {
    pub anchor: DVec3,
    pub objects: Vec<PlacedObject>,
    pub lights: Vec<RenderLight>,
    pub camera: RenderCamera,
    /// The scene's materials as the pose has them, indexed like
    /// `SceneDesc::materials`. Animating them changes shading only: which
    /// objects are dynamic depends on geometry alone.
    pub materials: Vec<Material>,
    /// True when the scene has no camera and one was made to frame it.
    pub automatic_camera: bool,
    /// Per object, its mesh as the pose deforms it (skins, morph targets),
    /// in object space; None for objects that do not deform.
    pub deformed: Vec<Option<Arc<DeformedMesh>>>,
}

/// World-space bounds of all meshes at a pose, in `f64`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneBounds {
    pub min: DVec3,
    pub max: DVec3,
}

impl SceneBounds {
    pub fn of(scene: &SceneDesc, pose: &Pose) -> Option<SceneBounds> {
        let mut bounds: Option<SceneBounds> = None;
        for (node, world) in scene.nodes.iter().zip(&pose.world) {
            let Some(mesh) = node.mesh.and_then(|mesh| scene.meshes.get(mesh)) else {
                continue;
            };
            for p in &mesh.positions {
                let p = world.transform_point3(p.as_dvec3());
                let b = bounds.get_or_insert(SceneBounds { min: p, max: p });
                b.min = b.min.min(p);
                b.max = b.max.max(p);
            }
        }
        bounds
    }

    pub fn centre(&self) -> DVec3 {
        0.5 * (self.min + self.max)
    }

    pub fn radius(&self) -> f64 {
        0.5 * (self.max - self.min).length()
    }
}

/// Which camera to render through.
#[derive(Clone, Copy, Debug)]
pub enum CameraChoice<'a> {
    First,
    Named(&'a str),
    /// A camera of no scene node: a camera path's pose at the frame's
    /// time, given by its world transform.
    Placed {
        world: DMat4,
        projection: Projection,
    },
}

impl CameraChoice<'_> {
    /// The camera `settings` ask for at `time` seconds: the camera path's
    /// pose where there is one, else the named camera or the first.
    pub fn for_frame(settings: &Settings, time: f64) -> CameraChoice<'_> {
        match (&settings.camera_path, &settings.camera) {
            (Some(path), _) => {
                let pose = path.pose_at(time);
                CameraChoice::Placed {
                    world: pose.world(),
                    projection: pose.projection(),
                }
            }
            (None, Some(name)) => CameraChoice::Named(name),
            (None, None) => CameraChoice::First,
        }
    }
}

#[derive(Debug, thiserror::Error)]
pub enum PlaceError {
    #[error("no camera named '{wanted}' (the scene has: {available})")]
    NoSuchCamera { wanted: String, available: String },
    /// A valid scene (glTF allows an empty one) that gives no picture:
    /// without geometry, no automatic camera can frame it.
    #[error("nothing to render: the scene has no geometry and no camera")]
    NothingToFrame,
}

impl FrameScene {
    /// The two-level world over every mesh instance of this placement,
    /// built once per sequence; later frames update it in place
    /// ([`FrameDelta::update_world`](crate::schedule::FrameDelta::update_world)).
    pub fn build_world(&self, scene: &SceneDesc) -> World {
        let objects: Vec<WorldObject> = (self.objects.iter())
            .map(|object| {
                let mesh = &scene.meshes[object.mesh];
                WorldObject {
                    positions: &mesh.positions,
                    triangles: &mesh.triangles,
                    to_render: object.to_render,
                    dynamic: object.dynamic,
                }
            })
            .collect();
        World::build(&objects)
    }

    /// Places `scene` at `pose` relative to `anchor`; `dynamic` says per
    /// node whether its object may move (see [`dynamic_nodes`], or a
    /// plan's narrower set over the frames it renders).
    pub fn place(
        scene: &SceneDesc,
        pose: &Pose,
        anchor: DVec3,
        camera: CameraChoice,
        lamps: &LampSettings,
        dynamic: &[bool],
    ) -> Result<FrameScene, PlaceError> {
        let relative = DMat4::from_translation(-anchor);
        let objects: Vec<PlacedObject> = scene
            .nodes
            .iter()
            .enumerate()
            .filter_map(|(index, node)| {
                let mesh = node.mesh?;
                let to_render = affine_f32(relative * pose.world[index]);
                Some(PlacedObject {
                    node: index,
                    mesh,
                    to_render,
                    normal_to_render: Mat3::from(to_render.matrix3).inverse().transpose(),
                    dynamic: dynamic[index],
                })
            })
            .collect();
        let lights = scene
            .nodes
            .iter()
            .enumerate()
            .filter_map(|(index, node)| {
                let light = pose.properties.lights.get(node.light?)?;
                Some(RenderLight::place(
                    light,
                    pose.world[index],
                    anchor,
                    lamp_radius(light, lamps),
                ))
            })
            .collect();
        let (camera, automatic_camera) = match place_camera(scene, pose, anchor, camera)? {
            Some(camera) => (camera, false),
            None => (framing_camera(scene, pose, anchor)?, true),
        };
        let deformed = objects
            .iter()
            .map(|object: &PlacedObject| {
                scene.nodes[object.node]
                    .deforms
                    .then(|| deformed_mesh(scene, pose, object.node).map(Arc::new))
                    .flatten()
            })
            .collect();
        Ok(FrameScene {
            anchor,
            objects,
            lights,
            camera,
            materials: pose.properties.materials.clone(),
            automatic_camera,
            deformed,
        })
    }
}

/// The lamp radius of a light: the settings file's entry for its name wins
/// (a user's explicit override), then the file's `extras.radius`, then the
/// settings' default, then an ideal point (0).
pub fn lamp_radius(light: &Light, lamps: &LampSettings) -> f32 {
    light
        .name
        .as_ref()
        .and_then(|name| lamps.radius.get(name).copied())
        .or(light.radius)
        .or(lamps.default_radius)
        .unwrap_or(0.0)
}

fn affine_f32(m: DMat4) -> Affine3A {
    Affine3A::from_mat4(m.as_mat4())
}

fn place_camera(
    scene: &SceneDesc,
    pose: &Pose,
    anchor: DVec3,
    choice: CameraChoice,
) -> Result<Option<RenderCamera>, PlaceError> {
    let name = match choice {
        CameraChoice::First => None,
        CameraChoice::Named(name) => Some(name),
        CameraChoice::Placed { world, projection } => {
            return Ok(Some(render_camera(world, projection, anchor)))
        }
    };
    let Some(node) = scene.camera_node(name) else {
        return match name {
            Some(wanted) => Err(PlaceError::NoSuchCamera {
                wanted: wanted.to_owned(),
                available: match scene.camera_names().join(", ") {
                    names if names.is_empty() => "no cameras".to_owned(),
                    names => names,
                },
            }),
            None => Ok(None),
        };
    };
    let projection = pose.properties.cameras[scene.nodes[node].camera.unwrap_or_default()];
    Ok(Some(render_camera(pose.world[node], projection, anchor)))
}

/// A camera whose node has the world transform `world`, in render space.
fn render_camera(world: DMat4, projection: Projection, anchor: DVec3) -> RenderCamera {
    let axis =
        |v: DVec3, fallback: DVec3| world.transform_vector3(v).normalize_or(fallback).as_vec3();
    RenderCamera {
        origin: (world.transform_point3(DVec3::ZERO) - anchor).as_vec3(),
        right: axis(DVec3::X, DVec3::X),
        up: axis(DVec3::Y, DVec3::Y),
        backward: axis(DVec3::Z, DVec3::Z),
        projection,
    }
}

/// A perspective camera that sees the whole scene from above and to the
/// front-right, for files that bring no camera.
fn framing_camera(
    scene: &SceneDesc,
    pose: &Pose,
    anchor: DVec3,
) -> Result<RenderCamera, PlaceError> {
    let bounds = SceneBounds::of(scene, pose).ok_or(PlaceError::NothingToFrame)?;
    let yfov = 45f32.to_radians();
    let radius = bounds.radius().max(1e-3);
    let distance = radius / (0.5 * yfov as f64).sin();
    let backward = Vec3::new(0.6, 0.45, 1.0).normalize();
    let target = (bounds.centre() - anchor).as_vec3();
    let right = Vec3::Y.cross(backward).normalize();
    Ok(RenderCamera {
        origin: target + backward * distance as f32,
        right,
        up: backward.cross(right),
        backward,
        projection: Projection::Perspective {
            yfov,
            aspect_ratio: None,
            znear: 0.01,
            zfar: None,
        },
    })
}
