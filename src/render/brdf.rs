//! The glTF metallic-roughness BRDF (the glTF 2.0 specification, appendix B):
//! Lambert diffuse plus GGX specular with height-correlated Smith
//! visibility, mixed by Schlick's Fresnel. It is the reflectance inside
//! Omega(i, P) of the paper's formulas (1) and (2).

use std::f32::consts::PI;

use glam::Vec3;
use wide::f32x8;

use super::lanes::{dot, each3, splat3, Lanes3};
use super::material::SurfaceMaterial;

/// Schlick's approximation of the Fresnel weight `(1 − cos)^5`.
pub fn schlick_weight(cos_theta: f32) -> f32 {
    (1.0 - cos_theta.clamp(0.0, 1.0)).powi(5)
}

/// The BRDF f(v, l) for unit normal `n`, unit view direction `v` and unit
/// light direction `l`, all pointing away from the surface. Zero when
/// either direction is below the surface. The part of the diffuse lobe that
/// is transmitted (KHR_materials_transmission) is left to the refracted ray.
pub fn evaluate(material: &SurfaceMaterial, n: Vec3, v: Vec3, l: Vec3) -> Vec3 {
    PointBrdf::new(material, n, v).evaluate(l)
}

/// The BRDF at one shading point, with everything that does not depend on
/// the light computed once: formulas (1) and (2) evaluate it for every
/// light that reaches the point, dozens in a street of lamps. The GPU's
/// direct-light pass uploads its fields and evaluates it there.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PointBrdf {
    pub(crate) n: Vec3,
    pub(crate) v: Vec3,
    pub(crate) n_dot_v: f32,
    /// α² of the GGX lobe (α = roughness²).
    pub(crate) alpha2: f32,
    /// The view half of the height-correlated Smith term,
    /// `sqrt((n·v)² (1 − α²) + α²)`.
    pub(crate) view_smith: f32,
    /// Lambert's lobe, less what transmission takes.
    pub(crate) diffuse: Vec3,
    pub(crate) base_color: Vec3,
    pub(crate) metallic: f32,
    pub(crate) specular: f32,
    pub(crate) dielectric_f0: f32,
}

impl PointBrdf {
    pub fn new(material: &SurfaceMaterial, n: Vec3, v: Vec3) -> PointBrdf {
        let n_dot_v = n.dot(v);
        let roughness = material.highlight_roughness();
        let alpha = roughness * roughness;
        let alpha2 = alpha * alpha;
        PointBrdf {
            n,
            v,
            n_dot_v,
            alpha2,
            view_smith: (n_dot_v * n_dot_v * (1.0 - alpha2) + alpha2).sqrt(),
            diffuse: material.base_color / PI * (1.0 - material.transmission),
            base_color: material.base_color,
            metallic: material.metallic,
            specular: material.specular,
            dielectric_f0: 0.04 * material.specular,
        }
    }

    /// f(v, l) for the unit light direction `l`.
    #[inline]
    pub fn evaluate(&self, l: Vec3) -> Vec3 {
        let n_dot_l = self.n.dot(l);
        if n_dot_l <= 0.0 || self.n_dot_v <= 0.0 {
            return Vec3::ZERO;
        }
        let h = (self.v + l).normalize_or_zero();
        if h == Vec3::ZERO {
            return Vec3::ZERO;
        }
        let n_dot_h = self.n.dot(h).max(0.0);
        let v_dot_h = self.v.dot(h).max(0.0);

        let specular = ggx_distribution(n_dot_h, self.alpha2) * self.smith_visibility(n_dot_l);
        let fresnel = schlick_weight(v_dot_h);
        let dielectric_fresnel =
            self.dielectric_f0 + (self.specular - self.dielectric_f0) * fresnel;
        let dielectric =
            self.diffuse * (1.0 - dielectric_fresnel) + Vec3::splat(specular * dielectric_fresnel);
        if self.metallic == 0.0 {
            return dielectric;
        }
        let metal = specular * (self.base_color + (Vec3::ONE - self.base_color) * fresnel);
        dielectric.lerp(metal, self.metallic)
    }

    /// f(v, l) for eight unit light directions at once: the arithmetic of
    /// [`PointBrdf::evaluate`], lane by lane.
    #[inline]
    pub fn evaluate_lanes(&self, l: Lanes3) -> Lanes3 {
        let zero = f32x8::splat(0.0);
        let one = f32x8::splat(1.0);
        if self.n_dot_v <= 0.0 {
            return [zero; 3];
        }
        let (n, v) = (splat3(self.n), splat3(self.v));
        let n_dot_l = dot(n, l);
        let half = each3(|axis| v[axis] + l[axis]);
        let half_recip = one / dot(half, half).sqrt();
        // `normalize_or_zero`: a half vector of no length reflects nothing.
        let has_half = half_recip.simd_lt(f32x8::splat(f32::INFINITY)) & half_recip.simd_gt(zero);
        let h = each3(|axis| half[axis] * half_recip);
        let n_dot_h = dot(n, h).max(zero);
        let v_dot_h = dot(v, h).max(zero).min(one);

        let alpha2 = f32x8::splat(self.alpha2);
        let denominator = n_dot_h * n_dot_h * (alpha2 - one) + one;
        let distribution = alpha2 / (f32x8::splat(PI) * denominator * denominator);
        let ggx_v = n_dot_l * f32x8::splat(self.view_smith);
        let ggx_l =
            f32x8::splat(self.n_dot_v) * (n_dot_l * n_dot_l * (one - alpha2) + alpha2).sqrt();
        let sum = ggx_v + ggx_l;
        let visibility = sum.simd_gt(zero).select(f32x8::splat(0.5) / sum, zero);
        let specular = distribution * visibility;
        let complement = one - v_dot_h;
        let squared = complement * complement;
        let fresnel = squared * squared * complement;

        let f0 = f32x8::splat(self.dielectric_f0);
        let dielectric_fresnel = f0 + (f32x8::splat(self.specular) - f0) * fresnel;
        let reflects = n_dot_l.simd_gt(zero) & has_half;
        each3(|channel| {
            let dielectric = f32x8::splat(self.diffuse[channel]) * (one - dielectric_fresnel)
                + specular * dielectric_fresnel;
            let value = if self.metallic == 0.0 {
                dielectric
            } else {
                let base = f32x8::splat(self.base_color[channel]);
                let metal = specular * (base + (one - base) * fresnel);
                dielectric + (metal - dielectric) * f32x8::splat(self.metallic)
            };
            reflects.select(value, zero)
        })
    }

    /// Height-correlated Smith G divided by 4 |n·l| |n·v|, as the spec
    /// writes it.
    fn smith_visibility(&self, n_dot_l: f32) -> f32 {
        let alpha2 = self.alpha2;
        let ggx_v = n_dot_l * self.view_smith;
        let ggx_l = self.n_dot_v * (n_dot_l * n_dot_l * (1.0 - alpha2) + alpha2).sqrt();
        let sum = ggx_v + ggx_l;
        if sum > 0.0 {
            0.5 / sum
        } else {
            0.0
        }
    }
}

/// Fresnel reflectance of a mirror reflection seen at `cos_theta`, the
/// weight of the Whitted reflected ray (same mix as [`evaluate`]).
pub fn mirror_reflectance(material: &SurfaceMaterial, cos_theta: f32) -> Vec3 {
    let fresnel = schlick_weight(cos_theta);
    let dielectric_f0 = 0.04 * material.specular;
    let dielectric = dielectric_f0 + (material.specular - dielectric_f0) * fresnel;
    let metal = material.base_color + (Vec3::ONE - material.base_color) * fresnel;
    Vec3::splat(dielectric).lerp(metal, material.metallic)
}

fn ggx_distribution(n_dot_h: f32, alpha2: f32) -> f32 {
    let denominator = n_dot_h * n_dot_h * (alpha2 - 1.0) + 1.0;
    alpha2 / (PI * denominator * denominator)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn material(metallic: f32, roughness: f32, specular: f32) -> SurfaceMaterial {
        SurfaceMaterial {
            base_color: Vec3::new(0.8, 0.6, 0.4),
            metallic,
            roughness,
            specular,
            transmission: 0.0,
            ior: 1.5,
            emissive: Vec3::ZERO,
        }
    }

    #[test]
    fn specular_weight_zero_is_exactly_lambert() {
        let m = material(0.0, 0.5, 0.0);
        let l = Vec3::new(0.3, 0.8, 0.1).normalize();
        let f = evaluate(&m, Vec3::Y, Vec3::new(-0.2, 0.9, 0.3).normalize(), l);
        assert_eq!(f, m.base_color / PI);
    }

    #[test]
    fn below_the_horizon_reflects_nothing() {
        let m = material(0.0, 0.5, 1.0);
        assert_eq!(
            evaluate(&m, Vec3::Y, Vec3::Y, Vec3::new(1.0, -0.01, 0.0).normalize()),
            Vec3::ZERO
        );
        assert_eq!(evaluate(&m, Vec3::Y, Vec3::NEG_Y, Vec3::Y), Vec3::ZERO);
    }

    /// A white furnace: the directional albedo of a rough white dielectric
    /// stays at about 1 or below. The spec's fresnel-mix weights the diffuse
    /// lobe by (1 − F(v·h)) per light direction, which conserves energy only
    /// approximately: to about a percent up to 60° from the normal (tested
    /// here), with a gain of about 7% at 85° (measured, the model's own).
    #[test]
    fn brdf_does_not_create_energy() {
        let mut m = material(0.0, 0.6, 1.0);
        m.base_color = Vec3::ONE;
        for view_degrees in [0.0f32, 30.0, 60.0] {
            let v = Vec3::new(
                view_degrees.to_radians().sin(),
                view_degrees.to_radians().cos(),
                0.0,
            );
            let steps = 256;
            let mut albedo = 0.0;
            for i in 0..steps {
                for j in 0..steps {
                    let cos_theta = (i as f32 + 0.5) / steps as f32;
                    let phi = 2.0 * PI * (j as f32 + 0.5) / steps as f32;
                    let sin_theta = (1.0 - cos_theta * cos_theta).sqrt();
                    let l = Vec3::new(sin_theta * phi.cos(), cos_theta, sin_theta * phi.sin());
                    albedo += evaluate(&m, Vec3::Y, v, l).x * cos_theta;
                }
            }
            albedo *= 2.0 * PI / (steps * steps) as f32;
            assert!(
                albedo <= 1.01 && albedo > 0.8,
                "albedo {albedo} at {view_degrees}°"
            );
        }
    }

    #[test]
    fn metal_mirror_reflectance_is_its_colour_at_normal_incidence() {
        let m = material(1.0, 0.0, 1.0);
        assert_eq!(mirror_reflectance(&m, 1.0), m.base_color);
        let grazing = mirror_reflectance(&m, 0.0);
        assert!((grazing - Vec3::ONE).abs().max_element() < 1e-6);
    }

    #[test]
    fn perfect_mirror_highlight_is_finite() {
        let m = material(1.0, 0.0, 1.0);
        let f = evaluate(&m, Vec3::Y, Vec3::Y, Vec3::Y);
        assert!(f.is_finite() && f.x > 0.0);
    }
}
