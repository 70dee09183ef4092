//! Morph targets: each primitive's POSITION and NORMAL offsets, merged per
//! mesh like the vertices, and the default weights of meshes and nodes.
//! TANGENT offsets are not imported (tangents are not).

use glam::Vec3;

use super::accessor::Use;
use super::error::Fault;
use crate::scene::{MorphTarget, Node};

/// The morph targets of one primitive, each attribute one element per
/// vertex. A target without POSITION offsets gets zeros.
pub fn targets(
    mesh: usize,
    primitive: &gltf::Primitive,
    buffers: &[Vec<u8>],
    vertex_count: usize,
) -> Result<Vec<MorphTarget>, Fault> {
    let p = primitive.index();
    primitive
        .morph_targets()
        .enumerate()
        .map(|(t, target)| {
            let read = |accessor: Option<gltf::Accessor>, name: &str| -> Result<Vec<Vec3>, Fault> {
                let Some(accessor) = accessor else {
                    return Ok(Vec::new());
                };
                let usage = format!("{name} of morph target {t} of mesh {mesh} primitive {p}");
                let offsets = Use {
                    accessor: &accessor,
                    usage: &usage,
                }
                .vectors::<3>(buffers)?;
                if offsets.len() != vertex_count {
                    return Err(Fault::Primitive {
                        mesh,
                        primitive: p,
                        problem: format!(
                            "morph target {t} {name} has {} elements but POSITION has {vertex_count}",
                            offsets.len()
                        ),
                    });
                }
                Ok(offsets.into_iter().map(Vec3::from).collect())
            };
            let mut positions = read(target.positions(), "POSITION")?;
            positions.resize(vertex_count, Vec3::ZERO);
            Ok(MorphTarget {
                positions,
                normals: read(target.normals(), "NORMAL")?,
            })
        })
        .collect()
}

/// Appends one primitive's targets (for `added` vertices) to a merged mesh
/// with `base` vertices so far. The glTF spec asks every primitive of a
/// mesh for the same number of targets; `first` says whether this is the
/// first primitive appended, which sets that number.
pub fn append_targets(
    merged: &mut Vec<MorphTarget>,
    part: Vec<MorphTarget>,
    base: usize,
    added: usize,
    first: bool,
) -> Result<(), String> {
    if first {
        *merged = part;
        return Ok(());
    }
    if part.len() != merged.len() {
        return Err(format!(
            "has {} morph targets but the mesh's first primitive has {}",
            part.len(),
            merged.len()
        ));
    }
    for (target, mut next) in merged.iter_mut().zip(part) {
        target.positions.extend(next.positions);
        // NORMAL offsets are kept when any primitive has them; the others'
        // vertices get zeros.
        if !target.normals.is_empty() || !next.normals.is_empty() {
            target.normals.resize(base, Vec3::ZERO);
            next.normals.resize(added, Vec3::ZERO);
            target.normals.extend(next.normals);
        }
    }
    Ok(())
}

/// The mesh's default weights: the file's, which must give one per target,
/// or zeros.
pub fn mesh_weights(mesh: &gltf::Mesh, targets: usize) -> Result<Vec<f32>, Fault> {
    match mesh.weights() {
        None => Ok(vec![0.0; targets]),
        Some(weights) if weights.len() == targets && weights.iter().all(|w| w.is_finite()) => {
            Ok(weights.to_vec())
        }
        Some(weights) => Err(Fault::Invalid(format!(
            "mesh {} gives {} default weights; expected {targets} finite ones, one per morph target",
            mesh.index(),
            weights.len()
        ))),
    }
}

/// Nodes' own default weights must give one finite weight per morph target
/// of the node's mesh.
pub fn check_node_weights(
    nodes: &[Node],
    targets_of_mesh: impl Fn(usize) -> usize,
) -> Result<(), Fault> {
    for (index, node) in nodes.iter().enumerate() {
        let Some(weights) = &node.weights else {
            continue;
        };
        let targets = node.mesh.map_or(0, &targets_of_mesh);
        if weights.len() != targets || !weights.iter().all(|w| w.is_finite()) {
            return Err(Fault::Invalid(format!(
                "node {index} has {} weights, but its mesh has {targets} morph targets \
                 (one finite weight per target expected)",
                weights.len()
            )));
        }
    }
    Ok(())
}
