//! The order in which the wide walk hands leaves to its visitor, on both
//! node tests. Closest-hit answers do not depend on it, but which occluder
//! an any-hit walk returns does (the fill's hints start from it), and a
//! closest-hit walk that visits far children first does needless work:
//! so the order is pinned here, one node of eight leaves at a time.

use glam::{Vec3, Vec4};

use super::{traverse_wide, NodeTestPath, Order};
use crate::accel::node_test::TraversalRay;
use crate::accel::wide::{WideBvh, WideNode};

/// Where each slot's leaf box starts along `x`: not the slot order.
const STARTS: [f32; 8] = [3.0, 1.0, 4.0, 0.0, 6.0, 2.0, 7.0, 5.0];

/// A root whose slots in `present` hold a leaf (slot `s` leads to
/// primitive slot `s`): a box `x ∈ [STARTS[s], STARTS[s] + 0.5]`,
/// `y, z ∈ [0, 1]`.
fn leaves(present: &[usize]) -> WideBvh {
    let bounds = |slot: usize, side: usize, axis: usize| {
        if !present.contains(&slot) {
            return [f32::INFINITY, f32::NEG_INFINITY][side];
        }
        match axis {
            0 => STARTS[slot] + 0.5 * side as f32,
            _ => side as f32,
        }
    };
    let node = WideNode {
        planes: std::array::from_fn(|axis| {
            std::array::from_fn(|side| {
                std::array::from_fn(|half| {
                    Vec4::from_array(std::array::from_fn(|lane| {
                        bounds(half * 4 + lane, side, axis)
                    }))
                })
            })
        }),
        child: std::array::from_fn(|slot| slot as u32),
        prim_count: std::array::from_fn(|slot| u8::from(present.contains(&slot))),
    };
    WideBvh {
        nodes: vec![node],
        depth: 1,
    }
}

/// The slots visited, in order, on each node test; `cull_after_first`
/// lowers `t_cull` to that distance at the first leaf.
fn visits(bvh: &WideBvh, ray: &TraversalRay, order: Order, cull_after_first: f32) -> Vec<usize> {
    let paths = [NodeTestPath::Portable, NodeTestPath::detect()];
    let [portable, detected] = paths.map(|path| {
        let mut seen = Vec::new();
        let visit = |slot: usize, t_cull: &mut f32| {
            if seen.is_empty() {
                *t_cull = cull_after_first;
            }
            seen.push(slot);
            true
        };
        traverse_wide(bvh, ray, order, path, f32::INFINITY, visit);
        seen
    });
    assert_eq!(portable, detected, "the node tests disagree on the order");
    portable
}

/// Along `+x`, tilted off the axes so that the AVX2 test takes it too.
fn forwards() -> TraversalRay {
    TraversalRay::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(1.0, 0.01, 0.02))
}

/// Along `-x` from beyond every box: octant 4.
fn backwards() -> TraversalRay {
    TraversalRay::new(Vec3::new(9.0, 0.5, 0.5), Vec3::new(-1.0, 0.01, 0.02))
}

#[test]
fn nearest_order_visits_leaves_by_entry_distance() {
    let all = leaves(&[0, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(
        visits(&all, &forwards(), Order::Nearest, f32::INFINITY),
        [3, 1, 5, 0, 2, 7, 4, 6]
    );
    assert_eq!(
        visits(&all, &backwards(), Order::Nearest, f32::INFINITY),
        [6, 4, 7, 2, 0, 5, 1, 3]
    );
    // Two children take their own branch; three the sort.
    let two = leaves(&[2, 6]);
    assert_eq!(
        visits(&two, &forwards(), Order::Nearest, f32::INFINITY),
        [2, 6]
    );
    assert_eq!(
        visits(&two, &backwards(), Order::Nearest, f32::INFINITY),
        [6, 2]
    );
    let three = leaves(&[1, 4, 6]);
    assert_eq!(
        visits(&three, &forwards(), Order::Nearest, f32::INFINITY),
        [1, 4, 6]
    );
    assert_eq!(
        visits(&leaves(&[5]), &forwards(), Order::Nearest, f32::INFINITY),
        [5]
    );
}

#[test]
fn nearest_order_breaks_ties_by_the_lower_slot() {
    // Slots 0 and 2 share a start along x in this copy of the layout.
    let mut bvh = leaves(&[0, 2]);
    for side in 0..2 {
        let mut planes = bvh.nodes[0].planes[0][side][0].to_array();
        planes[2] = planes[0];
        bvh.nodes[0].planes[0][side][0] = Vec4::from_array(planes);
    }
    assert_eq!(
        visits(&bvh, &forwards(), Order::Nearest, f32::INFINITY),
        [0, 2]
    );
}

#[test]
fn a_lowered_cull_distance_skips_the_farther_children_on_the_stack() {
    let all = leaves(&[0, 1, 2, 3, 4, 5, 6, 7]);
    // The first leaf, entered at t = 1, culls everything entered past 2.5.
    assert_eq!(visits(&all, &forwards(), Order::Nearest, 2.5), [3, 1]);
}

#[test]
fn octant_order_visits_leaves_by_slot_flipped_by_the_octant() {
    let all = leaves(&[0, 1, 2, 3, 4, 5, 6, 7]);
    assert_eq!(
        visits(&all, &forwards(), Order::Octant, f32::INFINITY),
        [0, 1, 2, 3, 4, 5, 6, 7]
    );
    assert_eq!(
        visits(&all, &backwards(), Order::Octant, f32::INFINITY),
        [4, 5, 6, 7, 0, 1, 2, 3]
    );
    let three = leaves(&[1, 4, 6]);
    assert_eq!(
        visits(&three, &backwards(), Order::Octant, f32::INFINITY),
        [4, 6, 1]
    );
}

/// A root whose slots 1, 4 and 6 lead to inner nodes 1, 2 and 3, which
/// hold leaves in slots {0, 5, 7}, {2, 3} and {6}; the leaf in slot `s`
/// of node `n` is primitive slot `10 n + s`. Every box spans `x ∈ [0, 8]`,
/// `y, z ∈ [0, 1]`, so both test rays enter them all.
fn two_levels() -> WideBvh {
    let node = |children: &[(usize, u32, u8)]| {
        let present = |slot: usize| children.iter().find(|&&(s, _, _)| s == slot);
        let bound = |slot: usize, side: usize, axis: usize| match present(slot) {
            None => [f32::INFINITY, f32::NEG_INFINITY][side],
            Some(_) => [0.0, [8.0, 1.0, 1.0][axis]][side],
        };
        WideNode {
            planes: std::array::from_fn(|axis| {
                std::array::from_fn(|side| {
                    std::array::from_fn(|half| {
                        Vec4::from_array(std::array::from_fn(|lane| {
                            bound(half * 4 + lane, side, axis)
                        }))
                    })
                })
            }),
            child: std::array::from_fn(|slot| present(slot).map_or(0, |&(_, to, _)| to)),
            prim_count: std::array::from_fn(|slot| present(slot).map_or(0, |&(_, _, n)| n)),
        }
    };
    let leaves = |n: u32, slots: &[usize]| {
        let children: Vec<_> = slots.iter().map(|&s| (s, 10 * n + s as u32, 1)).collect();
        node(&children)
    };
    WideBvh {
        nodes: vec![
            node(&[(1, 1, 0), (4, 2, 0), (6, 3, 0)]),
            leaves(1, &[0, 5, 7]),
            leaves(2, &[2, 3]),
            leaves(3, &[6]),
        ],
        depth: 2,
    }
}

#[test]
fn octant_order_finishes_a_subtree_before_the_next_sibling() {
    // Forwards the ranks are the slots; backwards (octant 4) they are
    // `slot ^ 4`, at the root and in every child alike.
    let bvh = two_levels();
    assert_eq!(
        visits(&bvh, &forwards(), Order::Octant, f32::INFINITY),
        [10, 15, 17, 22, 23, 36]
    );
    assert_eq!(
        visits(&bvh, &backwards(), Order::Octant, f32::INFINITY),
        [22, 23, 36, 15, 17, 10]
    );
}
