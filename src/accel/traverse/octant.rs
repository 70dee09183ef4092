//! The any-hit walk: children in obvhs' octant order, which needs no entry
//! `t` on the stack. A node whose test lets several children through
//! leaves one entry, the node and the ranks still to visit, where pushing
//! each child cost about seventeen instructions: a shadow ray pushed nine
//! children on average and, stopping at its first hit, popped a third of
//! one.

use std::mem::MaybeUninit;

use super::super::wide::{ChildRef, WideBvh};
use super::node_test_path::ChildTest;
use super::stack::UninitStack;
use super::{visit_leaf, TraversalRay, Visit, Walk};

/// [`Order::Octant`](super::Order::Octant).
pub struct OctantOrder;

/// A node some of whose children are still to visit.
#[derive(Clone, Copy, Debug)]
pub struct Group {
    node: u32,
    /// Bit `r` for the child of rank `r`, lowest next.
    ranks: u32,
}

impl Walk for OctantOrder {
    type Entry = Group;

    /// At most one group per level: a group is taken off before the walk
    /// leaves its node's subtree for good.
    fn capacity(depth: usize) -> usize {
        depth
    }

    /// The same visits in the same order as pushing every child, highest
    /// rank first, and popping them one by one.
    #[inline(always)]
    fn walk(
        bvh: &WideBvh,
        ray: &TraversalRay,
        mut t_cull: f32,
        mut visit: impl Visit,
        slots: &mut [MaybeUninit<Group>],
        test: impl ChildTest,
    ) {
        let mut stack = UninitStack::new(slots);
        // Ranked `slot ^ octant`, children come front to back, as obvhs
        // placed them in their slots for the ray's octant.
        let flip = ray.octant();
        let mut child = ChildRef::ROOT;
        loop {
            if child.prim_count > 0 {
                if !visit_leaf(child, &mut visit, &mut t_cull) {
                    return;
                }
            } else {
                let node = &bvh.nodes[child.index as usize];
                let (ranks, _) = test.ranked_children(ray, node, t_cull, flip);
                if ranks != 0 {
                    let rest = ranks & (ranks - 1);
                    if rest != 0 {
                        stack.push(Group {
                            node: child.index,
                            ranks: rest,
                        });
                    }
                    child = node.child_ref((ranks.trailing_zeros() ^ flip) as usize);
                    continue;
                }
            }
            let Some(group) = stack.top_mut() else {
                return;
            };
            let (node, rank) = (group.node, group.ranks.trailing_zeros());
            group.ranks &= group.ranks - 1;
            if group.ranks == 0 {
                stack.pop();
            }
            child = bvh.nodes[node as usize].child_ref((rank ^ flip) as usize);
        }
    }
}
