//! Lights placed in render space, and what one of them delivers to a surface
//! point: the direction to it, the irradiance it brings (before the cosine),
//! and the shadow segment that decides its visibility V(i, P).

use glam::{DMat4, DVec3, Vec3};

use crate::accel::Ray;
use crate::scene::{Light, LightKind};

/// Shadow segments stop this fraction short of the light, so a light placed
/// exactly on a surface (a lamp on a wall) is not shadowed by that surface.
/// It is relative to the segment's length, like the rounding error of the
/// hit distance it absorbs; it is not a distance in metres.
const SHADOW_SEGMENT_END: f32 = 1.0 - 1.0 / 65536.0;

/// A light in render space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RenderLight {
    pub source: LightSource,
    /// Colour × intensity: W/sr for point and spot lights, W/m² for
    /// directional ones.
    pub power: Vec3,
    pub range: Option<f32>,
    /// Radius of the physical lamp a point light stands for, in metres (0
    /// for an ideal point); the light-mesh methods size penumbrae from it.
    pub lamp_radius: f32,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum LightSource {
    Point {
        position: Vec3,
    },
    Spot {
        position: Vec3,
        /// Unit direction the spot shines along.
        axis: Vec3,
        cos_outer: f32,
        cos_inner: f32,
    },
    Directional {
        /// Unit direction from any surface point towards the light.
        towards: Vec3,
    },
}

/// What light `i` sends towards a point, visibility aside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Incidence {
    /// Unit direction from the point to the light.
    pub direction: Vec3,
    /// Irradiance on a surface facing the light (the cosine is applied by
    /// the shading).
    pub irradiance: Vec3,
}

impl RenderLight {
    /// Places `light` by its node's world transform, relative to `anchor`.
    /// `lamp_radius` is the resolved lamp size (extras, settings or 0).
    pub fn place(light: &Light, node_world: DMat4, anchor: DVec3, lamp_radius: f32) -> RenderLight {
        let position = (node_world.transform_point3(DVec3::ZERO) - anchor).as_vec3();
        let axis = node_world
            .transform_vector3(DVec3::NEG_Z)
            .normalize_or(DVec3::NEG_Z)
            .as_vec3();
        let source = match light.kind {
            LightKind::Point => LightSource::Point { position },
            LightKind::Spot {
                inner_cone,
                outer_cone,
            } => LightSource::Spot {
                position,
                axis,
                cos_outer: outer_cone.cos(),
                cos_inner: inner_cone.cos(),
            },
            LightKind::Directional => LightSource::Directional { towards: -axis },
        };
        RenderLight {
            source,
            power: light.color * light.intensity,
            range: light.range,
            lamp_radius,
        }
    }

    /// Position of a positional light, None for a directional one.
    pub fn position(&self) -> Option<Vec3> {
        match self.source {
            LightSource::Point { position } | LightSource::Spot { position, .. } => Some(position),
            LightSource::Directional { .. } => None,
        }
    }

    /// The light's contribution arriving at `p`, or None where it brings
    /// nothing (outside its range or cone, or at its very position).
    #[inline]
    pub fn incidence(&self, p: Vec3) -> Option<Incidence> {
        let (direction, irradiance) = match self.source {
            LightSource::Directional { towards } => (towards, self.power),
            LightSource::Point { position } => self.positional(position, p)?,
            LightSource::Spot {
                position,
                axis,
                cos_outer,
                cos_inner,
            } => {
                let (direction, irradiance) = self.positional(position, p)?;
                let cone = spot_attenuation(-direction.dot(axis), cos_outer, cos_inner);
                (direction, irradiance * cone)
            }
        };
        (irradiance.max_element() > 0.0).then_some(Incidence {
            direction,
            irradiance,
        })
    }

    /// Inverse-square falloff with glTF's recommended smooth range window.
    fn positional(&self, position: Vec3, p: Vec3) -> Option<(Vec3, Vec3)> {
        let to_light = position - p;
        let distance_squared = to_light.length_squared();
        if distance_squared.is_nan() || distance_squared <= 0.0 {
            return None;
        }
        let window = match self.range {
            Some(range) => {
                let ratio = distance_squared / (range * range);
                (1.0 - ratio * ratio).clamp(0.0, 1.0).powi(2)
            }
            None => 1.0,
        };
        let direction = to_light / distance_squared.sqrt();
        Some((direction, self.power * (window / distance_squared)))
    }

    /// The shadow segment from `origin` (already offset off its surface) to
    /// the light. Directional lights get an unbounded ray.
    pub fn shadow_ray(&self, origin: Vec3) -> Ray {
        match self.source {
            LightSource::Directional { towards } => Ray::new(origin, towards, f32::INFINITY),
            LightSource::Point { position } | LightSource::Spot { position, .. } => {
                segment_to_lamp(origin, position)
            }
        }
    }
}

/// The shadow segment from `origin` to `target`, a point of a lamp (its
/// centre, or another point of it), ending short of it as every shadow
/// segment does.
pub fn segment_to_lamp(origin: Vec3, target: Vec3) -> Ray {
    Ray::new(origin, target - origin, SHADOW_SEGMENT_END)
}

/// glTF's spot falloff: full inside the inner cone, nothing outside the
/// outer one, a squared smooth ramp between.
fn spot_attenuation(cos_angle: f32, cos_outer: f32, cos_inner: f32) -> f32 {
    if cos_inner <= cos_outer {
        return if cos_angle > cos_outer { 1.0 } else { 0.0 };
    }
    ((cos_angle - cos_outer) / (cos_inner - cos_outer))
        .clamp(0.0, 1.0)
        .powi(2)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn light(kind: LightKind, range: Option<f32>) -> Light {
        Light {
            name: None,
            kind,
            color: Vec3::new(1.0, 0.5, 0.25),
            intensity: 8.0,
            range,
            radius: None,
            group: None,
        }
    }

    #[test]
    fn point_light_falls_off_with_the_square_of_distance() {
        let placed = RenderLight::place(
            &light(LightKind::Point, None),
            DMat4::from_translation(DVec3::new(1e5, 2.0, 0.0)),
            DVec3::new(1e5, 0.0, 0.0),
            0.0,
        );
        let incidence = placed.incidence(Vec3::ZERO).unwrap();
        assert_eq!(incidence.direction, Vec3::Y);
        assert_eq!(incidence.irradiance, Vec3::new(2.0, 1.0, 0.5));
        assert!(placed.incidence(Vec3::new(0.0, 2.0, 0.0)).is_none());
    }

    #[test]
    fn range_window_reaches_zero_at_the_range() {
        let placed = RenderLight::place(
            &light(LightKind::Point, Some(4.0)),
            DMat4::IDENTITY,
            DVec3::ZERO,
            0.0,
        );
        assert!(placed.incidence(Vec3::new(4.0, 0.0, 0.0)).is_none());
        let near = placed.incidence(Vec3::new(1.0, 0.0, 0.0)).unwrap();
        let expected = (1.0f32 - (1.0f32 / 16.0).powi(2)).powi(2) * 8.0;
        assert!((near.irradiance.x - expected).abs() < 1e-6);
    }

    #[test]
    fn spot_cone_cuts_off_outside_the_outer_angle() {
        let spot = light(
            LightKind::Spot {
                inner_cone: 0.2,
                outer_cone: 0.4,
            },
            None,
        );
        // The node's −Z points down −Z: the spot shines along −Z.
        let placed = RenderLight::place(&spot, DMat4::IDENTITY, DVec3::ZERO, 0.0);
        let on_axis = Vec3::new(0.0, 0.0, -1.0);
        let inside = Vec3::new(0.0, (0.19f32).tan(), -1.0);
        let outside = Vec3::new(0.0, (0.41f32).tan(), -1.0);
        let between = Vec3::new(0.0, (0.3f32).tan(), -1.0);
        assert!(placed.incidence(on_axis).is_some());
        let full = placed.incidence(inside).unwrap().irradiance.x * inside.length_squared();
        assert!((full - 8.0).abs() < 1e-4, "{full}");
        assert!(placed.incidence(outside).is_none());
        let partial = placed.incidence(between).unwrap().irradiance.x * between.length_squared();
        assert!(partial > 0.0 && partial < 8.0);
    }

    #[test]
    fn directional_light_comes_from_minus_its_axis() {
        let placed = RenderLight::place(
            &light(LightKind::Directional, None),
            DMat4::from_rotation_x(-std::f64::consts::FRAC_PI_2),
            DVec3::ZERO,
            0.0,
        );
        let incidence = placed.incidence(Vec3::new(3.0, 0.0, 7.0)).unwrap();
        assert!((incidence.direction - Vec3::Y).length() < 1e-6);
        assert_eq!(incidence.irradiance, Vec3::new(8.0, 4.0, 2.0));
        let ray = placed.shadow_ray(Vec3::ZERO);
        assert_eq!(ray.t_max, f32::INFINITY);
    }
}
