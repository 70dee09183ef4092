//! Geometry of the city's parts: facades with recessed windows, cars and
//! trees bound to a chain of joints. Each part is built once in its own
//! object space and instanced by many nodes, which keeps a scene of
//! hundreds of thousands of triangles in a small file.

use glam::{Mat3, Mat4, Quat, Vec3};

use super::cell_noise;
use crate::{shapes, Geometry};
use lmanim::scene::JointSet;

/// Appends a planar quad whose front faces `facing`: the corners are
/// given in order around the quad, either way round.
fn push_quad(geometry: &mut Geometry, mut corners: [Vec3; 4], facing: Vec3) {
    let normal = (corners[1] - corners[0]).cross(corners[2] - corners[0]);
    if normal.dot(facing) < 0.0 {
        corners.reverse();
    }
    let base = geometry.positions.len() as u32;
    geometry.positions.extend(corners);
    geometry.normals.extend([facing.normalize(); 4]);
    geometry
        .indices
        .extend([base, base + 1, base + 2, base, base + 2, base + 3]);
}

/// Appends `part` placed by `transform`. Texture coordinates are dropped:
/// the city's materials are plain colours.
fn append(geometry: &mut Geometry, part: &Geometry, transform: Mat4) {
    let base = geometry.positions.len() as u32;
    let normal_matrix = Mat3::from_mat4(transform).inverse().transpose();
    geometry.positions.extend(
        part.positions
            .iter()
            .map(|&p| transform.transform_point3(p)),
    );
    geometry.normals.extend(
        part.normals
            .iter()
            .map(|&n| (normal_matrix * n).normalize()),
    );
    geometry
        .indices
        .extend(part.indices.iter().map(|&index| base + index));
}

/// `part` placed by `transform`, as a geometry of its own.
fn placed(part: &Geometry, transform: Mat4) -> Geometry {
    let mut geometry = Geometry::default();
    append(&mut geometry, part, transform);
    geometry
}

/// A unit box's walls (with their roof) and its window panes, apart so
/// that each gets its own material.
pub(super) struct Facade {
    pub walls: Geometry,
    pub panes: Geometry,
}

/// Window recess depth, in the unit box's units (a building 10 m deep has
/// 0.15 m recesses).
const RECESS: f32 = 0.015;

/// One wall of the unit cube, facing `normal`, spanned by `across` and +Y.
#[derive(Clone, Copy)]
struct Wall {
    normal: Vec3,
    across: Vec3,
}

impl Wall {
    fn facing(normal: Vec3) -> Wall {
        Wall {
            normal,
            across: Vec3::Y.cross(normal),
        }
    }

    /// The point `a` across and `b` up from the wall's centre, `depth`
    /// behind its surface.
    fn at(self, a: f32, b: f32, depth: f32) -> Vec3 {
        (0.5 - depth) * self.normal + a * self.across + b * Vec3::Y
    }

    /// The rectangle [a0, a1] × [b0, b1], `depth` behind the surface.
    fn rect(self, [a0, a1, b0, b1]: [f32; 4], depth: f32) -> [Vec3; 4] {
        [
            self.at(a0, b0, depth),
            self.at(a1, b0, depth),
            self.at(a1, b1, depth),
            self.at(a0, b1, depth),
        ]
    }

    /// One window cell `size` wide from (a0, b0): the frame around the
    /// window and the recess's four sides into `walls`, the pane into
    /// `panes`.
    fn add_window(self, walls: &mut Geometry, panes: &mut Geometry, a0: f32, b0: f32, size: f32) {
        let (a1, b1) = (a0 + size, b0 + size);
        let (wa0, wa1) = (a0 + 0.25 * size, a0 + 0.75 * size);
        let (wb0, wb1) = (b0 + 0.3 * size, b0 + 0.8 * size);
        for frame in [
            [a0, a1, b0, wb0],
            [a0, a1, wb1, b1],
            [a0, wa0, wb0, wb1],
            [wa1, a1, wb0, wb1],
        ] {
            push_quad(walls, self.rect(frame, 0.0), self.normal);
        }
        // The recess's sides, each facing the window's centre.
        let sides = [
            ([wa0, wb0], [wa1, wb0], Vec3::Y),
            ([wa0, wb1], [wa1, wb1], Vec3::NEG_Y),
            ([wa0, wb0], [wa0, wb1], self.across),
            ([wa1, wb0], [wa1, wb1], -self.across),
        ];
        for ([p0, q0], [p1, q1], facing) in sides {
            let corners = [
                self.at(p0, q0, 0.0),
                self.at(p1, q1, 0.0),
                self.at(p1, q1, RECESS),
                self.at(p0, q0, RECESS),
            ];
            push_quad(walls, corners, facing);
        }
        push_quad(panes, self.rect([wa0, wa1, wb0, wb1], RECESS), self.normal);
    }
}

/// The unit cube of [`shapes::cuboid`] whose four walls carry a grid of
/// `cells` × `cells` recessed windows: per window a frame of four quads,
/// four reveals and a pane, 18 triangles.
pub(super) fn facade(cells: u32) -> Facade {
    let mut walls = Geometry::default();
    let mut panes = Geometry::default();
    let size = 1.0 / cells as f32;
    for normal in [Vec3::X, Vec3::NEG_X, Vec3::Z, Vec3::NEG_Z] {
        let wall = Wall::facing(normal);
        for row in 0..cells {
            for column in 0..cells {
                let (a0, b0) = (column as f32 * size - 0.5, row as f32 * size - 0.5);
                wall.add_window(&mut walls, &mut panes, a0, b0, size);
            }
        }
    }
    let roof =
        [(-0.5, -0.5), (0.5, -0.5), (0.5, 0.5), (-0.5, 0.5)].map(|(x, z)| Vec3::new(x, 0.5, z));
    push_quad(&mut walls, roof, Vec3::Y);
    Facade { walls, panes }
}

/// A car facing +Z, standing on its origin: body, cabin and wheels apart,
/// for paint, glass and rubber.
pub(super) struct Car {
    pub body: Geometry,
    pub cabin: Geometry,
    pub wheels: Geometry,
}

pub(super) fn car() -> Car {
    let wheel = shapes::uv_sphere(0.34, 12, 8);
    let mut wheels = Geometry::default();
    for (x, z) in [(-0.85, -1.35), (0.85, -1.35), (-0.85, 1.35), (0.85, 1.35)] {
        let place = Mat4::from_scale_rotation_translation(
            Vec3::new(0.45, 1.0, 1.0),
            Quat::IDENTITY,
            Vec3::new(x, 0.34, z),
        );
        append(&mut wheels, &wheel, place);
    }
    Car {
        body: placed(
            &shapes::cuboid(Vec3::new(0.9, 0.35, 2.1)),
            Mat4::from_translation(Vec3::new(0.0, 0.65, 0.0)),
        ),
        cabin: placed(
            &shapes::cuboid(Vec3::new(0.8, 0.32, 1.1)),
            Mat4::from_translation(Vec3::new(0.0, 1.32, -0.25)),
        ),
        wheels,
    }
}

/// Heights of a tree's joints above its root: the root, the crown's base
/// and the crown's top. Each joint is the child of the one before.
pub(super) const TREE_JOINTS: [f32; 3] = [0.0, 2.2, 4.0];

/// A tree standing on its origin: trunk, crown and leaves, every vertex
/// bound to the two joints of [`TREE_JOINTS`] its height lies between.
pub(super) struct Tree {
    pub trunk: Geometry,
    pub crown: Geometry,
    pub leaves: Geometry,
}

/// Leaves scattered over the crown's surface.
const LEAVES: u32 = 160;
const CROWN_CENTRE: f32 = 4.0;
const CROWN_RADIUS: f32 = 1.3;

pub(super) fn tree() -> Tree {
    let crown_scale = Vec3::new(1.0, 1.2, 1.0);
    let mut tree = Tree {
        trunk: placed(
            &shapes::cuboid(Vec3::new(0.14, 1.6, 0.14)),
            Mat4::from_translation(Vec3::new(0.0, 1.6, 0.0)),
        ),
        crown: placed(
            &shapes::uv_sphere(CROWN_RADIUS, 14, 10),
            Mat4::from_scale_rotation_translation(
                crown_scale,
                Quat::IDENTITY,
                Vec3::new(0.0, CROWN_CENTRE, 0.0),
            ),
        ),
        leaves: leaves(crown_scale * (CROWN_RADIUS + 0.1)),
    };
    for part in [&mut tree.trunk, &mut tree.crown, &mut tree.leaves] {
        bind_to_tree_joints(part);
    }
    tree
}

/// [`LEAVES`] square leaves 0.32 m wide, scattered evenly (in direction)
/// over an ellipsoid of semi-axes `extent` around the crown's centre,
/// each facing outwards at a random twist.
fn leaves(extent: Vec3) -> Geometry {
    use std::f32::consts::TAU;
    const HALF: f32 = 0.16;
    let mut leaves = Geometry::default();
    for leaf in 0..LEAVES {
        let [u, v, w] = [11, 12, 13].map(|salt| cell_noise(leaf, 0, salt));
        let (z, phi) = (2.0 * u - 1.0, TAU * v);
        let r = (1.0 - z * z).sqrt();
        let out = Vec3::new(r * phi.cos(), z, r * phi.sin());
        let centre = Vec3::new(0.0, CROWN_CENTRE, 0.0) + out * extent;
        let tangent = Quat::from_axis_angle(out, TAU * w) * out.any_orthonormal_vector();
        let side = out.cross(tangent);
        let corners = [
            centre - HALF * tangent,
            centre + HALF * side,
            centre + HALF * tangent,
            centre - HALF * side,
        ];
        push_quad(&mut leaves, corners, out);
    }
    leaves
}

/// One influence set: each vertex blends the two joints of
/// [`TREE_JOINTS`] around its height, so the tree bends smoothly.
fn bind_to_tree_joints(geometry: &mut Geometry) {
    let [_, low, high] = TREE_JOINTS;
    let (joints, weights) = geometry
        .positions
        .iter()
        .map(|p| {
            let (below, t) = if p.y <= low {
                (0, (p.y / low).clamp(0.0, 1.0))
            } else {
                (1, ((p.y - low) / (high - low)).clamp(0.0, 1.0))
            };
            let weights = [1.0 - t, t, 0.0, 0.0];
            // Unused slots name joint 0, as glTF asks of zero weights.
            let joints = [below, below + 1, 0, 0].map(|joint| joint as u16);
            let joints =
                std::array::from_fn(|slot| if weights[slot] > 0.0 { joints[slot] } else { 0 });
            (joints, weights)
        })
        .unzip();
    geometry.joint_sets = vec![JointSet { joints, weights }];
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_facade_has_18_triangles_per_window() {
        let facade = facade(3);
        let triangles = (facade.walls.indices.len() + facade.panes.indices.len()) / 3;
        assert_eq!(triangles, 4 * 9 * 18 + 2);
        // Every vertex lies on or just inside the unit cube.
        for p in &facade.walls.positions {
            assert!(p.abs().max_element() <= 0.5 + 1e-6);
        }
    }

    #[test]
    fn tree_vertices_blend_two_neighbouring_joints() {
        let tree = tree();
        for part in [&tree.trunk, &tree.crown, &tree.leaves] {
            let set = &part.joint_sets[0];
            assert_eq!(set.joints.len(), part.positions.len());
            for (joints, weights) in set.joints.iter().zip(&set.weights) {
                assert!((weights.iter().sum::<f32>() - 1.0).abs() < 1e-6);
                for (joint, weight) in joints.iter().zip(weights) {
                    assert!(*weight > 0.0 || *joint == 0, "{joints:?} {weights:?}");
                }
            }
        }
    }
}
