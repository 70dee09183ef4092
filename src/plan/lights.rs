//! Each light's shadow class over the planned frames ([`Shadows`]), with
//! the reason a user reads in `lmanim plan`:
//!
//! - `none` when in no planned frame it sends anything to a surface a
//!   camera path can meet: no power, out of range, outside its spot cone,
//!   or behind every such surface (seen from the camera, every triangle in
//!   its reach has it on the far side);
//! - `unshadowed` when in every planned frame all geometry within its
//!   reach, visible or not, lies in one axis-aligned plane it stands off:
//!   no segment from it to a lit point can meet anything;
//! - else `hard` for an ideal point, `soft` for a lamp with a radius.

use serde::Serialize;

use super::reach::{self, Miss};
use super::view::{placed_positions, FrameView};
use super::{PlannedFrames, Shadows};
use crate::render::frame::FrameScene;
use crate::render::light::RenderLight;
use crate::scene::SceneDesc;

/// One light's part in the plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct LightPlan {
    /// Its index among the frame's lights (scene nodes in order).
    pub index: usize,
    pub name: Option<String>,
    pub shadows: Shadows,
    #[serde(serialize_with = "super::report::display")]
    pub reason: Reason,
}

/// Why a light got its class.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reason {
    NoPower,
    NothingInView,
    /// Every visible surface is out of its range, outside its cone, or
    /// has it behind; which of these tests were needed.
    OutOfReach {
        range: bool,
        cone: bool,
        behind: bool,
    },
    /// All geometry in its reach lies in the plane `axis = value`.
    OnlyPlaneInReach {
        axis: usize,
        value: f32,
    },
    NoLampRadius,
    LampRadius(f32),
}

impl std::fmt::Display for Reason {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match *self {
            Reason::NoPower => {
                f.write_str("no power (colour × intensity is 0) in every planned frame")
            }
            Reason::NothingInView => f.write_str("the camera sees no surface in any planned frame"),
            Reason::OutOfReach {
                range,
                cone,
                behind,
            } => {
                let why: Vec<&str> = [
                    (range, "out of its range"),
                    (cone, "outside its spot cone"),
                    (behind, "facing away from it"),
                ]
                .into_iter()
                .filter_map(|(holds, text)| holds.then_some(text))
                .collect();
                write!(f, "every surface in view is {}", why.join(" or "))
            }
            Reason::OnlyPlaneInReach { axis, value } => write!(
                f,
                "nothing but the plane {} = {value} (render space) lies within its reach",
                reach::axis_name(axis)
            ),
            Reason::NoLampRadius => f.write_str("no lamp radius: exact shadow rays"),
            Reason::LampRadius(radius) => write!(f, "lamp radius {radius} m: the light mesh"),
        }
    }
}

/// Every light's plan, from the planned frames and their views.
pub fn plan(scene: &SceneDesc, planned: &PlannedFrames, views: &[FrameView]) -> Vec<LightPlan> {
    let names: Vec<Option<String>> = (scene.nodes.iter())
        .filter_map(|node| scene.lights.get(node.light?))
        .map(|light| light.name.clone())
        .collect();
    let Some(first) = planned.placed.first() else {
        return Vec::new();
    };
    (0..first.lights.len())
        .map(|index| {
            let (shadows, reason) = classify(scene, planned, views, index);
            LightPlan {
                index,
                name: names.get(index).cloned().flatten(),
                shadows,
                reason,
            }
        })
        .collect()
}

/// What light `index` met over the planned frames.
#[derive(Default)]
struct Findings {
    powered: bool,
    lit: bool,
    saw_anything: bool,
    range: bool,
    cone: bool,
    behind: bool,
    occluders: Occluders,
}

/// What could stand between a light and what it lights, over the frames
/// seen so far.
#[derive(Clone, Copy, Default, PartialEq)]
enum Occluders {
    /// No geometry within its reach.
    #[default]
    Nothing,
    /// Only a plane it stands off (the first frame's).
    OnlyPlane(usize, f32),
    Possible,
}

impl Occluders {
    /// Over this frame and the ones before.
    fn and(self, frame: Occluders) -> Occluders {
        match (self, frame) {
            (Occluders::Possible, _) | (_, Occluders::Possible) => Occluders::Possible,
            (Occluders::Nothing, frame) => frame,
            (kept, _) => kept,
        }
    }
}

fn classify(
    scene: &SceneDesc,
    planned: &PlannedFrames,
    views: &[FrameView],
    index: usize,
) -> (Shadows, Reason) {
    let mut found = Findings::default();
    for (placed, view) in planned.placed.iter().zip(views) {
        let light = &placed.lights[index];
        if light.power.max_element() <= 0.0 {
            continue;
        }
        found.powered = true;
        if !found.lit {
            look_for_lit_surface(scene, placed, view, light, &mut found);
        }
        if found.occluders != Occluders::Possible {
            found.occluders = found.occluders.and(occluders_in_reach(view, light));
        }
    }
    let radius = first_lamp_radius(planned, index);
    match (found.lit, found.occluders) {
        (false, _) if !found.powered => (Shadows::None, Reason::NoPower),
        (false, _) if !found.saw_anything => (Shadows::None, Reason::NothingInView),
        (false, _) => (
            Shadows::None,
            Reason::OutOfReach {
                range: found.range,
                cone: found.cone,
                behind: found.behind,
            },
        ),
        (true, Occluders::OnlyPlane(axis, value)) => (
            Shadows::Unshadowed,
            Reason::OnlyPlaneInReach { axis, value },
        ),
        (true, _) if radius > 0.0 => (Shadows::Soft, Reason::LampRadius(radius)),
        (true, _) => (Shadows::Hard, Reason::NoLampRadius),
    }
}

fn first_lamp_radius(planned: &PlannedFrames, index: usize) -> f32 {
    planned
        .placed
        .first()
        .map_or(0.0, |p| p.lights[index].lamp_radius)
}

/// Looks in one frame for a visible surface `light` can send something
/// to, noting in `found` which tests ruled the others out.
fn look_for_lit_surface(
    scene: &SceneDesc,
    placed: &FrameScene,
    view: &FrameView,
    light: &RenderLight,
    found: &mut Findings,
) {
    for (object, bounds) in view.bounds.iter().enumerate() {
        let Some(bounds) = bounds.filter(|_| view.objects[object]) else {
            continue;
        };
        found.saw_anything = true;
        match reach::meets(light, &bounds) {
            Err(Miss::Range) => found.range = true,
            Err(Miss::Cone) => found.cone = true,
            Ok(()) => match view.eye {
                Some(eye) if all_behind(scene, placed, object, light, eye) => found.behind = true,
                _ => {
                    found.lit = true;
                    return;
                }
            },
        }
    }
}

/// Whether every triangle of `object` has `light` on its far side from
/// `eye`.
fn all_behind(
    scene: &SceneDesc,
    placed: &FrameScene,
    object: usize,
    light: &RenderLight,
    eye: glam::Vec3,
) -> bool {
    let positions = placed_positions(scene, placed, object);
    let triangles = &scene.meshes[placed.objects[object].mesh].triangles;
    (triangles.iter()).all(|t| reach::behind(light, eye, t.map(|i| positions[i as usize])))
}

/// What could stand between `light` and what it lights in one frame: only
/// an axis-aligned plane it stands off when all geometry in its reach
/// lies in it (from the objects' bounds: a box flat along an axis holds
/// points that share that coordinate exactly). Geometry the camera cannot
/// see counts too: it can cast shadows.
fn occluders_in_reach(view: &FrameView, light: &RenderLight) -> Occluders {
    let corners: Vec<glam::Vec3> = (view.bounds.iter().flatten())
        .filter(|bounds| reach::meets(light, bounds).is_ok())
        .flat_map(|bounds| [bounds.min, bounds.max])
        .collect();
    if corners.is_empty() {
        return Occluders::Nothing;
    }
    match reach::common_plane(&corners) {
        Some(plane) if reach::off_plane(light, plane) => Occluders::OnlyPlane(plane.0, plane.1),
        _ => Occluders::Possible,
    }
}
