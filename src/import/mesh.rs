//! One glTF mesh → one [`scene::Mesh`]: the primitives' vertices are
//! concatenated, their triangles re-indexed into the merged vertex list, and
//! each triangle keeps its primitive's material. The renderer then builds one
//! acceleration structure per mesh instead of one per primitive.

use glam::{Vec2, Vec3};
use gltf::mesh::{Mode, Semantic};

use super::accessor::Use;
use super::error::Fault;
use super::{morph, normals, skin, topology};
use crate::scene;

/// Imports `mesh`; primitives without a material get `default_material`.
pub fn import(
    mesh: &gltf::Mesh,
    buffers: &[Vec<u8>],
    default_material: u32,
) -> Result<scene::Mesh, Fault> {
    let mut merged = scene::Mesh {
        name: mesh.name().map(str::to_owned),
        ..scene::Mesh::default()
    };
    let mut first = true;
    for primitive in mesh.primitives() {
        let material = primitive
            .material()
            .index()
            .map_or(default_material, |index| index as u32);
        if let Some(part) = read_primitive(mesh.index(), &primitive, buffers)? {
            append(
                &mut merged,
                part,
                material,
                first,
                (mesh.index(), primitive.index()),
            )?;
            first = false;
        }
    }
    if !merged.uvs.is_empty() {
        merged.uvs.resize(merged.positions.len(), Vec2::ZERO);
    }
    skin::normalize(&mut merged.joint_sets);
    merged.morph_weights = morph::mesh_weights(mesh, merged.morph_targets.len())?;
    Ok(merged)
}

/// One primitive's geometry, indices local to it.
struct Part {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    uvs: Option<Vec<Vec2>>,
    triangles: Vec<[u32; 3]>,
    joint_sets: Vec<scene::JointSet>,
    morph_targets: Vec<scene::MorphTarget>,
}

fn read_primitive(
    mesh: usize,
    primitive: &gltf::Primitive,
    buffers: &[Vec<u8>],
) -> Result<Option<Part>, Fault> {
    let p = primitive.index();
    let fault = |problem: String| Fault::Primitive {
        mesh,
        primitive: p,
        problem,
    };
    let mode = primitive.mode();
    if matches!(
        mode,
        Mode::Points | Mode::Lines | Mode::LineLoop | Mode::LineStrip
    ) {
        log::warn!("mesh {mesh} primitive {p}: skipping {mode:?}; only triangles are rendered");
        return Ok(None);
    }
    let attribute = |semantic: Semantic, name: &str| {
        primitive
            .get(&semantic)
            .map(|accessor| (accessor, format!("{name} of mesh {mesh} primitive {p}")))
    };
    let (accessor, usage) = attribute(Semantic::Positions, "POSITION")
        .ok_or_else(|| fault("has no POSITION attribute".to_owned()))?;
    let positions: Vec<Vec3> = Use {
        accessor: &accessor,
        usage: &usage,
    }
    .vectors::<3>(buffers)?
    .into_iter()
    .map(Vec3::from)
    .collect();
    let vertex_count = positions.len();
    let same_count = |name: &str, count: usize| {
        if count == vertex_count {
            Ok(())
        } else {
            Err(fault(format!(
                "{name} has {count} elements but POSITION has {vertex_count}"
            )))
        }
    };

    let indices = match primitive.indices() {
        Some(accessor) => {
            let usage = format!("indices of mesh {mesh} primitive {p}");
            Use {
                accessor: &accessor,
                usage: &usage,
            }
            .indices(buffers, vertex_count)?
        }
        None => {
            let count = u32::try_from(vertex_count)
                .map_err(|_| fault(format!("has {vertex_count} vertices, too many to index")))?;
            (0..count).collect()
        }
    };
    if mode == Mode::Triangles && indices.len() % 3 != 0 {
        log::warn!(
            "mesh {mesh} primitive {p}: {} indices is not a multiple of 3; the last {} are ignored",
            indices.len(),
            indices.len() % 3
        );
    }
    let triangles = topology::triangles(mode, &indices).unwrap_or_default();

    let normals = match attribute(Semantic::Normals, "NORMAL") {
        Some((accessor, usage)) => {
            let normals = Use {
                accessor: &accessor,
                usage: &usage,
            }
            .vectors::<3>(buffers)?;
            same_count("NORMAL", normals.len())?;
            normals
                .into_iter()
                .map(|normal| Vec3::from(normal).normalize_or(Vec3::Z))
                .collect()
        }
        None => normals::area_weighted(&positions, &triangles),
    };
    let uvs = match attribute(Semantic::TexCoords(0), "TEXCOORD_0") {
        Some((accessor, usage)) => {
            let uvs = Use {
                accessor: &accessor,
                usage: &usage,
            }
            .vectors::<2>(buffers)?;
            same_count("TEXCOORD_0", uvs.len())?;
            Some(uvs.into_iter().map(Vec2::from).collect())
        }
        None => None,
    };
    Ok(Some(Part {
        joint_sets: skin::joint_sets(mesh, primitive, buffers, vertex_count)?,
        morph_targets: morph::targets(mesh, primitive, buffers, vertex_count)?,
        positions,
        normals,
        uvs,
        triangles,
    }))
}

/// Appends a primitive's part; `first` says no other primitive has been
/// appended yet, `(mesh, primitive)` name it in errors.
fn append(
    merged: &mut scene::Mesh,
    part: Part,
    material: u32,
    first: bool,
    (mesh, primitive): (usize, usize),
) -> Result<(), Fault> {
    let base = merged.positions.len();
    let added = part.positions.len();
    if u32::try_from(base + part.positions.len()).is_err() {
        return Err(Fault::Primitive {
            mesh,
            primitive,
            problem: "the merged mesh has more vertices than 32-bit indices reach".to_owned(),
        });
    }
    let offset = base as u32;
    morph::append_targets(
        &mut merged.morph_targets,
        part.morph_targets,
        base,
        added,
        first,
    )
    .map_err(|problem| Fault::Primitive {
        mesh,
        primitive,
        problem,
    })?;
    skin::append_joint_sets(&mut merged.joint_sets, base, part.joint_sets, added);
    if let Some(uvs) = part.uvs {
        // Earlier primitives without UVs get zeros, so `uvs` stays parallel
        // to `positions`.
        merged.uvs.resize(base, Vec2::ZERO);
        merged.uvs.extend(uvs);
    }
    merged.positions.extend(part.positions);
    merged.normals.extend(part.normals);
    merged
        .triangle_materials
        .extend(std::iter::repeat_n(material, part.triangles.len()));
    merged.triangles.extend(
        part.triangles
            .into_iter()
            .map(|triangle| triangle.map(|index| index + offset)),
    );
    Ok(())
}
