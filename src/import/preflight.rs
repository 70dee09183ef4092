//! Checks on the parsed glTF document, before the glTF crate validates it
//! or import reads a byte: what the crate's accessors assume without its
//! validation ever checking, and the spec's layout rules that the
//! bounds-checked reader (`accessor.rs`) cannot see.
//!
//! The crate's validation checks most references (an index past its
//! array) and enumerations; these are the ones it leaves to chance, each
//! an `unwrap` in the crate that a file could otherwise reach:
//! - a primitive's POSITION accessor, which its validation indexes;
//! - a camera whose `type` names a projection it does not have;
//! - an image with neither a `uri` nor a `bufferView`, or a `bufferView`
//!   without a `mimeType`.
//!
//! And one layout rule: a buffer view's `byteStride` is at least the size
//! of the elements an accessor reads through it (glTF 2.0 §3.6.2.4), or the
//! elements would overlap.

use gltf::json;
use gltf::json::validation::Checked;

use super::accessor::{component_name, dimensions_name};
use super::error::Fault;

/// Runs every check; the first broken rule is the error.
pub fn check(root: &json::Root) -> Result<(), Fault> {
    primitive_accessors(root)?;
    camera_projections(root)?;
    image_sources(root)?;
    strides(root)
}

fn rule(path: String, rule: String) -> Fault {
    Fault::Rule { path, rule }
}

fn primitive_accessors(root: &json::Root) -> Result<(), Fault> {
    let accessors = root.accessors.len();
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let at = format!("meshes[{m}].primitives[{p}]");
            let attributes = primitive.attributes.iter().map(|(semantic, accessor)| {
                let name = match semantic {
                    Checked::Valid(semantic) => semantic.to_string(),
                    Checked::Invalid => "?".to_owned(),
                };
                (format!("{at}.attributes.{name}"), accessor.value())
            });
            let indices = primitive
                .indices
                .iter()
                .map(|accessor| (format!("{at}.indices"), accessor.value()));
            if let Some((path, accessor)) = attributes
                .chain(indices)
                .find(|&(_, accessor)| accessor >= accessors)
            {
                return Err(rule(
                    path,
                    format!("names accessor {accessor}, but the file has {accessors}"),
                ));
            }
        }
    }
    Ok(())
}

fn camera_projections(root: &json::Root) -> Result<(), Fault> {
    use json::camera::Type;
    for (c, camera) in root.cameras.iter().enumerate() {
        let missing = match camera.type_ {
            Checked::Valid(Type::Perspective) if camera.perspective.is_none() => "perspective",
            Checked::Valid(Type::Orthographic) if camera.orthographic.is_none() => "orthographic",
            _ => continue,
        };
        return Err(rule(
            format!("cameras[{c}].{missing}"),
            format!("is missing; a camera of type \"{missing}\" must have it"),
        ));
    }
    Ok(())
}

fn image_sources(root: &json::Root) -> Result<(), Fault> {
    for (i, image) in root.images.iter().enumerate() {
        let at = format!("images[{i}]");
        match (&image.uri, &image.buffer_view, &image.mime_type) {
            (Some(_), None, _) | (None, Some(_), Some(_)) => {}
            (None, None, _) => {
                return Err(rule(
                    at,
                    "has neither a uri nor a bufferView; an image must have one".to_owned(),
                ))
            }
            (Some(_), Some(_), _) => {
                return Err(rule(
                    at,
                    "has both a uri and a bufferView; an image has one source".to_owned(),
                ))
            }
            (None, Some(_), None) => {
                return Err(rule(
                    format!("{at}.mimeType"),
                    "is missing; an image stored in a bufferView must state it".to_owned(),
                ))
            }
        }
    }
    Ok(())
}

fn strides(root: &json::Root) -> Result<(), Fault> {
    for (a, accessor) in root.accessors.iter().enumerate() {
        let (Checked::Valid(component), Checked::Valid(kind)) =
            (&accessor.component_type, &accessor.type_)
        else {
            continue; // the crate's validation names the bad enumeration
        };
        let view_index = accessor.buffer_view.map(|view| view.value());
        let view = view_index.and_then(|index| root.buffer_views.get(index).map(|v| (index, v)));
        let Some((
            v,
            json::buffer::View {
                byte_stride: Some(stride),
                ..
            },
        )) = view
        else {
            continue;
        };
        let element = component.0.size() * kind.multiplicity();
        if stride.0 < element {
            return Err(rule(
                format!("bufferViews[{v}].byteStride"),
                format!(
                    "is {}, smaller than the {element}-byte elements of accessors[{a}] \
                     ({} of {}) that read through it; elements may not overlap",
                    stride.0,
                    dimensions_name(*kind),
                    component_name(component.0)
                ),
            ));
        }
    }
    Ok(())
}
