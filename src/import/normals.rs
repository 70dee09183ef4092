//! Vertex normals for primitives that come without them.

use glam::Vec3;

/// Area-weighted vertex normals: each triangle adds its unnormalized face
/// normal (whose length is twice its area) to its three corners, so large
/// triangles dominate slivers. Where vertices are not shared (a non-indexed
/// primitive) this gives flat shading. A vertex that touches only degenerate
/// triangles gets +Z, so that every normal is unit length.
pub fn area_weighted(positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Vec3> {
    let mut sums = vec![Vec3::ZERO; positions.len()];
    for triangle in triangles {
        let [a, b, c] = triangle.map(|index| positions[index as usize]);
        let face = (b - a).cross(c - a);
        for &index in triangle {
            sums[index as usize] += face;
        }
    }
    sums.into_iter()
        .map(|sum| sum.normalize_or(Vec3::Z))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_larger_triangle_dominates_a_shared_vertex() {
        // Two triangles share vertex 0: a big one in the XY plane (normal +Z)
        // and a small one in the XZ plane (normal +Y).
        let positions = [
            Vec3::ZERO,
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(0.0, 10.0, 0.0),
            Vec3::new(0.0, 0.0, 1.0),
            Vec3::new(1.0, 0.0, 0.0),
        ];
        let normals = area_weighted(&positions, &[[0, 1, 2], [0, 3, 4]]);
        assert!(normals[0].z > 0.99, "{:?}", normals[0]);
        assert_eq!(normals[3], Vec3::Y);
        assert!(normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-6));
    }

    #[test]
    fn degenerate_triangles_still_give_unit_normals() {
        let normals = area_weighted(&[Vec3::ZERO; 3], &[[0, 1, 2]]);
        assert_eq!(normals, vec![Vec3::Z; 3]);
    }
}
