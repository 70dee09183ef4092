//! The any-hit walk: children in obvhs' octant order, which needs no entry
//! `t` on the stack. A node whose test lets several children through
//! leaves one entry, the node and the ranks still to visit, where pushing
//! each child cost about seventeen instructions: a shadow ray pushed nine
//! children on average and, stopping at its first hit, popped a third of
//! one.

use super::super::wide::{ChildRef, WideBvh, WideNode};
use super::stack::UninitStack;
use super::{TraversalRay, Walk};

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

    /// Ranked `slot ^ octant`, children come front to back, as obvhs
    /// placed them in their slots for the ray's octant.
    #[inline(always)]
    fn flip(ray: &TraversalRay) -> u32 {
        ray.octant()
    }

    /// The lowest rank is visited next; the others wait as one group.
    #[inline(always)]
    fn descend(
        stack: &mut UninitStack<Group>,
        index: u32,
        node: &WideNode,
        ranks: u32,
        _: &[f32; 8],
        flip: u32,
    ) -> Option<ChildRef> {
        if ranks == 0 {
            return None;
        }
        let rest = ranks & (ranks - 1);
        if rest != 0 {
            stack.push(Group {
                node: index,
                ranks: rest,
            });
        }
        Some(node.child_ref((ranks.trailing_zeros() ^ flip) as usize))
    }

    /// The lowest rank of the group on top, which leaves the stack with
    /// its last rank: the same visits in the same order as pushing every
    /// child, highest rank first, and popping them one by one.
    #[inline(always)]
    fn resume(
        stack: &mut UninitStack<Group>,
        bvh: &WideBvh,
        _: f32,
        flip: u32,
    ) -> Option<ChildRef> {
        let group = stack.top_mut()?;
        let (node, rank) = (group.node, group.ranks.trailing_zeros());
        group.ranks &= group.ranks - 1;
        if group.ranks == 0 {
            stack.pop();
        }
        Some(bvh.nodes[node as usize].child_ref((rank ^ flip) as usize))
    }
}
