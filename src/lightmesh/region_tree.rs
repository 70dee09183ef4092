//! A bounding-volume hierarchy over one frame's changed regions, for
//! invalidation: a deformed object brings a box per moved cluster of its
//! triangles, hundreds in all, and culling each group of bricks, each
//! brick, against every one of them would cost more than the bits they
//! spare. The tree lets a query descend only into the parts of space its
//! test accepts, so a brick far from every crown pays a few tests, and one
//! in a crown's shadow only for the boxes that cast it.
//!
//! Built top-down by halving at the median of the longest axis of the
//! regions' centres (as the clusters are), one region per leaf. A node's
//! box holds its children's, so any test that is conservative for a box —
//! "a segment meeting this box may start here" — is conservative for every
//! region below it.

use glam::Vec3;

use super::invalidate::ChangedRegion;
use crate::accel::clusters::halve_at_median;

#[derive(Clone, Debug)]
pub struct RegionTree {
    /// Children before their parent; the root last.
    nodes: Vec<TreeNode>,
}

#[derive(Clone, Copy, Debug)]
struct TreeNode {
    bounds: ChangedRegion,
    content: Content,
}

#[derive(Clone, Copy, Debug)]
enum Content {
    /// Index of the region in the slice the tree was built from.
    Region(usize),
    Children(usize, usize),
}

impl RegionTree {
    /// The tree over `regions`; empty ones (min above max on some axis),
    /// which nothing can meet, are left out.
    pub fn new(regions: &[ChangedRegion]) -> RegionTree {
        let mut items: Vec<u32> = (0..regions.len() as u32)
            .filter(|&i| {
                let region = &regions[i as usize];
                region.min.cmple(region.max).all()
            })
            .collect();
        let centres: Vec<Vec3> = regions.iter().map(ChangedRegion::centre).collect();
        let mut tree = RegionTree {
            nodes: Vec::with_capacity(2 * items.len()),
        };
        if !items.is_empty() {
            tree.build(&mut items, regions, &centres);
        }
        tree
    }

    /// The boxes of the nodes, by node index: a leaf's is its region's, an
    /// inner node's holds its children's. Per-node culling volumes are
    /// made from these.
    pub fn node_bounds(&self) -> impl ExactSizeIterator<Item = &ChangedRegion> {
        self.nodes.iter().map(|node| &node.bounds)
    }

    /// Whether a leaf is reached when descending only into nodes that
    /// `accept` (given a node's index) takes.
    pub fn reaches(&self, mut accept: impl FnMut(usize) -> bool) -> bool {
        let mut reached = false;
        self.descend(&mut accept, |_| {
            reached = true;
            false
        });
        reached
    }

    /// Appends to `found` the region of every leaf reached when descending
    /// only into nodes that `accept` takes.
    pub fn reached(&self, mut accept: impl FnMut(usize) -> bool, found: &mut Vec<usize>) {
        self.descend(&mut accept, |region| {
            found.push(region);
            true
        });
    }

    /// Depth-first walk from the root; `reach` gets each accepted leaf's
    /// region and says whether to go on.
    fn descend(
        &self,
        accept: &mut impl FnMut(usize) -> bool,
        mut reach: impl FnMut(usize) -> bool,
    ) {
        let Some(root) = self.nodes.len().checked_sub(1) else {
            return;
        };
        let mut stack = vec![root];
        while let Some(index) = stack.pop() {
            if !accept(index) {
                continue;
            }
            match self.nodes[index].content {
                Content::Region(region) => {
                    if !reach(region) {
                        return;
                    }
                }
                Content::Children(a, b) => stack.extend([b, a]),
            }
        }
    }

    /// Pushes the subtree over `items` (children before parents) and
    /// returns its root's index.
    fn build(&mut self, items: &mut [u32], regions: &[ChangedRegion], centres: &[Vec3]) -> usize {
        let node = if let [only] = items {
            TreeNode {
                bounds: regions[*only as usize],
                content: Content::Region(*only as usize),
            }
        } else {
            let (low, high) = halve_at_median(items, centres);
            let a = self.build(low, regions, centres);
            let b = self.build(high, regions, centres);
            let (box_a, box_b) = (self.nodes[a].bounds, self.nodes[b].bounds);
            TreeNode {
                bounds: ChangedRegion {
                    min: box_a.min.min(box_b.min),
                    max: box_a.max.max(box_b.max),
                },
                content: Content::Children(a, b),
            }
        };
        self.nodes.push(node);
        self.nodes.len() - 1
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn unit_box_at(x: f32) -> ChangedRegion {
        ChangedRegion {
            min: Vec3::new(x, 0.0, 0.0),
            max: Vec3::new(x + 1.0, 1.0, 1.0),
        }
    }

    /// Descending into the nodes whose box meets a slab finds exactly the
    /// regions that meet it, as a scan of every region does, and visits a
    /// path rather than the whole tree.
    #[test]
    fn a_query_finds_what_a_scan_finds() {
        let mut regions: Vec<ChangedRegion> =
            (0..37).map(|i| unit_box_at(i as f32 * 1.5)).collect();
        regions.push(ChangedRegion {
            min: Vec3::ONE,
            max: Vec3::ZERO,
        });
        let tree = RegionTree::new(&regions);
        let bounds: Vec<ChangedRegion> = tree.node_bounds().copied().collect();
        assert_eq!(bounds.len(), 2 * 37 - 1, "the empty region is left out");
        for (low, high) in [(10.0, 14.0), (-5.0, -1.0), (0.5, 0.6), (54.5, 60.0)] {
            let meets = |node: usize| bounds[node].min.x <= high && bounds[node].max.x >= low;
            let mut found = Vec::new();
            tree.reached(meets, &mut found);
            found.sort_unstable();
            let expected: Vec<usize> = (0..37)
                .filter(|&i| regions[i].min.x <= high && regions[i].max.x >= low)
                .collect();
            assert_eq!(found, expected, "{low}..{high}");
            assert_eq!(tree.reaches(meets), !expected.is_empty());
        }
        let mut visited = 0;
        let mut found = Vec::new();
        tree.reached(
            |node| {
                visited += 1;
                bounds[node].min.x <= 0.5
            },
            &mut found,
        );
        assert_eq!(found, [0]);
        assert!(
            visited < 16,
            "a narrow query visits a path, not the tree: {visited}"
        );
        assert!(!RegionTree::new(&[]).reaches(|_| true));
    }
}
