//! What the camera can see in each planned frame, conservatively: the
//! objects whose bounds meet a cone around its view that holds the whole
//! image. Where a visible surface may spawn secondary rays (a mirror,
//! glass), camera paths can reach anything from any side, so every object
//! counts as visible in that frame.

use glam::Vec3;

use super::materials::{mesh_materials, spawns};
use super::PlannedFrames;
use crate::render::frame::FrameScene;
use crate::scene::{Projection, SceneDesc};
use crate::settings::Settings;

/// Added to the view cone's half angle, in radians: far more than the
/// rounding of any camera ray's direction.
const CONE_MARGIN: f64 = 1e-3;

/// An axis-aligned box in render space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: Vec3,
    pub max: Vec3,
}

impl Bounds {
    fn of(points: &[Vec3]) -> Option<Bounds> {
        let first = *points.first()?;
        let start = Bounds {
            min: first,
            max: first,
        };
        Some(points.iter().fold(start, |b, &p| Bounds {
            min: b.min.min(p),
            max: b.max.max(p),
        }))
    }

    pub fn centre(&self) -> glam::DVec3 {
        0.5 * (self.min.as_dvec3() + self.max.as_dvec3())
    }

    pub fn radius(&self) -> f64 {
        0.5 * (self.max.as_dvec3() - self.min.as_dvec3()).length()
    }
}

/// One planned frame as the camera sees it.
pub struct FrameView {
    /// Per object of the frame: whether a camera path may meet it.
    pub objects: Vec<bool>,
    /// Per object: its render-space bounds (None for an empty mesh).
    pub bounds: Vec<Option<Bounds>>,
    /// Where every camera path starts, when all of them do from one point
    /// (a perspective camera and no secondary rays): then a point is seen
    /// only from that side of its triangle. None otherwise.
    pub eye: Option<Vec3>,
}

/// The vertices of object `index` of `placed` in render space, as
/// shading places them (deformed where the frame deforms it).
pub fn placed_positions(scene: &SceneDesc, placed: &FrameScene, index: usize) -> Vec<Vec3> {
    let object = &placed.objects[index];
    let deformed = placed.deformed[index].as_deref();
    let positions = deformed.map_or(&scene.meshes[object.mesh].positions, |d| &d.positions);
    (positions.iter())
        .map(|&p| object.to_render.transform_point3(p))
        .collect()
}

/// Every planned frame's view.
pub fn views(scene: &SceneDesc, planned: &PlannedFrames, settings: &Settings) -> Vec<FrameView> {
    let mut previous: Option<(&FrameScene, Vec<Option<Bounds>>)> = None;
    let mut views = Vec::with_capacity(planned.placed.len());
    for placed in planned.placed {
        let bounds: Vec<Option<Bounds>> = (0..placed.objects.len())
            .map(|index| match &previous {
                Some((before, bounds))
                    if before.objects[index] == placed.objects[index]
                        && before.deformed[index] == placed.deformed[index] =>
                {
                    bounds[index]
                }
                _ => Bounds::of(&placed_positions(scene, placed, index)),
            })
            .collect();
        let in_view: Vec<bool> = (bounds.iter())
            .map(|b| b.is_some_and(|b| in_view_cone(placed, settings, &b)))
            .collect();
        let secondary = (placed.objects.iter().zip(&in_view))
            .filter(|(_, &seen)| seen)
            .flat_map(|(object, _)| mesh_materials(scene, object.mesh))
            .any(|material| {
                placed.materials.get(material).is_some_and(|m| {
                    let (reflects, transmits) = spawns(m);
                    reflects || transmits
                })
            });
        let (objects, eye) = match (secondary, placed.camera.projection) {
            (true, _) => (vec![true; in_view.len()], None),
            (false, Projection::Perspective { .. }) => (in_view, Some(placed.camera.origin)),
            (false, Projection::Orthographic { .. }) => (in_view, None),
        };
        views.push(FrameView {
            objects,
            bounds: bounds.clone(),
            eye,
        });
        previous = Some((placed, bounds));
    }
    views
}

/// Whether `bounds` meet the cone from the camera that holds every
/// primary ray of the image (an orthographic camera's rays are parallel:
/// everything counts).
fn in_view_cone(placed: &FrameScene, settings: &Settings, bounds: &Bounds) -> bool {
    let camera = &placed.camera;
    let Projection::Perspective { yfov, .. } = camera.projection else {
        return true;
    };
    // The camera keeps the vertical field of view and follows the image's
    // aspect (`RenderCamera::film`).
    let aspect = f64::from(settings.width) / f64::from(settings.height);
    let tan_half = (0.5 * f64::from(yfov)).tan();
    let half_angle = (tan_half * (1.0 + aspect * aspect).sqrt()).atan() + CONE_MARGIN;
    if half_angle >= std::f64::consts::FRAC_PI_2 {
        return true;
    }
    sphere_meets_cone(
        camera.origin.as_dvec3(),
        -camera.backward.as_dvec3(),
        half_angle,
        bounds.centre(),
        bounds.radius(),
    )
}

/// Whether the ball (`centre`, `radius`) meets the cone from `apex` along
/// unit `axis` with `half_angle` below π/2.
pub fn sphere_meets_cone(
    apex: glam::DVec3,
    axis: glam::DVec3,
    half_angle: f64,
    centre: glam::DVec3,
    radius: f64,
) -> bool {
    let to_centre = centre - apex;
    let distance = to_centre.length();
    if distance <= radius {
        return true;
    }
    let angle = (to_centre.dot(axis) / distance).clamp(-1.0, 1.0).acos();
    angle - (radius / distance).asin() <= half_angle
}
