//! Conservative ray/box tests for BVH traversal. A box test that rounds the
//! wrong way culls a box whose triangle the ray really hits, and rays aimed at
//! shared edges and vertices (which lie on box faces) then escape a closed
//! mesh; the watertight triangle test is only as good as the traversal that
//! reaches it. So every slab interval here is widened by a bound on its own
//! rounding error (Ize, "Robust BVH Ray Traversal", JCGT 2013), for obvhs'
//! binary nodes and for its quantised eight-wide nodes alike.

use glam::{BVec3A, Vec3, Vec3A, Vec4};
use obvhs::{aabb::Aabb, cwbvh::node::CwBvhNode};

/// `(1 + 2 gamma(3))` of Ize's paper: how far a slab exit may be understated
/// by the two roundings of `(bound - origin) * inv_dir`, plus the rounding of
/// `inv_dir` itself.
const BINARY_SCALE: f32 = 1.0 + 2.0 * gamma(3);
/// Relative error bound for the quantised child planes of a wide node,
/// `q * (extent * inv) + (p - origin) * inv`: a handful of roundings, plus
/// obvhs' quantisation of the child bounds, which may round in by one
/// rounding of `child - p`.
const WIDE_GAMMA: f32 = gamma(8);
/// Stand-in for `1 / 0` and the largest inverse used: keeps every slab value
/// finite (so no `0 * inf = NaN`) while far exceeding any real `t`.
const INV_LIMIT: f32 = 18_446_744_073_709_551_616.0; // 2^64

const fn gamma(n: u32) -> f32 {
    let u = f32::EPSILON * 0.5;
    (n as f32 * u) / (1.0 - n as f32 * u)
}

/// The per-ray data of traversal, computed once per ray (and once per
/// instance for rays taken into object space).
#[derive(Clone, Copy, Debug)]
pub struct TraversalRay {
    pub origin: Vec3A,
    pub direction: Vec3A,
    pub inv_direction: Vec3A,
    /// Axes along which the direction is exactly zero. The ray then lies in
    /// every slab plane through its origin, and `0 * inv` would put it on the
    /// slab's edge instead of inside; such rays take a slower, exact path.
    parallel: BVec3A,
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
        TraversalRay {
            origin: origin.into(),
            direction: direction.into(),
            inv_direction: Vec3A::new(inv(direction.x), inv(direction.y), inv(direction.z)),
            parallel: Vec3A::from(direction).cmpeq(Vec3A::ZERO),
        }
    }

    /// Entry `t` of the box if the ray meets it in `[0, t_cull]` (widened by
    /// the rounding bound), else `None`.
    #[inline(always)]
    pub fn enter_box(&self, aabb: &Aabb, t_cull: f32) -> Option<f32> {
        let t1 = (aabb.min - self.origin) * self.inv_direction;
        let t2 = (aabb.max - self.origin) * self.inv_direction;
        let (mut near, mut far) = (t1.min(t2), t1.max(t2));
        if self.parallel.any() {
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

    /// The obvhs hit mask of the children of a wide node that the ray meets
    /// in `[0, t_cull]`, widened by the rounding bound; same layout as
    /// `CwBvhNode::intersect_ray`.
    #[inline(always)]
    pub fn wide_child_mask(&self, node: &CwBvhNode, oct_inv4: u32, t_cull: f32) -> u32 {
        let scale = node.compute_extent() * self.inv_direction;
        let offset = (Vec3A::from(node.p) - self.origin) * self.inv_direction;
        let slack = WIDE_GAMMA * (255.0 * scale.abs() + offset.abs());
        let t_cull = Vec4::splat(t_cull * BINARY_SCALE);
        let (child_bits8, bit_index8) = node.get_child_and_index_bits(oct_inv4);
        let negative = self.direction.cmplt(Vec3A::ZERO);
        let mut hit_mask = 0;
        for half in 0..2 {
            let q = |v: &[u8; 8]| {
                let i = half * 4;
                Vec4::new(
                    v[i] as f32,
                    v[i + 1] as f32,
                    v[i + 2] as f32,
                    v[i + 3] as f32,
                )
            };
            // Near and far plane of each child along one axis, widened.
            let axis = |lo: &[u8; 8], hi: &[u8; 8], k: usize, neg: bool| {
                let (near, far) = if neg { (q(hi), q(lo)) } else { (q(lo), q(hi)) };
                (
                    near * scale[k] + offset[k] - slack[k],
                    far * scale[k] + offset[k] + slack[k],
                )
            };
            let (nx, fx) = axis(&node.child_min_x, &node.child_max_x, 0, negative.test(0));
            let (ny, fy) = axis(&node.child_min_y, &node.child_max_y, 1, negative.test(1));
            let (nz, fz) = axis(&node.child_min_z, &node.child_max_z, 2, negative.test(2));
            let t_near = nx.max(ny).max(nz).max(Vec4::ZERO);
            let t_far = fx.min(fy).min(fz).min(t_cull);
            let mask = t_near.cmple(t_far).bitmask();
            for j in 0..4 {
                if mask & (1 << j) != 0 {
                    let slot = (half * 4 + j) * 8;
                    let child_bits = ((child_bits8 >> slot) & 0xff) as u32;
                    let bit_index = ((bit_index8 >> slot) & 0xff) as u32;
                    hit_mask |= child_bits << bit_index;
                }
            }
        }
        hit_mask
    }
}
