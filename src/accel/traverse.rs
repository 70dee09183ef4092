//! Stack traversal of the two BVH layouts (obvhs' BVH2, our [`WideBvh`]) with
//! the conservative box tests of [`node_test`](super::node_test). The binary
//! layout has one loop for closest-hit and any-hit queries, the wide one a
//! loop per [`Order`] ([`nearest`] and [`octant`]): the visitor sees each
//! candidate primitive slot, may lower the culling distance, and may stop
//! the walk.

use std::mem::MaybeUninit;

use obvhs::{bvh2::Bvh2, fast_stack, faststack::FastStack};

use super::node_test::TraversalRay;
use super::wide::{ChildRef, WideBvh, WideNode};
use nearest::NearestFirst;
#[cfg(target_arch = "x86_64")]
use node_test_path::Avx2Test;
pub use node_test_path::NodeTestPath;
use node_test_path::{ChildTest, PortableTest};
use octant::OctantOrder;
use stack::UninitStack;

mod nearest;
mod node_test_path;
mod octant;
mod stack;
#[cfg(test)]
mod visit_order;

/// Called with a primitive slot (an index into the BVH's
/// `primitive_indices`) and the culling distance, which it may lower;
/// returns `false` to end the traversal. Closures are visitors; the mesh
/// queries' own are structs, whose `#[inline(always)]` visit inlines into
/// the walk's loop where a closure stays a call.
pub trait Visit {
    fn visit(&mut self, slot: usize, t_cull: &mut f32) -> bool;
}

impl<F: FnMut(usize, &mut f32) -> bool> Visit for F {
    #[inline(always)]
    fn visit(&mut self, slot: usize, t_cull: &mut f32) -> bool {
        self(slot, t_cull)
    }
}

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
        (first..first + count).all(|slot| visit.visit(slot as usize, t_cull))
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

/// In which order [`traverse_wide`] visits the children a ray meets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Order {
    /// By entry `t`: what a closest-hit query needs to lower `t_cull` early.
    Nearest,
    /// By obvhs' octant slots, unsorted: nearly front to back, and cheaper
    /// for any-hit queries, which stop at the first hit anyway. The walk
    /// keeps to the `t_cull` it was given for what it has queued (a lower
    /// one still bounds the nodes it tests next): any-hit visitors never
    /// lower it.
    Octant,
}

/// Walks a wide BVH in `order`, testing nodes by `path`. In nearest order
/// the children a node's test lets through go onto the stack with their
/// entry `t`, and are skipped when popped beyond a `t_cull` lowered
/// meanwhile.
pub fn traverse_wide(
    bvh: &WideBvh,
    ray: &TraversalRay,
    order: Order,
    path: NodeTestPath,
    t_cull: f32,
    visit: impl Visit,
) {
    if bvh.nodes.is_empty() {
        return;
    }
    match order {
        Order::Nearest => walk_wide::<NearestFirst>(bvh, ray, path, t_cull, visit),
        Order::Octant => walk_wide::<OctantOrder>(bvh, ray, path, t_cull, visit),
    }
}

/// What sets the wide walks' orders apart: how children are ranked, what
/// waits on the stack and how many of those, how a node's entered
/// children are queued and how the next one comes back. [`walk`] is the
/// loop both share.
trait Walk {
    type Entry: Copy;

    /// The most entries the stack holds on a tree `depth` nodes deep.
    fn capacity(depth: usize) -> usize;

    /// Children are ranked `slot ^ flip`.
    fn flip(ray: &TraversalRay) -> u32;

    /// Of the children of `node` (at `index`) the ray enters, by rank as
    /// [`ChildTest::ranked_children`] gives them, returns the one to visit
    /// next and queues the others; None when it enters none. The one
    /// returned was entered within `t_cull` by the test just made.
    fn descend(
        stack: &mut UninitStack<Self::Entry>,
        index: u32,
        node: &WideNode,
        ranks: u32,
        entry: &[f32; 8],
        flip: u32,
    ) -> Option<ChildRef>;

    /// The next queued child to visit, None when the walk is over.
    fn resume(
        stack: &mut UninitStack<Self::Entry>,
        bvh: &WideBvh,
        t_cull: f32,
        flip: u32,
    ) -> Option<ChildRef>;
}

/// Runs walk `W` on a stack kept on the call stack for the usual depths,
/// and never cleared (see `stack`).
fn walk_wide<W: Walk>(
    bvh: &WideBvh,
    ray: &TraversalRay,
    path: NodeTestPath,
    t_cull: f32,
    visit: impl Visit,
) {
    match W::capacity(bvh.depth) {
        n if n <= 128 => {
            let mut slots = [MaybeUninit::uninit(); 128];
            walk_with_test::<W>(bvh, ray, path, t_cull, visit, &mut slots);
        }
        n => walk_with_test::<W>(
            bvh,
            ray,
            path,
            t_cull,
            visit,
            &mut vec![MaybeUninit::uninit(); n],
        ),
    }
}

/// Runs walk `W` with the node test `path` asks for.
#[inline(always)]
fn walk_with_test<W: Walk>(
    bvh: &WideBvh,
    ray: &TraversalRay,
    path: NodeTestPath,
    t_cull: f32,
    visit: impl Visit,
    slots: &mut [MaybeUninit<W::Entry>],
) {
    match path {
        // Rays parallel to an axis need the portable test's exact fix-up,
        // so they take the portable walk as a whole.
        #[cfg(target_arch = "x86_64")]
        NodeTestPath::Avx2(detected) if !ray.has_parallel_axis() => {
            // SAFETY: `detected` proves that the CPU has AVX2.
            unsafe { walk_avx2::<W>(bvh, ray, t_cull, visit, slots, Avx2Test(detected)) }
        }
        _ => walk::<W>(bvh, ray, t_cull, visit, slots, PortableTest(ray.lanes())),
    }
}

/// The whole walk compiled for AVX2, visitor included, so that the AVX2
/// node test inlines into its loop (a call per node would cost more than
/// the wider test saves).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn walk_avx2<W: Walk>(
    bvh: &WideBvh,
    ray: &TraversalRay,
    t_cull: f32,
    visit: impl Visit,
    slots: &mut [MaybeUninit<W::Entry>],
    test: Avx2Test,
) {
    walk::<W>(bvh, ray, t_cull, visit, slots, test);
}

/// The walk itself, in `W`'s order, with `test` as the node test. The
/// child visited next is kept in hand rather than queued and taken back
/// at once: where a node lets one child through (most nodes, for most
/// rays) the stack is not touched at all.
#[inline(always)]
fn walk<W: Walk>(
    bvh: &WideBvh,
    ray: &TraversalRay,
    mut t_cull: f32,
    mut visit: impl Visit,
    slots: &mut [MaybeUninit<W::Entry>],
    test: impl ChildTest,
) {
    let mut stack = UninitStack::new(slots);
    let flip = W::flip(ray);
    let mut child = ChildRef::ROOT;
    loop {
        if child.prim_count > 0 {
            if !visit_leaf(child, &mut visit, &mut t_cull) {
                return;
            }
        } else {
            let node = &bvh.nodes[child.index as usize];
            let (ranks, entry) = test.ranked_children(ray, node, t_cull, flip);
            if let Some(next) = W::descend(&mut stack, child.index, node, ranks, &entry, flip) {
                child = next;
                continue;
            }
        }
        match W::resume(&mut stack, bvh, t_cull, flip) {
            Some(next) => child = next,
            None => return,
        }
    }
}

/// Visits the slots of a leaf in order until `visit` says stop; returns
/// whether the walk goes on. A loop, not `Iterator::all`: LLVM left that
/// closure as a call, compiled without the walk's AVX2.
#[inline(always)]
fn visit_leaf(leaf: ChildRef, visit: &mut impl Visit, t_cull: &mut f32) -> bool {
    for slot in leaf.index..leaf.index + leaf.prim_count {
        if !visit.visit(slot as usize, t_cull) {
            return false;
        }
    }
    true
}
