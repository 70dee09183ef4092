//! Stages 5–6 of an LMM frame: the interpolation set D_LM(P) and formula (2),
//!
//!   U_LM(P) = (1/m) Σ_k Σ_{i : N_{x_k}(i) = 1} Omega(i, P)
//!           = Σ_i Omega(i, P) · (visible nodes of light i) / m,
//!
//! with Omega always evaluated at P. LMM keeps only the nodes that P sees
//! (step 3, one short segment each); LMM1 skips that test. An empty set
//! falls back to formula (1) with real shadow rays.

use glam::{IVec3, Vec3};

use super::masks::NodeMask;
use super::LightMesh;
use crate::accel::offset::offset_ray_origin;
use crate::accel::{Ray, World};
use crate::render::light::RenderLight;
use crate::render::surface::ShadingPoint;
use crate::render::whitted;

/// Which variant of the method: LMM tests V(x_k, P), LMM1 does not.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Variant {
    Lmm,
    Lmm1,
}

/// What shading one point cost, summed into the frame's statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PointCounts {
    pub candidates: u64,
    pub interp_set: u64,
    pub p2n_tests: u64,
    pub fallback: u64,
    pub shadow_rays: u64,
}

impl std::ops::AddAssign for PointCounts {
    fn add_assign(&mut self, other: PointCounts) {
        self.candidates += other.candidates;
        self.interp_set += other.interp_set;
        self.p2n_tests += other.p2n_tests;
        self.fallback += other.fallback;
        self.shadow_rays += other.shadow_rays;
    }
}

/// Reusable per-thread buffers, so shading allocates nothing per point.
#[derive(Default)]
pub struct Scratch {
    nodes: Vec<IVec3>,
}

impl LightMesh {
    /// Direct light at `point` by formula (2). Every bit it reads must have
    /// been filled from this frame's demand.
    pub fn shade(
        &self,
        point: &ShadingPoint,
        lights: &[RenderLight],
        world: &World,
        variant: Variant,
        scratch: &mut Scratch,
    ) -> (Vec3, PointCounts) {
        let mut counts = PointCounts::default();
        let nodes = &mut scratch.nodes;
        nodes.clear();
        self.lattice
            .half_ball(point.position, point.geometric_normal, self.radius(), nodes);
        counts.candidates = nodes.len() as u64;
        if variant == Variant::Lmm {
            counts.p2n_tests = nodes.len() as u64;
            let origin = offset_ray_origin(point.position, point.geometric_normal);
            let lattice = self.lattice;
            nodes.retain(|&node| {
                let x = lattice.node_position(node);
                !world.occluded(&Ray::new(origin, x - origin, 1.0))
            });
        }
        let m = nodes.len();
        counts.interp_set = m as u64;
        if m == 0 {
            let (radiance, shadow_rays) = whitted::direct_light(point, lights, world);
            counts.fallback = 1;
            counts.shadow_rays = shadow_rays;
            return (radiance, counts);
        }
        let masks: Vec<NodeMask> = nodes
            .iter()
            .filter_map(|&node| self.masks().node(node))
            .collect();
        let mut radiance = Vec3::ZERO;
        for (index, light) in lights.iter().enumerate() {
            let Some(omega) = point.omega(light) else {
                continue;
            };
            let visible = masks
                .iter()
                .filter(|mask| mask.get(index) == Some(true))
                .count();
            debug_assert!(
                masks.len() == m && masks.iter().all(|mask| mask.get(index).is_some()),
                "formula (2) read a mask bit that the fill stage did not compute"
            );
            if visible == m {
                radiance += omega;
            } else if visible > 0 {
                radiance += omega * (visible as f32 / m as f32);
            }
        }
        (radiance, counts)
    }
}
