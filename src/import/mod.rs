//! glTF 2.0 (.gltf with embedded or external buffers, .glb) → [`SceneDesc`],
//! the first stage of a run: after this, nothing in lmanim sees glTF types.
//!
//! What is imported:
//! - the whole node tree with `f64` local transforms (TRS or matrix), the
//!   default scene's roots (or the first scene's), and which nodes
//!   animation moves (`animated`) or deforms (skins, animated morph weights);
//! - meshes as triangles (TRIANGLES, and strips and fans unrolled; points and
//!   lines are skipped with a warning), all primitives of a glTF mesh merged,
//!   normals generated where missing, UV set 0;
//! - metallic-roughness materials with base-colour and emissive textures
//!   (decoded to linear RGBA), KHR_materials_transmission, _ior and
//!   _specular (its factor only); a default material is appended for primitives that
//!   name none;
//! - KHR_lights_punctual lights with `range`, and `extras.radius` (metres);
//! - perspective and orthographic cameras;
//! - animation clips (translation, rotation, scale and morph-weight
//!   channels; STEP, LINEAR and CUBICSPLINE), skins with their inverse bind
//!   matrices and every JOINTS_n/WEIGHTS_n set (weights normalised), morph
//!   targets' POSITION and NORMAL offsets and the default weights of meshes
//!   and nodes;
//! - KHR_animation_pointer channels of those node properties, of lights
//!   (colour, intensity, range, spot cone angles), of perspective cameras
//!   (`yfov`, `zfar`) and of material factors (base colour, metallic,
//!   roughness, emissive, transmission, IOR, specular). A pointer to any
//!   other property, or to an object the file lacks, skips its channel with
//!   a warning that names the file, animation, channel and pointer.
//!
//! Indices of nodes, meshes, materials, lights, cameras, skins and
//! animations are the file's.
//!
//! Not (yet) imported: morph targets' TANGENT offsets, textures other than
//! base colour and emissive, texture transforms, UV sets other than 0.
//!
//! Bad files never panic: the asset's version and every reference and
//! property the glTF crate's accessors unwrap are checked on the JSON first
//! (`asset.rs`, `channel_targets.rs`, `preflight.rs`), sizes and bounds
//! before anything is allocated or indexed (`accessor.rs`, `buffers.rs`),
//! and every fault is one [`ImportError`] line that names the file and the
//! glTF object at fault, by JSON path where a spec rule is broken
//! (`animations[0].channels[2].target.node: …`). A panic that slips
//! through anyway (a bug, here or in a dependency) is caught and reported
//! the same way, without panic text (`panic_guard.rs`).

mod accessor;
mod animation;
mod asset;
mod buffers;
mod camera;
mod channel_targets;
mod container;
mod embed;
mod error;
mod lights;
mod material;
mod mesh;
mod morph;
mod nodes;
mod normals;
mod panic_guard;
mod pointer;
mod preflight;
mod skin;
mod texture;
mod topology;
mod uri;

use std::path::Path;

pub use container::SUPPORTED_EXTENSIONS;
pub use embed::self_contained_json;
pub use error::{Fault, ImportError};

use crate::scene::SceneDesc;
use animation::Animatable;

/// Imports the glTF scene at `path`.
pub fn load(path: &Path) -> Result<SceneDesc, ImportError> {
    panic_guard::run(|| import(path)).map_err(|fault| ImportError {
        file: path.to_path_buf(),
        fault,
    })
}

fn import(path: &Path) -> Result<SceneDesc, Fault> {
    let bytes = std::fs::read(path).map_err(Fault::Read)?;
    let container = container::split(&bytes, path)?;
    let container::Parsed { document, pointers } = container::parse_document(container.json)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = buffers::load(&document, container.bin, base)?;

    let (mut nodes, roots) = nodes::import(&document)?;
    let file_materials = document.materials().len();
    let append_default = document
        .meshes()
        .flat_map(|mesh| mesh.primitives())
        .any(|primitive| primitive.material().index().is_none());
    let (materials, textures) = material::import(&document, &buffers, base, append_default)?;
    let default_material = u32::try_from(file_materials)
        .map_err(|_| Fault::Invalid(format!("{file_materials} materials are too many")))?;
    let meshes = document
        .meshes()
        .map(|gltf_mesh| mesh::import(&gltf_mesh, &buffers, default_material))
        .collect::<Result<Vec<_>, _>>()?;
    morph::check_node_weights(&nodes, |mesh| {
        meshes.get(mesh).map_or(0, |mesh| mesh.morph_targets.len())
    })?;
    let skins = skin::import(&document, &buffers)?;
    skin::check_bindings(&nodes, &meshes, &skins)?;
    let lights = lights::import(&document)?;
    let cameras = camera::import(&document)?;
    let animations = animation::import(
        &document,
        &buffers,
        &pointers,
        &Animatable {
            nodes: &nodes,
            meshes: &meshes,
            lights: &lights,
            cameras: &cameras,
            materials: file_materials,
        },
    )?;
    for skipped in &animations.skipped {
        log::warn!("{}: {skipped}", path.display());
    }
    nodes::mark_motion(&mut nodes, &animations.clips);

    Ok(SceneDesc {
        name: path
            .file_stem()
            .map(|stem| stem.to_string_lossy().into_owned())
            .unwrap_or_default(),
        nodes,
        roots,
        meshes,
        materials,
        textures,
        lights,
        cameras,
        skins,
        animations: animations.clips,
    })
}
