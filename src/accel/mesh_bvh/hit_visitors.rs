//! What [`MeshBvh`]'s queries do with each candidate slot the walk hands
//! them: test its triangle, keep the closest hit or stop at the first.
//! Structs with an `#[inline(always)]` visit rather than closures: LLVM
//! kept a closure as a call per triangle, and around that call spilled and
//! reloaded the walk's ray data (6–7% of a ray's instructions).

use super::{normal, MeshBvh, MeshHit};
use crate::accel::traverse::Visit;
use crate::accel::triangle::WatertightRay;

/// Keeps the closest hit in `best` (ties by source) and lowers the culling
/// distance to it.
pub struct ClosestHit<'a> {
    pub mesh: &'a MeshBvh,
    pub exact: WatertightRay,
    pub best: &'a mut Option<MeshHit>,
}

impl Visit for ClosestHit<'_> {
    #[inline(always)]
    fn visit(&mut self, slot: usize, t_cull: &mut f32) -> bool {
        let vertices = &self.mesh.vertices[slot];
        let [a, b, c] = vertices;
        if let Some(hit) = self.exact.intersect(a, b, c) {
            let candidate = MeshHit {
                t: hit.t,
                source: self.mesh.sources[slot],
                barycentric: hit.barycentric,
                normal: normal(vertices),
            };
            if candidate.precedes(self.best) {
                *self.best = Some(candidate);
                *t_cull = hit.t;
            }
        }
        true
    }
}

/// Stops at the first slot whose triangle the ray crosses, kept in `found`.
pub struct AnyHit<'a> {
    pub vertices: &'a [[[f32; 3]; 3]],
    pub exact: WatertightRay,
    pub found: &'a mut Option<u32>,
}

impl Visit for AnyHit<'_> {
    #[inline(always)]
    fn visit(&mut self, slot: usize, _: &mut f32) -> bool {
        let [a, b, c] = &self.vertices[slot];
        if self.exact.intersect(a, b, c).is_some() {
            *self.found = Some(slot as u32);
        }
        self.found.is_none()
    }
}
