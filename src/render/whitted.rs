//! Whitted ray tracing's direct term, the paper's formula (1):
//! U_RT(P) = Σ_i V(i, P) · Omega(i, P), with V from a real shadow segment
//! per light. It is the reference the light-mesh methods approximate, and
//! their fallback where a point's interpolation set is empty.

use glam::Vec3;

use super::omega::{LightLanes, PointLanes, LANES};
use super::surface::ShadingPoint;
use crate::accel::World;
use crate::bits::set_bits;

/// Direct light at `point` by formula (1); also returns how many shadow
/// rays it traced (none for lights that cannot reach the point anyway).
/// Omega comes eight lights at a time; the sum runs in light order.
pub fn direct_light(point: &ShadingPoint, lights: &LightLanes, world: &World) -> (Vec3, u64) {
    let mut radiance = Vec3::ZERO;
    let mut shadow_rays = 0;
    let at = PointLanes::new(point);
    for block in 0..lights.blocks() {
        let omega = lights.omega(&at, block);
        for lane in set_bits(omega.reaching.into()) {
            shadow_rays += 1;
            let light = &lights.lights()[block * LANES + lane];
            if !world.occluded(&point.shadow_ray(light)) {
                radiance += omega.get(lane);
            }
        }
    }
    (radiance, shadow_rays)
}
