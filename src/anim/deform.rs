//! A mesh's vertices at a pose: morph targets first (base plus weighted
//! offsets), then linear blend skinning. The renderer calls this for
//! deforming nodes when it refits their geometry for a frame.

use glam::{DMat3, DMat4, DVec3, Vec3};

use crate::scene::pose::Pose;
use crate::scene::{Mesh, SceneDesc};

/// Deformed vertex attributes, parallel to the mesh's own.
#[derive(Clone, Debug, PartialEq)]
pub struct DeformedMesh {
    pub positions: Vec<Vec3>,
    /// Unit normals.
    pub normals: Vec<Vec3>,
}

/// The mesh of `node` as `pose` deforms it, in the node's object space, so
/// that the renderer places it with `pose.world[node]` like any other mesh
/// and keeps far-away scenes precise in `f64` until then. None when the node
/// has no mesh.
///
/// A skinned mesh's world placement is the joints' alone (the glTF spec
/// ignores the skinned node's transform); it is brought into object space
/// by the inverse of the node's world transform. Where that transform is
/// singular the node renders nothing, and the joint matrices are used as
/// they are.
pub fn deformed_mesh(scene: &SceneDesc, pose: &Pose, node: usize) -> Option<DeformedMesh> {
    let scene_node = scene.nodes.get(node)?;
    let mesh = scene.meshes.get(scene_node.mesh?)?;
    let weights = pose.weights.get(node).map_or(&[][..], Vec::as_slice);
    let joints = scene_node
        .skin
        .and_then(|skin| pose.joints.get(skin))
        .filter(|_| !mesh.joint_sets.is_empty())
        .map(|joints| {
            let world = pose.world.get(node).copied().unwrap_or(DMat4::IDENTITY);
            let to_object = if world.determinant().abs() > f64::MIN_POSITIVE {
                world.inverse()
            } else {
                DMat4::IDENTITY
            };
            joints
                .iter()
                .map(|joint| to_object * *joint)
                .collect::<Vec<_>>()
        });
    Some(deform(mesh, weights, joints.as_deref()))
}

/// `mesh` with morph `weights` applied (missing weights count as 0), then
/// skinned by `joints` (joint matrices in the space the result should be
/// in) when given.
pub fn deform(mesh: &Mesh, weights: &[f32], joints: Option<&[DMat4]>) -> DeformedMesh {
    let mut positions: Vec<DVec3> = mesh.positions.iter().map(|p| p.as_dvec3()).collect();
    let mut normals: Vec<DVec3> = mesh.normals.iter().map(|n| n.as_dvec3()).collect();
    for (target, &weight) in mesh.morph_targets.iter().zip(weights) {
        if weight == 0.0 {
            continue;
        }
        let weight = f64::from(weight);
        for (position, offset) in positions.iter_mut().zip(&target.positions) {
            *position += weight * offset.as_dvec3();
        }
        for (normal, offset) in normals.iter_mut().zip(&target.normals) {
            *normal += weight * offset.as_dvec3();
        }
    }
    if let Some(joints) = joints {
        for (vertex, position) in positions.iter_mut().enumerate() {
            let blend = blended_matrix(mesh, joints, vertex);
            *position = blend.transform_point3(*position);
            if let Some(normal) = normals.get_mut(vertex) {
                *normal = normal_matrix(&blend) * *normal;
            }
        }
    }
    DeformedMesh {
        positions: positions.iter().map(|p| p.as_vec3()).collect(),
        normals: normals
            .iter()
            .map(|n| n.normalize_or(DVec3::Z).as_vec3())
            .collect(),
    }
}

/// Σ weight · joint matrix over every influence of `vertex`, in all joint
/// sets. Influences naming a joint the skin lacks are skipped (import
/// refuses them).
fn blended_matrix(mesh: &Mesh, joints: &[DMat4], vertex: usize) -> DMat4 {
    let mut blend = DMat4::ZERO;
    for set in &mesh.joint_sets {
        let (Some(indices), Some(weights)) = (set.joints.get(vertex), set.weights.get(vertex))
        else {
            continue;
        };
        for (&joint, &weight) in indices.iter().zip(weights) {
            if let (Some(matrix), true) = (joints.get(usize::from(joint)), weight != 0.0) {
                blend += *matrix * f64::from(weight);
            }
        }
    }
    blend
}

/// The inverse transpose of the matrix's linear part, which keeps normals
/// perpendicular under non-uniform scale; the linear part itself where it
/// is singular.
fn normal_matrix(matrix: &DMat4) -> DMat3 {
    let linear = DMat3::from_mat4(*matrix);
    if linear.determinant().abs() > f64::MIN_POSITIVE {
        linear.inverse().transpose()
    } else {
        linear
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{JointSet, MorphTarget};

    fn mesh() -> Mesh {
        Mesh {
            positions: vec![Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
            normals: vec![Vec3::Z, Vec3::Z],
            morph_targets: vec![MorphTarget {
                positions: vec![Vec3::new(0.0, 2.0, 0.0), Vec3::ZERO],
                normals: vec![Vec3::new(0.0, 0.0, -2.0), Vec3::ZERO],
            }],
            ..Mesh::default()
        }
    }

    #[test]
    fn morph_targets_add_weighted_offsets() {
        let deformed = deform(&mesh(), &[0.5], None);
        assert_eq!(deformed.positions[0], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(deformed.positions[1], Vec3::new(0.0, 1.0, 0.0));
        // Normal Z + 0.5 · (−2 Z) = 0: the fallback keeps it a unit vector.
        assert_eq!(deformed.normals[0], Vec3::Z);
        assert_eq!(deform(&mesh(), &[], None).positions, mesh().positions);
    }

    #[test]
    fn skinning_blends_joint_matrices_over_all_sets() {
        let mut mesh = mesh();
        // Vertex 0: half joint 0 (identity), half joint 1 (+4 x) split over
        // two sets; vertex 1: all joint 2 (scale 2 in y).
        mesh.joint_sets = vec![
            JointSet {
                joints: vec![[0, 0, 0, 0], [2, 0, 0, 0]],
                weights: vec![[0.5, 0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]],
            },
            JointSet {
                joints: vec![[1, 0, 0, 0], [0, 0, 0, 0]],
                weights: vec![[0.5, 0.0, 0.0, 0.0], [0.0; 4]],
            },
        ];
        let joints = [
            DMat4::IDENTITY,
            DMat4::from_translation(DVec3::new(4.0, 0.0, 0.0)),
            DMat4::from_scale(DVec3::new(1.0, 2.0, 1.0)),
        ];
        let deformed = deform(&mesh, &[0.0], Some(&joints));
        assert_eq!(deformed.positions[0], Vec3::new(3.0, 0.0, 0.0));
        assert_eq!(deformed.positions[1], Vec3::new(0.0, 2.0, 0.0));
        assert_eq!(deformed.normals[1], Vec3::Z);
    }
}
