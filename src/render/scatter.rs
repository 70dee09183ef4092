//! The Whitted recursion: the mirror-reflected and refracted rays a shading
//! point spawns, with the weights they carry. Only materials that call for
//! them spawn any (see `SurfaceMaterial::reflects` / `transmits`), so a
//! scene without mirrors or glass traces no secondary rays at all.

use glam::{Vec2, Vec3};

use super::brdf;
use super::material::SurfaceMaterial;
use super::surface::ShadingPoint;
use crate::accel::offset::offset_ray_origin;
use crate::accel::Ray;
use crate::scene::Material;

/// A ray continuing a camera path, and the throughput it carries.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SecondaryRay {
    pub ray: Ray,
    pub weight: Vec3,
}

/// Secondary rays of `point` (at most a reflection and a refraction).
pub fn secondary_rays(point: &ShadingPoint) -> impl Iterator<Item = SecondaryRay> {
    let m = &point.material;
    let n = point.shading_normal;
    let cos_view = n.dot(point.view).clamp(0.0, 1.0);
    let mirror = reflect(point.view, n);
    let reflected_origin = offset_ray_origin(point.position, point.geometric_normal);

    let mut reflection_weight = if m.reflects() {
        brdf::mirror_reflectance(m, cos_view)
    } else {
        Vec3::ZERO
    };
    let mut refraction = None;
    if m.transmits() {
        let eta = if point.front_face { 1.0 / m.ior } else { m.ior };
        let fresnel = dielectric_fresnel(cos_view, eta);
        let transmitted = m.base_color * (m.transmission * (1.0 - m.metallic));
        match refract(point.view, n, eta) {
            Some(direction) => {
                let origin = offset_ray_origin(point.position, -point.geometric_normal);
                refraction = Some(SecondaryRay {
                    ray: Ray::new(origin, direction, f32::INFINITY),
                    weight: point.weight * transmitted * (1.0 - fresnel),
                });
                if !m.reflects() {
                    reflection_weight += transmitted * fresnel;
                }
            }
            // Total internal reflection: all transmitted light reflects.
            None => reflection_weight += transmitted,
        }
    }
    let reflection = (reflection_weight.max_element() > 0.0).then(|| SecondaryRay {
        ray: Ray::new(reflected_origin, mirror, f32::INFINITY),
        weight: point.weight * reflection_weight,
    });
    reflection.into_iter().chain(refraction)
}

/// The most secondary rays one point of any of `materials` spawns (0, 1
/// or 2): whether a material reflects or transmits depends on its factors
/// alone, never on a texture, so a frame's materials bound each level of
/// its recursion before the level is made (the GPU sizes levels so).
pub fn most_secondary_rays<'m>(materials: impl IntoIterator<Item = &'m Material>) -> usize {
    let most = |material: &Material| {
        let material = SurfaceMaterial::at(material, &[], Vec2::ZERO);
        match (material.transmits(), material.reflects()) {
            (true, _) => 2,
            (false, reflects) => usize::from(reflects),
        }
    };
    materials.into_iter().map(most).max().unwrap_or(0)
}

/// Mirror direction of `v` (pointing away from the surface) about `n`.
fn reflect(v: Vec3, n: Vec3) -> Vec3 {
    2.0 * n.dot(v) * n - v
}

/// Refracted direction for `v` pointing away from the surface on the side
/// of `n`, with `eta` = n_incident / n_transmitted; None on total internal
/// reflection.
fn refract(v: Vec3, n: Vec3, eta: f32) -> Option<Vec3> {
    let cos_i = n.dot(v);
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    Some((-v * eta + n * (eta * cos_i - cos_t)).normalize())
}

/// Schlick's Fresnel for a dielectric interface, on the transmitted side's
/// cosine when leaving the denser medium (which is what keeps it right past
/// the critical angle).
fn dielectric_fresnel(cos_i: f32, eta: f32) -> f32 {
    let f0 = ((1.0 - eta) / (1.0 + eta)).powi(2);
    let cos = if eta > 1.0 {
        let sin2_t = eta * eta * (1.0 - cos_i * cos_i);
        if sin2_t >= 1.0 {
            return 1.0;
        }
        (1.0 - sin2_t).sqrt()
    } else {
        cos_i
    };
    f0 + (1.0 - f0) * brdf::schlick_weight(cos)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_frames_materials_bound_the_rays_a_point_spawns() {
        let matte = Material {
            metallic: 0.0,
            ..Material::default()
        };
        let mirror = Material {
            metallic: 1.0,
            roughness: 0.0,
            ..Material::default()
        };
        let glass = Material {
            metallic: 0.0,
            transmission: 1.0,
            ..Material::default()
        };
        assert_eq!(most_secondary_rays([&matte]), 0);
        assert_eq!(most_secondary_rays([&matte, &mirror]), 1);
        assert_eq!(most_secondary_rays([&mirror, &glass, &matte]), 2);
        assert_eq!(most_secondary_rays([]), 0);
    }

    #[test]
    fn reflection_mirrors_about_the_normal() {
        let v = Vec3::new(1.0, 1.0, 0.0).normalize();
        let r = reflect(v, Vec3::Y);
        assert!((r - Vec3::new(-1.0, 1.0, 0.0).normalize()).length() < 1e-6);
    }

    #[test]
    fn refraction_obeys_snell() {
        let v = Vec3::new(0.5f32.sin(), 0.5f32.cos(), 0.0);
        let eta = 1.0 / 1.5;
        let t = refract(v, Vec3::Y, eta).unwrap();
        assert!(t.y < 0.0);
        let sin_t = t.x.abs();
        assert!((sin_t - eta * 0.5f32.sin()).abs() < 1e-6);
        // Normal incidence passes straight through.
        assert!((refract(Vec3::Y, Vec3::Y, eta).unwrap() - Vec3::NEG_Y).length() < 1e-6);
    }

    #[test]
    fn grazing_exit_from_glass_is_totally_reflected() {
        let v = Vec3::new(0.9f32.sin(), 0.9f32.cos(), 0.0);
        assert!(refract(v, Vec3::Y, 1.5).is_none());
        assert_eq!(dielectric_fresnel(0.9f32.cos(), 1.5), 1.0);
    }

    #[test]
    fn fresnel_at_normal_incidence_is_f0() {
        let f = dielectric_fresnel(1.0, 1.0 / 1.5);
        assert!((f - 0.04).abs() < 1e-6);
    }
}
