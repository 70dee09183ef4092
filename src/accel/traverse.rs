//! Stack traversal of the two BVH layouts (obvhs' BVH2, our [`WideBvh`]) with
//! the conservative box tests of [`node_test`](super::node_test). One loop
//! per layout serves both closest-hit and any-hit queries: the visitor sees
//! each candidate primitive slot, may lower the culling distance, and may stop
//! the walk.

use std::mem::MaybeUninit;

use obvhs::{bvh2::Bvh2, fast_stack, faststack::FastStack};

use super::node_test::{TraversalRay, BINARY_SCALE};
use super::wide::{ChildRef, WideBvh, WideNode};
#[cfg(target_arch = "x86_64")]
use node_test_path::Avx2Test;
pub use node_test_path::NodeTestPath;
use node_test_path::{ChildTest, PortableTest};
use stack::UninitStack;

mod node_test_path;
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
    /// for any-hit queries, which stop at the first hit anyway.
    Octant,
}

/// Walks a wide BVH in `order`, testing nodes by `path`. The children a
/// node's test lets through go onto the stack with their entry `t`, and
/// are skipped when popped beyond a `t_cull` lowered meanwhile.
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
    // Each node visited pops one entry and pushes at most eight, so the stack
    // never holds more than seven per level plus one. Kept on the call stack
    // for the usual depths, and never cleared (see `stack`).
    match 7 * bvh.depth + 1 {
        n if n <= 128 => {
            let mut slots = [MaybeUninit::uninit(); 128];
            walk_wide(bvh, ray, order, path, t_cull, visit, &mut slots);
        }
        n => walk_wide(
            bvh,
            ray,
            order,
            path,
            t_cull,
            visit,
            &mut vec![MaybeUninit::uninit(); n],
        ),
    }
}

/// Runs the walk with the node test `path` asks for.
#[inline(always)]
fn walk_wide(
    bvh: &WideBvh,
    ray: &TraversalRay,
    order: Order,
    path: NodeTestPath,
    t_cull: f32,
    visit: impl Visit,
    slots: &mut [MaybeUninit<Entry>],
) {
    match path {
        // Rays parallel to an axis need the portable test's exact fix-up,
        // so they take the portable walk as a whole.
        #[cfg(target_arch = "x86_64")]
        NodeTestPath::Avx2(detected) if !ray.has_parallel_axis() => {
            let test = Avx2Test(detected);
            // SAFETY: `detected` proves that the CPU has AVX2.
            unsafe { walk_wide_avx2(bvh, ray, order, t_cull, visit, slots, test) }
        }
        _ => {
            let test = PortableTest(ray.lanes());
            walk_wide_with(bvh, ray, order, t_cull, visit, slots, test)
        }
    }
}

/// The whole walk compiled for AVX2, visitor included, so that the AVX2
/// node test inlines into its loop (a call per node would cost more than
/// the wider test saves).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
fn walk_wide_avx2(
    bvh: &WideBvh,
    ray: &TraversalRay,
    order: Order,
    t_cull: f32,
    visit: impl Visit,
    slots: &mut [MaybeUninit<Entry>],
    test: Avx2Test,
) {
    walk_wide_with(bvh, ray, order, t_cull, visit, slots, test);
}

/// The walk itself, with `test` as the node test. The child visited next
/// is kept in hand rather than pushed and popped at once: where a node
/// lets one child through (most nodes, for most rays) the stack is not
/// touched at all.
#[inline(always)]
fn walk_wide_with(
    bvh: &WideBvh,
    ray: &TraversalRay,
    order: Order,
    mut t_cull: f32,
    mut visit: impl Visit,
    slots: &mut [MaybeUninit<Entry>],
    test: impl ChildTest,
) {
    let mut stack = UninitStack::new(slots);
    let mut child = ChildRef::ROOT;
    // Children are taken in ascending rank. Ranked `slot ^ octant`, they
    // come front to back, as obvhs placed them in their slots for the
    // ray's octant; ranked by slot, they are sorted by entry `t`.
    let flip = match order {
        Order::Octant => ray.octant(),
        Order::Nearest => 0,
    };
    loop {
        if child.prim_count > 0 {
            let slots = child.index..child.index + child.prim_count;
            if !slots
                .into_iter()
                .all(|slot| visit.visit(slot as usize, &mut t_cull))
            {
                return;
            }
        } else {
            let node = &bvh.nodes[child.index as usize];
            let (ranks, entry) = test.ranked_children(ray, node, t_cull, flip);
            if let Some(next) = descend(&mut stack, node, ranks, &entry, flip, order) {
                child = next;
                continue;
            }
        }
        // The next child on the stack still entered within `t_cull`.
        child = loop {
            let Some(Entry { child, t }) = stack.pop() else {
                return;
            };
            if t > t_cull * BINARY_SCALE {
                continue;
            }
            break child;
        };
    }
}

/// Of the children of `node` the ray enters (by rank, as
/// [`ChildTest::ranked_children`] gives them), returns the one to visit
/// next and pushes the others so that they come off the stack in `order`;
/// None when it enters none. The one returned was entered within `t_cull`
/// by the test just made, so it needs no check.
#[inline(always)]
fn descend(
    stack: &mut UninitStack<Entry>,
    node: &WideNode,
    mut ranks: u32,
    entry: &[f32; 8],
    flip: u32,
    order: Order,
) -> Option<ChildRef> {
    let pushed = |slot: usize| Entry {
        child: node.child_ref(slot),
        t: entry[slot],
    };
    if ranks == 0 {
        return None;
    }
    let lowest = ranks.trailing_zeros();
    if order == Order::Octant || ranks.is_power_of_two() {
        ranks &= ranks - 1;
        push_descending(stack, ranks, flip, pushed);
        return Some(node.child_ref((lowest ^ flip) as usize));
    }
    // Nearest order, where `flip` is 0 and ranks are slots.
    let highest = 31 - ranks.leading_zeros();
    if ranks == 1 << lowest | 1 << highest {
        // Two children, the commonest case after one: the nearer is taken,
        // the lower slot on a tie, as the sort below would.
        let (near, far) = (lowest as usize, highest as usize);
        let (near, far) = if entry[far] < entry[near] {
            (far, near)
        } else {
            (near, far)
        };
        stack.push(pushed(far));
        return Some(node.child_ref(near));
    }
    let first = stack.len();
    push_descending(stack, ranks, 0, pushed);
    sort_far_to_near(stack.pushed_since(first));
    stack.pop().map(|nearest| nearest.child)
}

/// Pushes the children whose ranks are set in `ranks`, highest rank first.
#[inline(always)]
fn push_descending(
    stack: &mut UninitStack<Entry>,
    mut ranks: u32,
    flip: u32,
    pushed: impl Fn(usize) -> Entry,
) {
    while ranks != 0 {
        let rank = 31 - ranks.leading_zeros();
        ranks &= !(1 << rank);
        stack.push(pushed((rank ^ flip) as usize));
    }
}

/// Orders a node's pushed children so the nearest is popped first; rarely
/// more than two or three.
#[inline(always)]
fn sort_far_to_near(pushed: &mut [Entry]) {
    for i in 1..pushed.len() {
        let mut at = i;
        while at > 0 && pushed[at - 1].t < pushed[at].t {
            pushed.swap(at - 1, at);
            at -= 1;
        }
    }
}

/// A child waiting on the stack of [`walk_wide`], with its entry `t`.
#[derive(Clone, Copy, Debug)]
struct Entry {
    child: ChildRef,
    t: f32,
}
