//! Fixed spatial clusters of a dynamic object's triangles, so that a
//! deformation can say *where* the object changed, not only that it did:
//! the scheduler turns the boxes of the clusters whose vertices moved into
//! the light mesh's changed regions (ARCHITECTURE.md, "The light mesh"). A
//! swaying tree crown then invalidates the bits whose segments pass near
//! its surface, not every bit whose segment crosses its bounding box.
//!
//! Clusters are made once, from the positions the object is built with, by
//! halving the triangles at the median of the longest axis of their
//! centroids until each part holds at most [`CLUSTER_TRIANGLES`]. Median
//! halving keeps every cluster compact (each cut crosses the part's widest
//! extent) and never strands a few far-apart triangles in one group, as a
//! run of a Morton order can where the curve jumps; and being fixed, a
//! cluster's box before and after a frame bound the same triangles.

use glam::Vec3;

use super::bounds::Bounds;

/// Most triangles per cluster, for meshes of up to [`MAX_CLUSTERS`] times
/// as many. Smaller clusters hug a deformed surface more closely but give
/// the light mesh more regions to cull: on the city's swaying trees
/// (584 triangles, 19 clusters each) clusters of 16 drop 4% fewer bits
/// than 32 and of 64 5% more, while the invalidation's own cost moves the
/// other way by about as much as the fill saves or spends.
pub const CLUSTER_TRIANGLES: usize = 32;

/// Most clusters per object: larger meshes get larger clusters, so that a
/// deformed object never brings more than twice this many regions.
pub const MAX_CLUSTERS: usize = 256;

/// An object's triangles in spatially coherent clusters, each held as the
/// distinct vertices of its triangles.
#[derive(Clone, Debug)]
pub struct TriangleClusters {
    vertices: Vec<Vec<u32>>,
}

impl TriangleClusters {
    /// Clusters `triangles` (vertex indices in range of `positions`) by
    /// their centroids at `positions`.
    pub fn new(positions: &[Vec3], triangles: &[[u32; 3]]) -> TriangleClusters {
        let centroids: Vec<Vec3> = triangles
            .iter()
            .map(|triangle| {
                triangle
                    .iter()
                    .map(|&v| positions[v as usize])
                    .sum::<Vec3>()
                    / 3.0
            })
            .collect();
        let size = CLUSTER_TRIANGLES.max(triangles.len().div_ceil(MAX_CLUSTERS));
        let vertices = median_split(&centroids, size)
            .into_iter()
            .map(|members| {
                let mut vertices: Vec<u32> = members
                    .iter()
                    .flat_map(|&triangle| triangles[triangle as usize])
                    .collect();
                vertices.sort_unstable();
                vertices.dedup();
                vertices
            })
            .collect();
        TriangleClusters { vertices }
    }

    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Boxes that hold every position a triangle with a moved vertex had
    /// at `old` or has at `new`: for each cluster with a vertex whose
    /// position differs, its box at `old` and its box at `new` — merged
    /// into one when that is no larger (see [`old_and_new`]). Clusters
    /// whose vertices all stayed put give nothing: their triangles are the
    /// same triangles.
    pub fn changed(&self, old: &[Vec3], new: &[Vec3]) -> Vec<Bounds> {
        self.vertices
            .iter()
            .filter(|vertices| vertices.iter().any(|&v| old[v as usize] != new[v as usize]))
            .flat_map(|vertices| {
                let [before, after] = [old, new].map(|positions| {
                    Bounds::from_points(vertices.iter().map(|&v| positions[v as usize]))
                });
                old_and_new(before, after)
            })
            .collect()
    }
}

/// The boxes to report for a cluster that was in `before` and is in
/// `after`: their union when its surface is no larger than theirs together
/// — a cluster nudged by one frame's sway, where the union is barely
/// larger than either and halves the regions the light mesh culls — else
/// both, so that a cluster that jumped does not sweep the space between.
fn old_and_new(before: Bounds, after: Bounds) -> Vec<Bounds> {
    let union = before.union(after);
    if half_area(&union) <= half_area(&before) + half_area(&after) {
        vec![union]
    } else {
        vec![before, after]
    }
}

/// Half the surface area of a box (0 for an empty one).
fn half_area(bounds: &Bounds) -> f32 {
    if bounds.is_empty() {
        return 0.0;
    }
    let size = bounds.max - bounds.min;
    size.x * size.y + size.y * size.z + size.z * size.x
}

/// Splits the indices of `points` into parts of at most `max_part` (at
/// least one), halving each part at the median of the longest axis of its
/// points' bounds. Parts come out in the order of a depth-first walk of
/// the halvings, so neighbouring parts are near in space. Deterministic:
/// the same points give the same parts.
pub fn median_split(points: &[Vec3], max_part: usize) -> Vec<Vec<u32>> {
    let mut order: Vec<u32> = (0..points.len() as u32).collect();
    let mut parts = Vec::with_capacity(points.len().div_ceil(max_part.max(1)));
    split_into(&mut order, points, max_part.max(1), &mut parts);
    parts
}

fn split_into(items: &mut [u32], points: &[Vec3], max_part: usize, parts: &mut Vec<Vec<u32>>) {
    if items.len() <= max_part {
        if !items.is_empty() {
            parts.push(items.to_vec());
        }
        return;
    }
    let (low, high) = halve_at_median(items, points);
    split_into(low, points, max_part, parts);
    split_into(high, points, max_part, parts);
}

/// Reorders `items` (indices into `points`) so that its first half lies at
/// or below the median of the longest axis of their bounds and its second
/// half at or above, and returns the two halves: one step of a top-down
/// median split, shared by the clusters and by the light mesh's tree over
/// changed regions.
pub fn halve_at_median<'a>(
    items: &'a mut [u32],
    points: &[Vec3],
) -> (&'a mut [u32], &'a mut [u32]) {
    let bounds = Bounds::from_points(items.iter().map(|&i| points[i as usize]));
    let axis = (bounds.max - bounds.min).max_position();
    let middle = items.len() / 2;
    items.select_nth_unstable_by(middle, |&a, &b| {
        points[a as usize][axis].total_cmp(&points[b as usize][axis])
    });
    items.split_at_mut(middle)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A strip of `n` unit quads along x: two triangles per quad.
    fn strip(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let positions = (0..=n)
            .flat_map(|i| [Vec3::new(i as f32, 0.0, 0.0), Vec3::new(i as f32, 1.0, 0.0)])
            .collect();
        let triangles = (0..n)
            .flat_map(|i| {
                let [a, b, c, d] = [2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 3];
                [[a, c, d], [a, d, b]]
            })
            .collect();
        (positions, triangles)
    }

    #[test]
    fn parts_are_small_compact_and_cover_every_point_once() {
        let points: Vec<Vec3> = (0..1000)
            .map(|i| Vec3::new((i * 37 % 101) as f32, (i % 7) as f32, 0.0))
            .collect();
        let parts = median_split(&points, 32);
        let mut seen: Vec<u32> = parts.iter().flatten().copied().collect();
        seen.sort_unstable();
        assert_eq!(seen, (0..1000).collect::<Vec<u32>>());
        for part in &parts {
            assert!((16..=32).contains(&part.len()), "{}", part.len());
            let bounds = Bounds::from_points(part.iter().map(|&i| points[i as usize]));
            assert!(bounds.max.x - bounds.min.x < 10.0, "{bounds:?}");
        }
        assert_eq!(median_split(&points, 32), parts, "deterministic");
        assert!(median_split(&[], 8).is_empty());
    }

    #[test]
    fn only_clusters_with_a_moved_vertex_report_their_boxes() {
        let (rest, triangles) = strip(64);
        let clusters = TriangleClusters::new(&rest, &triangles);
        assert_eq!(clusters.len(), 4, "128 triangles in clusters of 32");
        assert!(clusters.changed(&rest, &rest).is_empty());
        // Lift the strip's last vertex a little: only the cluster from
        // x = 48 to 64 moved, and one box holds it before and after.
        let mut nudged = rest.clone();
        nudged.last_mut().unwrap().y += 0.5;
        let boxes = clusters.changed(&rest, &nudged);
        assert_eq!(boxes.len(), 1);
        assert_eq!(
            (boxes[0].min, boxes[0].max),
            (Vec3::new(48.0, 0.0, 0.0), Vec3::new(64.0, 1.5, 0.0))
        );
        // Lift the whole strip far: two boxes per cluster, none spanning
        // the space between.
        let lifted: Vec<Vec3> = rest.iter().map(|&p| p + 100.0 * Vec3::Y).collect();
        let boxes = clusters.changed(&rest, &lifted);
        assert_eq!(boxes.len(), 8);
        assert!(
            boxes.iter().all(|b| b.max.y <= 1.0 || b.min.y >= 100.0),
            "{boxes:?}"
        );
    }

    #[test]
    fn large_meshes_get_larger_clusters() {
        let (rest, triangles) = strip(4 * MAX_CLUSTERS as u32 * CLUSTER_TRIANGLES as u32);
        let clusters = TriangleClusters::new(&rest, &triangles);
        assert_eq!(clusters.len(), MAX_CLUSTERS);
    }
}
