//! Stack traversal of obvhs' two BVH layouts with the conservative box tests
//! of [`node_test`](super::node_test). One loop per layout serves both
//! closest-hit and any-hit queries: the visitor sees each candidate primitive
//! slot, may lower the culling distance, and may stop the walk.

use glam::UVec2;
use obvhs::{bvh2::Bvh2, cwbvh::CwBvh, fast_stack, faststack::FastStack};

use super::node_test::TraversalRay;

/// Called with a primitive slot (an index into the BVH's
/// `primitive_indices`) and the culling distance, which it may lower;
/// returns `false` to end the traversal.
pub trait Visit: FnMut(usize, &mut f32) -> bool {}
impl<F: FnMut(usize, &mut f32) -> bool> Visit for F {}

/// Walks a binary BVH near child first. Boxes entered beyond `t_cull`
/// (inclusive, so ties at equal `t` are still visited) are skipped.
pub fn traverse_binary(bvh: &Bvh2, ray: &TraversalRay, mut t_cull: f32, mut visit: impl Visit) {
    let Some(root) = bvh.nodes.first() else {
        return;
    };
    if ray.enter_box(root.aabb(), t_cull).is_none() {
        return;
    }
    let mut visit_leaf = |first: u32, count: u32, t_cull: &mut f32| {
        (first..first + count).all(|slot| visit(slot as usize, t_cull))
    };
    if root.is_leaf() {
        visit_leaf(root.first_index, root.prim_count, &mut t_cull);
        return;
    }
    fast_stack!(u32, (96, 192), bvh.max_depth, stack, {
        stack.push(root.first_index);
        while let Some(first_child) = stack.pop() {
            let left = &bvh.nodes[first_child as usize];
            let right = &bvh.nodes[first_child as usize + 1];
            let t_left = ray.enter_box(left.aabb(), t_cull);
            let t_right = ray.enter_box(right.aabb(), t_cull);
            let (near, far) = match (t_left, t_right) {
                (Some(l), Some(r)) if r < l => ((right, t_right), (left, t_left)),
                _ => ((left, t_left), (right, t_right)),
            };
            // Leaves are visited at once, near first; inner children go onto
            // the stack far first, so the near one is popped next.
            for (node, t) in [near, far] {
                if t.is_some()
                    && node.is_leaf()
                    && !visit_leaf(node.first_index, node.prim_count, &mut t_cull)
                {
                    return;
                }
            }
            for (node, t) in [far, near] {
                if t.is_some() && !node.is_leaf() {
                    stack.push(node.first_index);
                }
            }
        }
    });
}

/// Walks a compressed wide BVH in obvhs' ordered traversal, testing child
/// boxes conservatively.
pub fn traverse_wide(bvh: &CwBvh, ray: &TraversalRay, mut t_cull: f32, mut visit: impl Visit) {
    if bvh.nodes.is_empty() {
        return;
    }
    let mut state = bvh.new_traversal(ray.direction);
    let mut node;
    'walk: {
        obvhs::traverse!(
            bvh,
            node,
            state,
            ray.wide_child_mask(node, state.oct_inv4, t_cull),
            {
                if !visit(state.primitive_id as usize, &mut t_cull) {
                    break 'walk;
                }
            }
        );
    }
}
