//! The soft-shadow reference (`--method area`): every point or spot light
//! with a lamp radius R > 0 is shaded as the spherical lamp it stands for,
//! by Monte Carlo sampling of the cone of directions the sphere subtends
//! from P, one sample per pixel sample, each with its own shadow segment.
//! It runs in the shade stage in place of formula (1), on the same shading
//! points; the light-mesh methods imitate the penumbrae it computes.
//!
//! The lamp has the light's power spread over its sphere: uniform radiance
//! L = I / (π R²) per colour channel, so that far away it delivers the point
//! light's I / d². Choices where the physics leaves some freedom:
//! - the spot cone and the range window are evaluated once, from the lamp's
//!   centre, and scale the whole lamp (a spot is a lamp behind a shade);
//! - a point inside a lamp's sphere (d ≤ R), where the cone is undefined,
//!   sees that light as the point light, exactly as Whitted would;
//! - lights with R = 0 and directional lights are Whitted's: one shadow ray;
//! - the shadow segment ends on the sphere, so geometry cutting into the
//!   lamp hides the part of it that lies behind that geometry.

use std::f32::consts::TAU;

use glam::{Vec2, Vec3};

use super::light::RenderLight;
use super::light_terms::LightTerms;
use super::shadow_split::ShadowSplit;
use super::surface::ShadingPoint;
use crate::accel::offset::offset_ray_origin;
use crate::accel::{Ray, World};
use crate::stats::ClassRays;

/// Direct light at `point` from every light, spherical lamps sampled once
/// each, light by light into `terms`; `lamp_sample(i)` is the point of the
/// unit square that light `i`'s sample comes from (stratified over the
/// pixel's samples by the backend). Returns the shadow rays it traced,
/// by the class `shadows` gives their light.
pub fn direct_light(
    point: &ShadingPoint,
    lights: &[RenderLight],
    world: &World,
    lamp_sample: impl Fn(u32) -> Vec2,
    shadows: &ShadowSplit,
    terms: &mut impl LightTerms,
) -> ClassRays {
    let mut shadow_rays = ClassRays::default();
    light_samples(point, lights, lamp_sample, |light, sample| {
        shadow_rays.add(shadows.class(light, lights));
        if !world.occluded(&sample.shadow_ray) {
            terms.add(light, sample.value);
        }
    });
    shadow_rays
}

/// The samples [`direct_light`] weighs, visibility aside, in light order,
/// each with its light's index: one per light whose sample can bring
/// anything. A backend that traces the shadow rays elsewhere sums the
/// visible values in this order.
pub fn light_samples(
    point: &ShadingPoint,
    lights: &[RenderLight],
    lamp_sample: impl Fn(u32) -> Vec2,
    mut each: impl FnMut(usize, LightSample),
) {
    for (index, light) in lights.iter().enumerate() {
        if let Some(sample) = sample_light(point, light, lamp_sample(index as u32)) {
            each(index, sample);
        }
    }
}

/// One sample of a light's contribution at a point, visibility aside.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightSample {
    /// The unoccluded estimate: f · L · cos / pdf for a lamp, Omega for a
    /// point or directional light.
    pub value: Vec3,
    /// The segment that decides whether `value` counts.
    pub shadow_ray: Ray,
}

/// The estimate of light `light` at `point` from the unit-square sample `u`,
/// or None when this sample brings nothing whatever the occluders (no
/// shadow ray is needed then).
pub fn sample_light(point: &ShadingPoint, light: &RenderLight, u: Vec2) -> Option<LightSample> {
    let as_point_light = || {
        Some(LightSample {
            value: point.omega(light)?,
            shadow_ray: point.shadow_ray(light),
        })
    };
    let radius = light.lamp_radius;
    let Some(centre) = light.position().filter(|_| radius > 0.0) else {
        return as_point_light();
    };
    let to_centre = centre - point.position;
    let distance = to_centre.length();
    if distance.is_nan() || distance <= radius {
        return as_point_light();
    }
    let Some(cone) = Cone::subtended(to_centre / distance, radius / distance) else {
        return as_point_light();
    };
    // Irradiance from the centre carries I, the spot cone and the range
    // window, divided by d²; the lamp's radiance is that times d² / (π R²).
    let incidence = light.incidence(point.position)?;
    let (direction, one_minus_cos) = cone.sample(u);
    if point.geometric_normal.dot(direction) <= 0.0 {
        return None;
    }
    let cos_surface = point.shading_normal.dot(direction);
    if cos_surface <= 0.0 {
        return None;
    }
    let reflectance = point.brdf().evaluate(direction);
    // f · L · cos / pdf with L = E d² / (π R²) and 1/pdf = 2π (1 − cos θmax):
    // since 1 − cos θmax = (R²/d²) / (1 + cos θmax), the radii cancel and
    // the weight is 2 / (1 + cos θmax), which tends to 1 (the point light)
    // as R → 0 and stays finite at any size.
    let weight = 2.0 / (1.0 + cone.cos_max);
    let value = reflectance * incidence.irradiance * (cos_surface * weight);
    (value.max_element() > 0.0).then(|| {
        let lamp_point =
            point.position + direction * cone.distance_to_sphere(distance, one_minus_cos);
        let origin = offset_ray_origin(point.position, point.geometric_normal);
        LightSample {
            value,
            shadow_ray: Ray::segment(origin, lamp_point),
        }
    })
}

/// The cone of directions in which a sphere is seen from a point outside it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cone {
    /// Unit direction to the sphere's centre.
    pub axis: Vec3,
    /// cos θmax = sqrt(1 − R²/d²).
    pub cos_max: f32,
    /// 1 − cos θmax, computed without cancellation for small lamps.
    pub one_minus_cos_max: f32,
    /// sin² θmax = R²/d².
    pub sin2_max: f32,
}

impl Cone {
    /// The cone a sphere of radius `R = sin_max · d` subtends around unit
    /// `axis`; None when it is too narrow to sample in f32 (the point light
    /// is then exact to rounding) or not a cone at all (`sin_max` ≥ 1).
    pub fn subtended(axis: Vec3, sin_max: f32) -> Option<Cone> {
        let sin2_max = sin_max * sin_max;
        if sin2_max.is_nan() || sin2_max >= 1.0 {
            return None;
        }
        let cos_max = (1.0 - sin2_max).sqrt();
        let one_minus_cos_max = sin2_max / (1.0 + cos_max);
        (one_minus_cos_max > 0.0).then_some(Cone {
            axis,
            cos_max,
            one_minus_cos_max,
            sin2_max,
        })
    }

    /// Density of [`Cone::sample`] per unit solid angle: uniform over the
    /// cone's 2π (1 − cos θmax) steradians.
    pub fn pdf(&self) -> f32 {
        1.0 / (TAU * self.one_minus_cos_max)
    }

    /// A direction uniform in the cone from `u` in [0, 1)², with 1 − cos θ
    /// to the axis (kept apart from cos θ, which rounds to 1 in narrow
    /// cones): u.x picks cos θ in (cos θmax, 1], u.y the azimuth, so strata
    /// of the square are strata of the cone.
    pub fn sample(&self, u: Vec2) -> (Vec3, f32) {
        let one_minus_cos = u.x * self.one_minus_cos_max;
        let cos_theta = 1.0 - one_minus_cos;
        // sin² θ = (1 − cos)(1 + cos), exact for tiny cones.
        let sin_theta = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0).sqrt();
        let phi = TAU * u.y;
        let (tangent, bitangent) = self.axis.any_orthonormal_pair();
        let direction = (tangent * (sin_theta * phi.cos()) + bitangent * (sin_theta * phi.sin()))
            + self.axis * cos_theta;
        (direction.normalize_or(self.axis), one_minus_cos)
    }

    /// Distance from the cone's apex, along a direction with
    /// `one_minus_cos` = 1 − cos θ to the axis, to the near side of the
    /// sphere whose centre is `distance` away: d cos θ − sqrt(R² − d² sin² θ),
    /// with the root clamped at the rim where rounding can make it negative.
    pub fn distance_to_sphere(&self, distance: f32, one_minus_cos: f32) -> f32 {
        let cos_theta = 1.0 - one_minus_cos;
        let sin2_theta = (one_minus_cos * (2.0 - one_minus_cos)).max(0.0);
        let chord = (self.sin2_max - sin2_theta).max(0.0).sqrt();
        (distance * (cos_theta - chord)).max(0.0)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::light::LightSource;

    fn lamp(position: Vec3, radius: f32) -> RenderLight {
        RenderLight {
            source: LightSource::Point { position },
            power: Vec3::splat(10.0),
            range: None,
            lamp_radius: radius,
        }
    }

    /// A grid of unit-square points, including both edges.
    fn grid(n: u32) -> impl Iterator<Item = Vec2> {
        (0..n)
            .flat_map(move |i| (0..n).map(move |j| Vec2::new(i as f32, j as f32) / (n - 1) as f32))
    }

    #[test]
    fn cone_samples_stay_inside_the_cone() {
        let axis = Vec3::new(0.3, -0.8, 0.5).normalize();
        for sin_max in [1e-4, 0.01, 0.3, 0.9, 0.999_999] {
            let cone = Cone::subtended(axis, sin_max).unwrap();
            for u in grid(17) {
                let (direction, one_minus_cos) = cone.sample(u);
                let cos_theta = 1.0 - one_minus_cos;
                assert!((direction.length() - 1.0).abs() < 1e-5);
                assert!((direction.dot(axis) - cos_theta).abs() < 1e-5);
                assert!(
                    one_minus_cos >= 0.0 && one_minus_cos <= cone.one_minus_cos_max,
                    "{sin_max} {u}"
                );
                assert!(direction.dot(axis) >= cone.cos_max - 1e-6);
            }
        }
    }

    #[test]
    fn cone_pdf_integrates_to_one_over_the_sphere_of_directions() {
        // Midpoint rule over (cos θ, φ) on the whole sphere, counting the
        // cells whose centre lies in the cone.
        for sin_max in [0.1f32, 0.5, 0.95] {
            let cone = Cone::subtended(Vec3::Z, sin_max).unwrap();
            let n = 2000;
            let cell = 2.0 / n as f32 * TAU;
            let inside = (0..n)
                .filter(|&i| -1.0 + (i as f32 + 0.5) * 2.0 / n as f32 > cone.cos_max)
                .count();
            let integral = inside as f32 * cell * cone.pdf();
            assert!((integral - 1.0).abs() < 0.02, "{sin_max}: {integral}");
        }
    }

    #[test]
    fn sampled_directions_hit_the_sphere() {
        let centre = Vec3::new(1.0, 2.0, -0.5);
        let radius = 0.4;
        let to_centre = centre;
        let distance = to_centre.length();
        let cone = Cone::subtended(to_centre / distance, radius / distance).unwrap();
        for u in grid(9) {
            let (direction, one_minus_cos) = cone.sample(u);
            let t = cone.distance_to_sphere(distance, one_minus_cos);
            let on_sphere = (direction * t - centre).length();
            assert!((on_sphere - radius).abs() < 1e-4, "{u}: {on_sphere}");
        }
    }

    #[test]
    fn a_far_small_lamp_delivers_the_point_lights_irradiance() {
        let point = ShadingPoint::matte(Vec3::ZERO, Vec3::Y);
        let centre = Vec3::new(0.0, 3.0, 0.0);
        let expected = point.omega(&lamp(centre, 0.0)).unwrap();
        let n = 16;
        let mut sum = Vec3::ZERO;
        for i in 0..n {
            for j in 0..n {
                let u = (Vec2::new(i as f32, j as f32) + 0.5) / n as f32;
                sum += sample_light(&point, &lamp(centre, 0.3), u).unwrap().value;
            }
        }
        let estimate = sum / (n * n) as f32;
        assert!(
            ((estimate - expected) / expected).abs().max_element() < 2e-3,
            "{estimate} vs {expected}"
        );
    }

    #[test]
    fn spot_cone_and_range_scale_the_whole_lamp_from_its_centre() {
        let point = ShadingPoint::matte(Vec3::ZERO, Vec3::Y);
        let centre = Vec3::new(0.0, 2.0, 0.0);
        let spot = |axis: Vec3, range: Option<f32>| RenderLight {
            source: LightSource::Spot {
                position: centre,
                axis,
                cos_outer: 0.9,
                cos_inner: 0.95,
            },
            range,
            ..lamp(centre, 1.0)
        };
        let u = Vec2::new(0.3, 0.6);
        let full = sample_light(&point, &lamp(centre, 1.0), u).unwrap().value;
        let down = sample_light(&point, &spot(Vec3::NEG_Y, None), u).unwrap();
        assert_eq!(down.value, full);
        // The centre's direction is outside the cone: nothing, although
        // part of the sphere would be inside a cone drawn from its rim.
        let aside = Vec3::new(0.5, -1.0, 0.0).normalize();
        assert!(sample_light(&point, &spot(aside, None), u).is_none());
        let windowed = sample_light(&point, &spot(Vec3::NEG_Y, Some(3.0)), u).unwrap();
        let window = (1.0f32 - (4.0f32 / 9.0).powi(2)).powi(2);
        assert!((windowed.value / full - window).abs().max_element() < 1e-5);
    }

    #[test]
    fn no_nan_near_the_sphere_or_at_grazing_angles() {
        let centre = Vec3::new(0.0, 1.0, 0.0);
        let radius = 0.5;
        let cases = [
            // Just outside the sphere, facing it and tangent to it.
            (Vec3::new(0.0, 0.5 - 1e-6, 0.0), Vec3::Y),
            (Vec3::new(0.0, 0.5 - 1e-6, 0.0), Vec3::X),
            (Vec3::new(0.5 + 1e-7, 1.0, 0.0), Vec3::X),
            // A floor whose horizon cuts the lamp, and one tangent to it.
            (Vec3::new(3.0, 0.9, 0.0), Vec3::Y),
            (Vec3::new(3.0, 0.5, 0.0), Vec3::Y),
            // Far away: a tiny cone.
            (Vec3::new(1e4, 0.0, 0.0), Vec3::Y),
            // Inside the sphere and at its centre: the point light.
            (Vec3::new(0.0, 0.8, 0.0), Vec3::Y),
            (centre, Vec3::Y),
        ];
        for (position, normal) in cases {
            let point = ShadingPoint::matte(position, normal);
            for u in grid(11) {
                if let Some(sample) = sample_light(&point, &lamp(centre, radius), u) {
                    assert!(sample.value.is_finite(), "{position} {u}: {}", sample.value);
                    assert!(sample.value.min_element() >= 0.0);
                    let ray = sample.shadow_ray;
                    assert!(ray.origin.is_finite() && ray.direction.is_finite());
                    let end = ray.at(ray.t_max);
                    assert!(
                        (end - centre).length() <= radius * (1.0 + 1e-3),
                        "{position} {u}: ends at {end}"
                    );
                }
            }
        }
    }
}
