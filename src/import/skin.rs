//! Skins: the joints and inverse bind matrices of each glTF skin, the
//! JOINTS_n/WEIGHTS_n influences of each primitive (merged and normalised
//! per mesh), and the check that every influence names a joint of the skin
//! of each node that uses the mesh.

use glam::DMat4;
use gltf::mesh::Semantic;

use super::accessor::Use;
use super::error::Fault;
use crate::scene::{JointSet, Mesh, Node, Skin};

/// Every skin of the file.
pub fn import(document: &gltf::Document, buffers: &[Vec<u8>]) -> Result<Vec<Skin>, Fault> {
    document
        .skins()
        .map(|skin| {
            let fault = |problem: String| Fault::Skin {
                skin: skin.index(),
                problem,
            };
            let joints: Vec<usize> = skin.joints().map(|joint| joint.index()).collect();
            if joints.is_empty() {
                return Err(fault("has no joints".into()));
            }
            let inverse_bind = match skin.inverse_bind_matrices() {
                Some(accessor) => {
                    let usage = format!("inverseBindMatrices of skin {}", skin.index());
                    let matrices = Use {
                        accessor: &accessor,
                        usage: &usage,
                    }
                    .matrices(buffers)?;
                    if matrices.len() < joints.len() {
                        return Err(fault(format!(
                            "has {} joints but only {} inverse bind matrices",
                            joints.len(),
                            matrices.len()
                        )));
                    }
                    matrices[..joints.len()].to_vec()
                }
                None => vec![DMat4::IDENTITY; joints.len()],
            };
            Ok(Skin {
                name: skin.name().map(str::to_owned),
                joints,
                inverse_bind,
                skeleton: skin.skeleton().map(|node| node.index()),
            })
        })
        .collect()
}

/// The JOINTS_n/WEIGHTS_n pairs of one primitive, n = 0, 1, … until a
/// pair is missing. Each pair must be complete and hold one element per
/// vertex.
pub fn joint_sets(
    mesh: usize,
    primitive: &gltf::Primitive,
    buffers: &[Vec<u8>],
    vertex_count: usize,
) -> Result<Vec<JointSet>, Fault> {
    let p = primitive.index();
    let fault = |problem: String| Fault::Primitive {
        mesh,
        primitive: p,
        problem,
    };
    let mut sets = Vec::new();
    for n in 0u32.. {
        let (joints, weights) = match (
            primitive.get(&Semantic::Joints(n)),
            primitive.get(&Semantic::Weights(n)),
        ) {
            (None, None) => break,
            (Some(joints), Some(weights)) => (joints, weights),
            (Some(_), None) => return Err(fault(format!("has JOINTS_{n} without WEIGHTS_{n}"))),
            (None, Some(_)) => return Err(fault(format!("has WEIGHTS_{n} without JOINTS_{n}"))),
        };
        let usage = |name: &str| format!("{name}_{n} of mesh {mesh} primitive {p}");
        let set = JointSet {
            joints: Use {
                accessor: &joints,
                usage: &usage("JOINTS"),
            }
            .joints(buffers)?,
            weights: Use {
                accessor: &weights,
                usage: &usage("WEIGHTS"),
            }
            .weights(buffers)?,
        };
        for (name, count) in [("JOINTS", set.joints.len()), ("WEIGHTS", set.weights.len())] {
            if count != vertex_count {
                return Err(fault(format!(
                    "{name}_{n} has {count} elements but POSITION has {vertex_count}"
                )));
            }
        }
        sets.push(set);
    }
    Ok(sets)
}

/// Appends one primitive's sets (for `added` vertices) to a merged mesh
/// that has `base` vertices so far. Where one side has fewer sets, zero
/// influences fill in, which [`normalize`] then binds.
pub fn append_joint_sets(
    merged: &mut Vec<JointSet>,
    base: usize,
    part: Vec<JointSet>,
    added: usize,
) {
    let zeros = |count| JointSet {
        joints: vec![[0; 4]; count],
        weights: vec![[0.0; 4]; count],
    };
    while merged.len() < part.len() {
        merged.push(zeros(base));
    }
    let mut part = part.into_iter();
    for set in merged.iter_mut() {
        let next = part.next().unwrap_or_else(|| zeros(added));
        set.joints.extend(next.joints);
        set.weights.extend(next.weights);
    }
}

/// Scales every vertex's weights over all sets to sum to 1. A vertex whose
/// weights sum to 0 (all-zero WEIGHTS, or a primitive without JOINTS_0 in
/// a mesh whose other primitives have it) is bound wholly to the joint in
/// its first JOINTS_0 slot: it stays on the skeleton rather than collapse
/// to the origin, which a blend of zero weights would do.
pub fn normalize(sets: &mut [JointSet]) {
    let Some(vertices) = sets.first().map(|set| set.weights.len()) else {
        return;
    };
    for vertex in 0..vertices {
        let sum: f32 = sets
            .iter()
            .filter_map(|set| set.weights.get(vertex))
            .flatten()
            .sum();
        for (index, set) in sets.iter_mut().enumerate() {
            let Some(weights) = set.weights.get_mut(vertex) else {
                continue;
            };
            if sum > 0.0 {
                weights.iter_mut().for_each(|w| *w /= sum);
            } else {
                *weights = [if index == 0 { 1.0 } else { 0.0 }, 0.0, 0.0, 0.0];
            }
        }
    }
}

/// Every influence of a skinned node's mesh names a joint its skin has.
/// Checked per node, since one mesh may be used with several skins. A
/// skinned mesh without influences is drawn unskinned, with a warning.
pub fn check_bindings(nodes: &[Node], meshes: &[Mesh], skins: &[Skin]) -> Result<(), Fault> {
    for (index, node) in nodes.iter().enumerate() {
        let (Some(skin), Some(mesh)) = (node.skin, node.mesh) else {
            continue;
        };
        let (Some(skin_desc), Some(mesh_desc)) = (skins.get(skin), meshes.get(mesh)) else {
            continue;
        };
        if mesh_desc.joint_sets.is_empty() {
            // The spec requires them; without any there is nothing to
            // blend, and the mesh still has a placement of its own.
            log::warn!(
                "node {index} uses skin {skin}, but its mesh {mesh} has no JOINTS_0/WEIGHTS_0; \
                 it is drawn unskinned"
            );
            continue;
        }
        let fault = |problem: String| Fault::Skin { skin, problem };
        let limit = skin_desc.joints.len();
        for (n, set) in mesh_desc.joint_sets.iter().enumerate() {
            let past = set.joints.iter().zip(&set.weights).enumerate().find_map(
                |(vertex, (joints, weights))| {
                    let slot =
                        (0..4).find(|&i| usize::from(joints[i]) >= limit && weights[i] > 0.0)?;
                    Some((vertex, joints[slot]))
                },
            );
            if let Some((vertex, joint)) = past {
                return Err(fault(format!(
                    "node {index}'s mesh {mesh} binds vertex {vertex} to joint {joint} (JOINTS_{n}), \
                     but the skin has {limit} joints"
                )));
            }
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn weights_are_normalised_over_all_sets_and_zero_sums_bind_the_first_joint() {
        let mut sets = vec![
            JointSet {
                joints: vec![[3, 1, 0, 0], [5, 2, 0, 0]],
                weights: vec![[2.0, 1.0, 0.0, 0.0], [0.0; 4]],
            },
            JointSet {
                joints: vec![[4, 0, 0, 0], [6, 0, 0, 0]],
                weights: vec![[1.0, 0.0, 0.0, 0.0], [0.0; 4]],
            },
        ];
        normalize(&mut sets);
        assert_eq!(sets[0].weights[0], [0.5, 0.25, 0.0, 0.0]);
        assert_eq!(sets[1].weights[0], [0.25, 0.0, 0.0, 0.0]);
        assert_eq!(sets[0].weights[1], [1.0, 0.0, 0.0, 0.0]);
        assert_eq!(sets[1].weights[1], [0.0; 4]);
    }

    #[test]
    fn merging_pads_missing_sets_with_zero_influences() {
        let one = |joint| JointSet {
            joints: vec![[joint, 0, 0, 0]],
            weights: vec![[1.0, 0.0, 0.0, 0.0]],
        };
        let mut merged = Vec::new();
        append_joint_sets(&mut merged, 0, vec![one(1)], 1);
        append_joint_sets(&mut merged, 1, vec![one(2), one(3)], 1);
        append_joint_sets(&mut merged, 2, Vec::new(), 1);
        assert_eq!(merged.len(), 2);
        assert_eq!(merged[0].joints, vec![[1, 0, 0, 0], [2, 0, 0, 0], [0; 4]]);
        assert_eq!(merged[1].joints, vec![[0; 4], [3, 0, 0, 0], [0; 4]]);
        assert_eq!(merged[1].weights[0], [0.0; 4]);
    }
}
