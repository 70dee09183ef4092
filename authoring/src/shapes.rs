//! Test geometry: a cuboid with flat faces, a plane and a UV sphere, with
//! normals and texture coordinates, wound counter-clockwise seen from
//! outside. Each is centred on the origin.

use std::f32::consts::{PI, TAU};

use glam::{Vec2, Vec3};

use super::Geometry;

/// The six faces of a cube as (outward normal, u, v) with u × v = normal,
/// so corners `-u-v, u-v, u+v, -u+v` run counter-clockwise seen from outside.
pub const CUBE_FACES: [(Vec3, Vec3, Vec3); 6] = [
    (Vec3::X, Vec3::Y, Vec3::Z),
    (Vec3::NEG_X, Vec3::Z, Vec3::Y),
    (Vec3::Y, Vec3::Z, Vec3::X),
    (Vec3::NEG_Y, Vec3::X, Vec3::Z),
    (Vec3::Z, Vec3::X, Vec3::Y),
    (Vec3::NEG_Z, Vec3::Y, Vec3::X),
];

/// A box with the given half extents; every face has its own four vertices
/// so that normals stay flat (hard edges).
pub fn cuboid(half_extents: Vec3) -> Geometry {
    let mut geometry = Geometry::default();
    for (normal, u, v) in CUBE_FACES {
        add_face(&mut geometry, half_extents, normal, u, v);
    }
    geometry
}

/// A horizontal rectangle in the XZ plane facing +Y, `half_size.x` by
/// `half_size.y` metres from its centre (a floor).
pub fn plane(half_size: Vec2) -> Geometry {
    let mut geometry = Geometry::default();
    let half_extents = Vec3::new(half_size.x, 0.0, half_size.y);
    add_face(&mut geometry, half_extents, Vec3::Y, Vec3::Z, Vec3::X);
    geometry
}

/// A sphere of `segments` slices around +Y and `rings` stacks from pole to
/// pole (at least 3 and 2). The seam and pole vertices are repeated so
/// that texture coordinates stay continuous; u runs around, v from the top.
pub fn uv_sphere(radius: f32, segments: u32, rings: u32) -> Geometry {
    let (segments, rings) = (segments.max(3), rings.max(2));
    let mut geometry = Geometry::default();
    for ring in 0..=rings {
        let theta = PI * ring as f32 / rings as f32;
        for segment in 0..=segments {
            let phi = TAU * segment as f32 / segments as f32;
            let normal = Vec3::new(
                theta.sin() * phi.sin(),
                theta.cos(),
                theta.sin() * phi.cos(),
            );
            geometry.positions.push(normal * radius);
            geometry.normals.push(normal);
            geometry.uvs.push(Vec2::new(
                segment as f32 / segments as f32,
                ring as f32 / rings as f32,
            ));
        }
    }
    let row = segments + 1;
    for ring in 0..rings {
        for segment in 0..segments {
            let a = ring * row + segment;
            let (b, c, d) = (a + row, a + row + 1, a + 1);
            // The pole rows would give one degenerate triangle per quad.
            if ring != 0 {
                geometry.indices.extend([a, c, d]);
            }
            if ring != rings - 1 {
                geometry.indices.extend([a, b, c]);
            }
        }
    }
    geometry
}

/// Appends one rectangular face: centre `normal * extent`, spanned by
/// `u` and `v` (unit axes with `u × v = normal`), scaled by `half_extents`.
fn add_face(geometry: &mut Geometry, half_extents: Vec3, normal: Vec3, u: Vec3, v: Vec3) {
    let centre = normal * half_extents;
    let (u, v) = (u * half_extents, v * half_extents);
    let first = geometry.positions.len() as u32;
    let corners = [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)];
    for (s, t) in corners {
        geometry.positions.push(centre + u * s + v * t);
        geometry.normals.push(normal);
        geometry
            .uvs
            .push(Vec2::new((s + 1.0) * 0.5, (1.0 - t) * 0.5));
    }
    geometry
        .indices
        .extend([first, first + 1, first + 2, first, first + 2, first + 3]);
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every triangle faces the way its vertex normals say, normals are
    /// unit length and all attributes are parallel.
    fn check(geometry: &Geometry) {
        let n = geometry.positions.len();
        assert_eq!(geometry.normals.len(), n);
        assert_eq!(geometry.uvs.len(), n);
        assert_eq!(geometry.indices.len() % 3, 0);
        for normal in &geometry.normals {
            assert!((normal.length() - 1.0).abs() < 1e-5);
        }
        for triangle in geometry.indices.chunks_exact(3) {
            let [a, b, c] = [0, 1, 2].map(|k| geometry.positions[triangle[k] as usize]);
            let face = (b - a).cross(c - a);
            assert!(face.length() > 1e-9, "degenerate triangle {triangle:?}");
            let mean: Vec3 = triangle.iter().map(|&i| geometry.normals[i as usize]).sum();
            assert!(face.dot(mean) > 0.0, "triangle {triangle:?} faces inward");
        }
    }

    #[test]
    fn cuboid_has_flat_outward_faces() {
        let cuboid = cuboid(Vec3::new(1.0, 2.0, 3.0));
        check(&cuboid);
        assert_eq!((cuboid.positions.len(), cuboid.indices.len()), (24, 36));
        let max = cuboid
            .positions
            .iter()
            .fold(Vec3::ZERO, |m, p| m.max(p.abs()));
        assert_eq!(max, Vec3::new(1.0, 2.0, 3.0));
    }

    #[test]
    fn plane_faces_up() {
        let plane = plane(Vec2::new(2.0, 1.0));
        check(&plane);
        assert!(plane
            .positions
            .iter()
            .all(|p| p.y == 0.0 && p.x.abs() == 2.0));
        assert!(plane.normals.iter().all(|&n| n == Vec3::Y));
    }

    #[test]
    fn sphere_is_round_and_closed() {
        let sphere = uv_sphere(0.5, 16, 8);
        check(&sphere);
        for p in &sphere.positions {
            assert!((p.length() - 0.5).abs() < 1e-5);
        }
        // 2 triangles per quad, minus one per quad in each pole row.
        assert_eq!(sphere.indices.len() / 3, 16 * (2 * 8 - 2));
        // Tiny inputs are raised to the smallest closed sphere.
        check(&uv_sphere(1.0, 0, 0));
    }
}
