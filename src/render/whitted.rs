//! Whitted ray tracing's direct term, the paper's formula (1):
//! U_RT(P) = Σ_i V(i, P) · Omega(i, P), with V from a real shadow segment
//! per light. It is the reference the light-mesh methods approximate, and
//! their fallback where a point's interpolation set is empty.

use glam::Vec3;

use super::light::RenderLight;
use super::surface::ShadingPoint;
use crate::accel::World;

/// Direct light at `point` by formula (1); also returns how many shadow
/// rays it traced (none for lights that cannot reach the point anyway).
pub fn direct_light(point: &ShadingPoint, lights: &[RenderLight], world: &World) -> (Vec3, u64) {
    let mut radiance = Vec3::ZERO;
    let mut shadow_rays = 0;
    for light in lights {
        let Some(omega) = point.omega(light) else {
            continue;
        };
        shadow_rays += 1;
        if !world.occluded(&point.shadow_ray(light)) {
            radiance += omega;
        }
    }
    (radiance, shadow_rays)
}
