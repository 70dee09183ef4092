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
    /// Axes along which the direction is negative, `x` in bit 0, `y` in 1,
    /// `z` in 2: the near plane of a box is then its max.
    negative: u32,
}

/// A ray's origin and inverse direction, each axis in four lanes.
#[derive(Clone, Copy, Debug)]
pub struct RayLanes {
    origin: [Vec4; 3],
    inv_direction: [Vec4; 3],
}

impl TraversalRay {
    /// All three axes at once in SIMD lanes, with the operations of one
    /// axis at a time, so with their bits: a ray's setup weighs on short
    /// shadow rays.
    pub fn new(origin: Vec3, direction: Vec3) -> TraversalRay {
        let direction = Vec3A::from(direction);
        let limit = Vec3A::splat(INV_LIMIT);
        // `f32::clamp`, NaN kept: `min`/`max` would replace it.
        let inv = Vec3A::ONE / direction;
        let inv = Vec3A::select(inv.cmplt(-limit), -limit, inv);
        let inv = Vec3A::select(inv.cmpgt(limit), limit, inv);
        // Both zeros count as positive, as in obvhs' octant order.
        let parallel = direction.cmpeq(Vec3A::ZERO);
        let negative = direction.cmplt(Vec3A::ZERO).bitmask();
        TraversalRay {
            origin: origin.into(),
            inv_direction: Vec3A::select(parallel, limit, inv),
            parallel,
            negative,
        }
    }

    /// The axes along which the direction is negative as obvhs' octant
    /// order of wide children numbers them: `x` in bit 2, `y` in 1, `z`
    /// in 0.
    #[inline(always)]
    pub fn octant(&self) -> u32 {
        let negative = self.negative;
        (negative & 1) << 2 | (negative & 2) | (negative >> 2)
    }

    /// Whether the direction is exactly zero along some axis, which only
    /// the portable tests handle.
    #[inline]
    pub fn has_parallel_axis(&self) -> bool {
        self.parallel.any()
    }

    /// Which of a box's planes along axis `k` the ray enters by: 0 for the
    /// min, 1 for the max.
    #[inline(always)]
    pub fn near_side(&self, k: usize) -> usize {
        (self.negative >> k & 1) as usize
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

    /// The ray's origin and inverse direction splatted per axis, for
    /// [`TraversalRay::enter_children`]: made once per walk, by the walks
    /// that use it, rather than with every ray.
    pub fn lanes(&self) -> RayLanes {
        RayLanes {
            origin: [0, 1, 2].map(|k| Vec4::splat(self.origin[k])),
            inv_direction: [0, 1, 2].map(|k| Vec4::splat(self.inv_direction[k])),
        }
    }

    /// Which children of a wide node the ray meets in `[0, t_cull]`, as a
    /// bit per child, and their entry `t`s: [`TraversalRay::enter_box`] for
    /// eight boxes at once. `lanes` are this ray's.
    #[inline(always)]
    pub fn enter_children(
        &self,
        lanes: &RayLanes,
        node: &WideNode,
        t_cull: f32,
    ) -> (u32, [f32; 8]) {
        let t_cull = Vec4::splat(t_cull * BINARY_SCALE);
        let mut hits = 0;
        let mut entry = [Vec4::ZERO; 2];
        for half in 0..2 {
            let (mut near, mut far) = (Vec4::ZERO, Vec4::INFINITY);
            // Loops, not `map` with closures: LLVM left those as calls
            // where the whole walk is inlined into a query.
            for k in 0..3 {
                let planes = &node.planes[k];
                let side = self.near_side(k);
                let slab = |plane: Vec4| (plane - lanes.origin[k]) * lanes.inv_direction[k];
                let mut near_k = slab(planes[side][half]);
                let mut far_k = slab(planes[side ^ 1][half]);
                if self.has_parallel_axis() && self.parallel.test(k) {
                    // As in `enter_box`, for four boxes at once.
                    let (min, max) = (planes[0][half], planes[1][half]);
                    let inside = min.cmple(lanes.origin[k]) & lanes.origin[k].cmple(max);
                    near_k = Vec4::select(inside, Vec4::NEG_INFINITY, Vec4::INFINITY);
                    far_k = -near_k;
                }
                near = near.max(near_k);
                far = far.min(far_k);
            }
            hits |= near.cmple((far * BINARY_SCALE).min(t_cull)).bitmask() << (4 * half);
            entry[half] = near;
        }
        let [a, b] = entry.map(|v| v.to_array());
        (hits, [a[0], a[1], a[2], a[3], b[0], b[1], b[2], b[3]])
    }
}
