//! Our eight-wide BVH for traversal: the topology of obvhs' CWBVH (its
//! SAH-driven collapse of the binary tree, at most three triangles per leaf)
//! with each child's box stored exactly in f32, structure of arrays, as
//! Embree's BVH8 does. The quantised CWBVH node saves memory but costs a
//! dequantisation and a per-node rounding bound on every visit, which made it
//! the bulk of a ray's instructions; exact boxes need only the per-ray bound
//! of [`node_test`](super::node_test).

use glam::{Vec3A, Vec4};
use obvhs::{aabb::Aabb, cwbvh::CwBvh};

/// Eight children: their boxes, and where each one leads. Padded from 232
/// bytes to 256 on four whole cache lines: a child's address is then its
/// index shifted, not multiplied by 240, one step shorter on the chain from
/// one node's load to the next that bounds a ray's time (3–4% more rays per
/// second; BENCHMARKS.md, "Ray tracing core", sixth session).
#[derive(Clone, Copy, Debug)]
#[repr(C, align(64))]
pub struct WideNode {
    /// `planes[axis][0]` are the children's min planes along `axis`,
    /// `planes[axis][1]` their max planes; children 0–3 then 4–7. An empty
    /// slot has the empty box (min `+inf`, max `-inf`), which no ray meets.
    pub planes: [[[Vec4; 2]; 2]; 3],
    /// Per child: a node index when `prim_count` is 0, else its leaf's first
    /// primitive slot.
    pub child: [u32; 8],
    pub prim_count: [u8; 8],
}

impl WideNode {
    /// The box of the child in `slot` as `[min, max]`, or None for an empty
    /// slot.
    ///
    /// Shaft queries call this for every child they reach, so it is
    /// written out rather than built with `array::map`, whose closures one
    /// build of the crate left as a call per coordinate (2 G instructions
    /// of a 540p frame's fill, measured by callgrind).
    #[inline(always)]
    pub fn child_box(&self, slot: usize) -> Option<[Vec3A; 2]> {
        let (half, lane) = (slot / 4, slot % 4);
        let side = |side: usize| {
            let plane = |axis: usize| self.planes[axis][side][half][lane];
            Vec3A::new(plane(0), plane(1), plane(2))
        };
        let (min, max) = (side(0), side(1));
        (!min.cmpgt(max).any()).then_some([min, max])
    }

    /// Where the child in `slot` leads.
    #[inline(always)]
    pub fn child_ref(&self, slot: usize) -> ChildRef {
        ChildRef {
            index: self.child[slot],
            prim_count: u32::from(self.prim_count[slot]),
        }
    }
}

/// A child to visit: an inner node (`prim_count == 0`) or a leaf's slots.
#[derive(Clone, Copy, Debug, Default)]
pub struct ChildRef {
    pub index: u32,
    pub prim_count: u32,
}

impl ChildRef {
    /// Where every walk starts: node 0.
    pub const ROOT: ChildRef = ChildRef {
        index: 0,
        prim_count: 0,
    };
}

pub struct WideBvh {
    /// The root is node 0; children always follow their parent.
    pub nodes: Vec<WideNode>,
    /// Nodes on the longest root-to-leaf path.
    pub depth: usize,
}

impl WideBvh {
    /// Takes `cwbvh`'s tree; `slot_bounds` gives the exact bounds of the
    /// primitive in each slot of its `primitive_indices`.
    pub fn from_cwbvh(cwbvh: &CwBvh, slot_bounds: impl Fn(usize) -> Aabb) -> WideBvh {
        let empty = WideNode {
            planes: [[[Vec4::INFINITY; 2], [Vec4::NEG_INFINITY; 2]]; 3],
            child: [0; 8],
            prim_count: [0; 8],
        };
        let mut nodes = vec![empty; cwbvh.nodes.len()];
        let mut depth = vec![1; cwbvh.nodes.len()];
        // Children follow their parent, so walking backwards finishes every
        // child before its parent needs its box.
        for (index, cw) in cwbvh.nodes.iter().enumerate().rev() {
            let mut inner_rank = 0;
            for slot in 0..8 {
                let meta = cw.child_meta[slot];
                let (child, prim_count, bounds) = if cw.imask & (1 << slot) != 0 {
                    let child = cw.child_base_idx + inner_rank;
                    inner_rank += 1;
                    depth[index] = depth[index].max(depth[child as usize] + 1);
                    (child, 0, node_bounds(&nodes[child as usize]))
                } else if meta != 0 {
                    // Leaf: the offset of its first primitive in the low five
                    // bits, its count in unary in the high three.
                    let first = cw.primitive_base_idx + u32::from(meta & 0b1_1111);
                    let count = (meta >> 5).count_ones();
                    let bounds = (first..first + count)
                        .fold(Aabb::empty(), |b, s| b.union(&slot_bounds(s as usize)));
                    (first, count as u8, bounds)
                } else {
                    continue;
                };
                let node = &mut nodes[index];
                node.child[slot] = child;
                node.prim_count[slot] = prim_count;
                let (half, lane) = (slot / 4, slot % 4);
                for axis in 0..3 {
                    node.planes[axis][0][half][lane] = bounds.min[axis];
                    node.planes[axis][1][half][lane] = bounds.max[axis];
                }
            }
        }
        WideBvh {
            nodes,
            depth: depth.first().copied().unwrap_or(0),
        }
    }
}

impl WideBvh {
    /// Visits the primitive slots of every leaf whose box, and whose
    /// ancestors' boxes, `may_meet` accepts; stops as soon as `visit`
    /// returns false, and then returns false.
    pub fn visit_boxes(
        &self,
        may_meet: impl Fn(Vec3A, Vec3A) -> bool,
        mut visit: impl FnMut(usize) -> bool,
    ) -> bool {
        if self.nodes.is_empty() {
            return true;
        }
        let mut stack = vec![0u32];
        while let Some(index) = stack.pop() {
            let node = &self.nodes[index as usize];
            for slot in 0..8 {
                if !node
                    .child_box(slot)
                    .is_some_and(|[min, max]| may_meet(min, max))
                {
                    continue;
                }
                let child = node.child[slot];
                match node.prim_count[slot] {
                    0 => stack.push(child),
                    count => {
                        if !(child..child + u32::from(count)).all(|s| visit(s as usize)) {
                            return false;
                        }
                    }
                }
            }
        }
        true
    }
}

/// The union of a node's child boxes.
fn node_bounds(node: &WideNode) -> Aabb {
    let axis = |side: usize, fold: fn(Vec4, Vec4) -> Vec4, pick: fn(Vec4) -> f32| {
        Vec3A::from_array(
            [0, 1, 2].map(|k| pick(fold(node.planes[k][side][0], node.planes[k][side][1]))),
        )
    };
    Aabb::new(
        axis(0, Vec4::min, Vec4::min_element),
        axis(1, Vec4::max, Vec4::max_element),
    )
}

#[cfg(test)]
mod tests {
    use std::time::Duration;

    use glam::Vec3A;
    use obvhs::{cwbvh::builder::build_cwbvh, BvhBuildParams};

    use super::*;

    /// Every primitive slot sits in exactly one leaf, under boxes that
    /// contain its own: the CWBVH's packed child metadata is read right.
    #[test]
    fn leaves_cover_every_slot_once_inside_their_boxes() {
        let aabbs: Vec<Aabb> = (0..500u32)
            .map(|i| {
                let f = |k: u32| {
                    (i.wrapping_mul(2_654_435_761).wrapping_add(k * 7919) % 997) as f32 / 10.0
                };
                let min = Vec3A::new(f(1), f(2), f(3));
                Aabb::new(min, min + Vec3A::new(f(4), f(5), f(6)) * 0.05)
            })
            .collect();
        let cwbvh = build_cwbvh(
            &aabbs,
            BvhBuildParams::medium_build(),
            &mut Duration::default(),
        );
        let slot_bounds = |slot: usize| aabbs[cwbvh.primitive_indices[slot] as usize];
        let bvh = WideBvh::from_cwbvh(&cwbvh, slot_bounds);
        let mut seen = vec![0; aabbs.len()];
        let mut stack = vec![(0usize, Aabb::new(Vec3A::NEG_INFINITY, Vec3A::INFINITY))];
        while let Some((index, outer)) = stack.pop() {
            let node = &bvh.nodes[index];
            for slot in 0..8 {
                let Some([min, max]) = node.child_box(slot) else {
                    continue;
                };
                assert!(outer.min.cmple(min).all() && max.cmple(outer.max).all());
                let child = node.child[slot] as usize;
                match node.prim_count[slot] {
                    0 => stack.push((child, Aabb::new(min, max))),
                    n => {
                        for (s, count) in seen.iter_mut().enumerate().skip(child).take(n.into()) {
                            *count += 1;
                            let b = slot_bounds(s);
                            assert!(min.cmple(b.min).all() && b.max.cmple(max).all());
                        }
                    }
                }
            }
        }
        assert!(seen.iter().all(|&n| n == 1));
        assert!(bvh.depth >= 3);
    }

    #[test]
    fn a_node_fills_four_whole_cache_lines() {
        assert_eq!(std::mem::size_of::<WideNode>(), 256);
        assert_eq!(std::mem::align_of::<WideNode>(), 64);
    }
}
