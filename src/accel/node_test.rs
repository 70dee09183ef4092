//! Conservative ray/box tests for BVH traversal. A box test that rounds the
//! wrong way culls a box whose triangle the ray really hits, and rays aimed at
//! shared edges and vertices (which lie on box faces) then escape a closed
//! mesh; the watertight triangle test is only as good as the traversal that
//! reaches it. So every slab interval here is widened by a bound on its own
//! rounding error (Ize, "Robust BVH Ray Traversal", JCGT 2013), for obvhs'
//! binary nodes and for the eight-wide nodes of [`wide`](super::wide) alike.
//! The eight-wide test has a twin for AVX2 ([`avx2`]) that answers bit for
//! bit alike.

use glam::{BVec3A, Vec3, Vec3A, Vec4};
use obvhs::aabb::Aabb;

use super::wide::WideNode;

#[cfg(target_arch = "x86_64")]
mod avx2;

/// `(1 + 2 gamma(3))` of Ize's paper: how far a slab exit may be understated
/// by the two roundings of `(bound - origin) * inv_dir`, plus the rounding of
/// `inv_dir` itself.
pub const BINARY_SCALE: f32 = 1.0 + 2.0 * gamma(3);
/// Stand-in for `1 / 0` and the largest inverse used: keeps every slab value
/// finite (so no `0 * inf = NaN`) while far exceeding any real `t`.
pub const INV_LIMIT: f32 = 18_446_744_073_709_551_616.0; // 2^64

const fn gamma(n: u32) -> f32 {
    let u = f32::EPSILON * 0.5;
    (n as f32 * u) / (1.0 - n as f32 * u)
}

/// The per-ray data of traversal, computed once per ray (and once per
/// instance for rays taken into object space).
#[derive(Clone, Copy, Debug)]
pub struct TraversalRay {
    pub origin: Vec3A,
    pub inv_direction: Vec3A,
    /// Axes along which the direction is exactly zero. The ray then lies in
    /// every slab plane through its origin, and `0 * inv` would put it on the
    /// slab's edge instead of inside; such rays take a slower, exact path.
    parallel: BVec3A,
    /// Axes along which the direction is negative: the near plane of a box
    /// is then its max.
    negative: [bool; 3],
    /// The same as a number, `x` in bit 2, `y` in 1, `z` in 0: obvhs' octant
    /// order of wide children.
    pub octant: u32,
    /// `origin` and `inv_direction` per axis, splatted for the wide test.
    origin4: [Vec4; 3],
    inv_direction4: [Vec4; 3],
}

impl TraversalRay {
    pub fn new(origin: Vec3, direction: Vec3) -> TraversalRay {
        let inv = |d: f32| {
            // Both zeros count as positive, as in obvhs' octant order.
            if d == 0.0 {
                INV_LIMIT
            } else {
                (1.0 / d).clamp(-INV_LIMIT, INV_LIMIT)
            }
        };
        let inv_direction = Vec3A::new(inv(direction.x), inv(direction.y), inv(direction.z));
        TraversalRay {
            origin: origin.into(),
            inv_direction,
            parallel: Vec3A::from(direction).cmpeq(Vec3A::ZERO),
            negative: direction.to_array().map(|d| d < 0.0),
            octant: (direction.x < 0.0) as u32 * 4
                + (direction.y < 0.0) as u32 * 2
                + (direction.z < 0.0) as u32,
            origin4: origin.to_array().map(Vec4::splat),
            inv_direction4: inv_direction.to_array().map(Vec4::splat),
        }
    }

    /// Whether the direction is exactly zero along some axis, which only
    /// the portable tests handle.
    #[inline]
    pub fn has_parallel_axis(&self) -> bool {
        self.parallel.any()
    }

    /// Entry `t` of the box if the ray meets it in `[0, t_cull]` (widened by
    /// the rounding bound), else `None`.
    #[inline(always)]
    pub fn enter_box(&self, aabb: &Aabb, t_cull: f32) -> Option<f32> {
        let t1 = (aabb.min - self.origin) * self.inv_direction;
        let t2 = (aabb.max - self.origin) * self.inv_direction;
        let (mut near, mut far) = (t1.min(t2), t1.max(t2));
        if self.has_parallel_axis() {
            // Inside a slab (faces included) it never leaves; outside it never
            // enters.
            let inside = aabb.min.cmple(self.origin) & self.origin.cmple(aabb.max);
            let open = Vec3A::select(inside, Vec3A::NEG_INFINITY, Vec3A::INFINITY);
            near = Vec3A::select(self.parallel, open, near);
            far = Vec3A::select(self.parallel, -open, far);
        }
        let t_near = near.max_element().max(0.0);
        let t_far = far.min_element() * BINARY_SCALE;
        (t_near <= t_far && t_near <= t_cull * BINARY_SCALE).then_some(t_near)
    }

    /// Which children of a wide node the ray meets in `[0, t_cull]`, as a
    /// bit per child, and their entry `t`s: [`TraversalRay::enter_box`] for
    /// eight boxes at once.
    #[inline(always)]
    pub fn enter_children(&self, node: &WideNode, t_cull: f32) -> (u32, [f32; 8]) {
        let t_cull = Vec4::splat(t_cull * BINARY_SCALE);
        let mut hits = 0;
        let mut entry = [Vec4::ZERO; 2];
        for half in 0..2 {
            let mut slabs = [0, 1, 2].map(|k| {
                let planes = &node.planes[k];
                let side = self.negative[k] as usize;
                let slab = |plane: Vec4| (plane - self.origin4[k]) * self.inv_direction4[k];
                (slab(planes[side][half]), slab(planes[side ^ 1][half]))
            });
            if self.has_parallel_axis() {
                // As in `enter_box`, for four boxes at once.
                for (k, (near, far)) in slabs.iter_mut().enumerate() {
                    if self.parallel.test(k) {
                        let [min, max] = node.planes[k].map(|p| p[half]);
                        let inside = min.cmple(self.origin4[k]) & self.origin4[k].cmple(max);
                        *near = Vec4::select(inside, Vec4::NEG_INFINITY, Vec4::INFINITY);
                        *far = -*near;
                    }
                }
            }
            let near = slabs.iter().fold(Vec4::ZERO, |t, (near, _)| t.max(*near));
            let far = slabs.iter().fold(Vec4::INFINITY, |t, (_, far)| t.min(*far));
            hits |= near.cmple((far * BINARY_SCALE).min(t_cull)).bitmask() << (4 * half);
            entry[half] = near;
        }
        let [a, b] = entry.map(|v| v.to_array());
        (hits, [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]])
    }
}
