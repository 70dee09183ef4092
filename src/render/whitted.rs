//! Whitted ray tracing's direct term, the paper's formula (1):
//! U_RT(P) = Σ_i V(i, P) · Omega(i, P), with V from a real shadow segment
//! per light. It is the reference the light-mesh methods approximate, and
//! their fallback where a point's interpolation set is empty.

use glam::Vec3;

use super::light_terms::LightTerms;
use super::omega::{LightLanes, PointLanes, LANES};
use super::shadow_split::ShadowSplit;
use super::surface::ShadingPoint;
use crate::accel::{Ray, World};
use crate::bits::set_bits;
use crate::stats::ClassRays;

/// Direct light at `point` by formula (1), every light's segment tested;
/// also returns how many shadow rays it traced (none for lights that
/// cannot reach the point anyway).
pub fn direct_light(point: &ShadingPoint, lights: &LightLanes, world: &World) -> (Vec3, u64) {
    let mut radiance = Vec3::ZERO;
    let split = ShadowSplit::default();
    let shadow_rays = direct_light_terms(point, lights, world, &split, &mut radiance);
    (radiance, shadow_rays.total())
}

/// Formula (1)'s visible terms at `point`, light by light into `terms`;
/// returns the shadow rays it traced, by class. The segments of lights
/// `shadows` calls unshadowed are not traced: nothing can block them.
pub fn direct_light_terms(
    point: &ShadingPoint,
    lights: &LightLanes,
    world: &World,
    shadows: &ShadowSplit,
    terms: &mut impl LightTerms,
) -> ClassRays {
    let mut shadow_rays = ClassRays::default();
    light_terms(point, lights, |light, omega, shadow_ray| {
        if shadows.tests_segment(light) {
            shadow_rays.add(shadows.class(light, lights.lights()));
            if world.occluded(&shadow_ray) {
                return;
            }
        }
        terms.add(light, omega);
    });
    shadow_rays
}

/// Direct light at `point` as formula (1) gives it with every light
/// visible (V = 1): what the point would get without shadows.
pub fn unshadowed_light(point: &ShadingPoint, lights: &LightLanes) -> Vec3 {
    let mut radiance = Vec3::ZERO;
    light_terms(point, lights, |_, omega, _| radiance += omega);
    radiance
}

/// Formula (1)'s terms at `point`, visibility aside: for each light that
/// can reach it, in light order, its index, its Omega and the shadow segment that
/// decides whether it counts. Omega comes eight lights at a time. A
/// backend that traces the segments elsewhere sums the visible terms in
/// this order, and gets [`direct_light`]'s bits.
pub fn light_terms(
    point: &ShadingPoint,
    lights: &LightLanes,
    mut term: impl FnMut(usize, Vec3, Ray),
) {
    let at = PointLanes::new(point);
    for block in 0..lights.blocks() {
        let omega = lights.omega(&at, block);
        for lane in set_bits(omega.reaching.into()) {
            let index = block * LANES + lane;
            term(
                index,
                omega.get(lane),
                point.shadow_ray(&lights.lights()[index]),
            );
        }
    }
}
