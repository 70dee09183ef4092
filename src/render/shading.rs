//! Omega(i, P): what light i would reflect from P towards the viewer if it
//! were visible, and the shadow segment that decides V(i, P). Formula (1)
//! multiplies these by a 0/1 visibility; formula (2) by the share of visible
//! light-mesh nodes. Omega is always evaluated at P itself.

use glam::Vec3;

use super::light::{Incidence, RenderLight};
use super::surface::ShadingPoint;
use crate::accel::offset::offset_ray_origin;
use crate::accel::Ray;

impl ShadingPoint {
    /// The light arriving from light i and its cosine at P, or None when
    /// light i cannot reach P whatever the occluders (behind the surface,
    /// outside its cone or range).
    #[inline]
    pub fn reaching(&self, light: &RenderLight) -> Option<(Incidence, f32)> {
        let incidence = light.incidence(self.position)?;
        let l = incidence.direction;
        // A light below the geometric surface cannot reach it even where
        // the interpolated normal leans towards it.
        if self.geometric_normal.dot(l) <= 0.0 {
            return None;
        }
        let cos_theta = self.shading_normal.dot(l);
        (cos_theta > 0.0).then_some((incidence, cos_theta))
    }

    /// Omega(i, P), or None when light i brings nothing to P whatever the
    /// occluders.
    #[inline]
    pub fn omega(&self, light: &RenderLight) -> Option<Vec3> {
        let (incidence, cos_theta) = self.reaching(light)?;
        let reflectance = self.brdf().evaluate(incidence.direction);
        let value = reflectance * incidence.irradiance * cos_theta;
        (value.max_element() > 0.0).then_some(value)
    }

    /// The shadow segment from P to light i, its origin lifted off the
    /// surface on the lit side by the ULP offset.
    pub fn shadow_ray(&self, light: &RenderLight) -> Ray {
        light.shadow_ray(offset_ray_origin(self.position, self.geometric_normal))
    }

    /// Light emitted by the surface itself towards the viewer.
    pub fn emitted(&self) -> Vec3 {
        self.material.emissive
    }
}
