//! Geometric tests of what a light can reach: its range ball, its spot
//! cone, and the side of a surface it stands on. Each pads its bounds
//! (by the lamp's radius, whose sampled points the `area` method lights
//! from, and by margins far above rounding), so it answers "cannot reach"
//! only where the renderer's own arithmetic surely gives nothing.

use glam::Vec3;

use super::view::{sphere_meets_cone, Bounds};
use crate::render::light::{LightSource, RenderLight};

/// Relative padding of a light's range, and added to the spot cone's half
/// angle (radians).
const RANGE_MARGIN: f64 = 1e-3;
const CONE_MARGIN: f64 = 1e-3;
/// How far (metres, in render space) a light must stand from a
/// triangle's plane to count as on one side of it, beyond its lamp.
const PLANE_MARGIN: f64 = 1e-3;
/// Smallest |n · towards| for a directional light to count as on one side.
const DIRECTION_MARGIN: f64 = 1e-4;

/// Why a light cannot reach a box.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Miss {
    Range,
    Cone,
}

/// Whether `light` can send anything into `bounds`.
pub fn meets(light: &RenderLight, bounds: &Bounds) -> Result<(), Miss> {
    let Some(position) = light.position() else {
        return Ok(());
    };
    let position = position.as_dvec3();
    let lamp = f64::from(light.lamp_radius);
    let (centre, radius) = (bounds.centre(), bounds.radius());
    if let Some(range) = light.range {
        let reach = f64::from(range) * (1.0 + RANGE_MARGIN) + lamp;
        if (centre - position).length() > reach + radius {
            return Err(Miss::Range);
        }
    }
    if let LightSource::Spot {
        axis, cos_outer, ..
    } = light.source
    {
        let half_angle = f64::from(cos_outer).clamp(-1.0, 1.0).acos() + CONE_MARGIN;
        if half_angle < std::f64::consts::FRAC_PI_2 {
            // A cone holding the cones of every point of the lamp: its
            // apex moved back along the axis until the lamp fits inside.
            let axis = axis.as_dvec3().normalize();
            let apex = position - axis * (lamp / half_angle.sin());
            if !sphere_meets_cone(apex, axis, half_angle, centre, radius) {
                return Err(Miss::Cone);
            }
        }
    }
    Ok(())
}

/// Whether `light` stands, with all of its lamp, on the other side of
/// `triangle`'s plane from `eye`: a point seen from `eye` then has its
/// light behind its geometric normal, which Omega lets through as nothing.
/// Degenerate triangles and lights near the plane answer false.
pub fn behind(light: &RenderLight, eye: Vec3, triangle: [Vec3; 3]) -> bool {
    let [a, b, c] = triangle.map(|p| p.as_dvec3());
    let normal = (b - a).cross(c - a);
    let length = normal.length();
    if length == 0.0 || !length.is_finite() {
        return false;
    }
    let normal = normal / length;
    let eye_side = normal.dot(eye.as_dvec3() - a);
    if eye_side.abs() <= PLANE_MARGIN {
        return false;
    }
    let light_side = match light.source {
        LightSource::Directional { towards } => {
            let side = normal.dot(towards.as_dvec3());
            if side.abs() <= DIRECTION_MARGIN {
                return false;
            }
            side
        }
        LightSource::Point { position } | LightSource::Spot { position, .. } => {
            let side = normal.dot(position.as_dvec3() - a);
            if side.abs() <= PLANE_MARGIN + f64::from(light.lamp_radius) {
                return false;
            }
            side
        }
    };
    eye_side.signum() != light_side.signum()
}

/// The axis-aligned plane every one of `points` lies in exactly, as
/// (axis, coordinate), if there is one.
pub fn common_plane(points: &[Vec3]) -> Option<(usize, f32)> {
    let first = *points.first()?;
    (0..3).find_map(|axis| {
        let value = first[axis];
        (points.iter())
            .all(|p| p[axis] == value)
            .then_some((axis, value))
    })
}

/// Whether `light` stands off the plane `axis = value`, with all of its
/// lamp: then no segment from it to a point of the plane meets the plane
/// before its end.
pub fn off_plane(light: &RenderLight, (axis, value): (usize, f32)) -> bool {
    match light.source {
        LightSource::Directional { towards } => f64::from(towards[axis]).abs() > DIRECTION_MARGIN,
        LightSource::Point { position } | LightSource::Spot { position, .. } => {
            let distance = (f64::from(position[axis]) - f64::from(value)).abs();
            distance > PLANE_MARGIN + f64::from(light.lamp_radius)
        }
    }
}

/// The name of coordinate `axis`, for reports.
pub fn axis_name(axis: usize) -> char {
    ['x', 'y', 'z'][axis.min(2)]
}
