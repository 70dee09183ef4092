//! The closest-hit walk: children by entry `t`, each waiting on the stack
//! with its `t`, so that those beyond a culling distance lowered meanwhile
//! are skipped when popped.

use super::super::node_test::BINARY_SCALE;
use super::super::wide::{ChildRef, WideBvh, WideNode};
use super::stack::UninitStack;
use super::{TraversalRay, Walk};

/// [`Order::Nearest`](super::Order::Nearest).
pub struct NearestFirst;

/// A child waiting on the stack, with its entry `t`.
#[derive(Clone, Copy, Debug)]
pub struct Entry {
    child: ChildRef,
    t: f32,
}

impl Walk for NearestFirst {
    type Entry = Entry;

    /// Each node visited pops one entry and pushes at most eight: seven
    /// per level plus one.
    fn capacity(depth: usize) -> usize {
        7 * depth + 1
    }

    /// Ranked by slot: `descend` sorts by entry `t`.
    #[inline(always)]
    fn flip(_: &TraversalRay) -> u32 {
        0
    }

    #[inline(always)]
    fn descend(
        stack: &mut UninitStack<Entry>,
        _: u32,
        node: &WideNode,
        slots: u32,
        entry: &[f32; 8],
        _: u32,
    ) -> Option<ChildRef> {
        descend_nearest_first(stack, node, slots, entry)
    }

    /// The next child on the stack that still entered within `t_cull`.
    #[inline(always)]
    fn resume(
        stack: &mut UninitStack<Entry>,
        _: &WideBvh,
        t_cull: f32,
        _: u32,
    ) -> Option<ChildRef> {
        loop {
            let Entry { child, t } = stack.pop()?;
            if t > t_cull * BINARY_SCALE {
                continue;
            }
            return Some(child);
        }
    }
}

/// Of the children of `node` the ray enters (bit per slot in `slots`),
/// returns the nearest, the lower slot on a tie, and pushes the others so
/// that they come off the stack nearest first; None when it enters none.
/// The one returned was entered within `t_cull` by the test just made, so
/// it needs no check.
#[inline(always)]
fn descend_nearest_first(
    stack: &mut UninitStack<Entry>,
    node: &WideNode,
    slots: u32,
    entry: &[f32; 8],
) -> Option<ChildRef> {
    let pushed = |slot: usize| Entry {
        child: node.child_ref(slot),
        t: entry[slot],
    };
    if slots == 0 {
        return None;
    }
    let lowest = slots.trailing_zeros() as usize;
    if slots.is_power_of_two() {
        return Some(node.child_ref(lowest));
    }
    let highest = 31 - slots.leading_zeros() as usize;
    if slots == 1 << lowest | 1 << highest {
        // Two children, the commonest case after one: the nearer is taken,
        // the lower slot on a tie, as the sort below would.
        let (near, far) = if entry[highest] < entry[lowest] {
            (highest, lowest)
        } else {
            (lowest, highest)
        };
        stack.push(pushed(far));
        return Some(node.child_ref(near));
    }
    let first = stack.len();
    let mut rest = slots;
    while rest != 0 {
        let slot = 31 - rest.leading_zeros();
        rest &= !(1 << slot);
        stack.push(pushed(slot as usize));
    }
    sort_far_to_near(stack.pushed_since(first));
    stack.pop().map(|nearest| nearest.child)
}

/// Orders a node's pushed children, pushed by descending slot, so that
/// the nearest is popped first and ties go to the lower slot; rarely more
/// than two or three.
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
