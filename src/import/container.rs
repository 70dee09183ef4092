//! From the file's bytes to a validated glTF document: the .glb container
//! (header and chunks), the JSON, the required extensions, and the glTF
//! crate's schema validation. KHR_animation_pointer channels, which the
//! crate refuses, are taken out of the JSON first (see `pointer.rs`).
//!
//! The .glb container is split here rather than by the glTF crate so that a
//! wrong magic or a truncated file gets a message that says so (the crate
//! would try the bytes as JSON) and so that a header length below 12 cannot
//! underflow.

use std::path::Path;

use gltf::json;

use super::error::Fault;
use super::pointer::PointerChannels;

/// Extensions lmanim honours; a file that requires any other is refused,
/// since rendering it without the extension would be wrong.
pub const SUPPORTED_EXTENSIONS: &[&str] = &[
    "KHR_lights_punctual",
    "KHR_materials_transmission",
    "KHR_materials_ior",
    "KHR_materials_specular",
    ANIMATION_POINTER,
];

const ANIMATION_POINTER: &str = "KHR_animation_pointer";

/// The JSON and the optional BIN chunk of a file.
pub struct Container<'a> {
    pub json: &'a [u8],
    pub bin: Option<&'a [u8]>,
}

const GLB_MAGIC: &[u8; 4] = b"glTF";
const GLB_HEADER: usize = 12;
const CHUNK_HEADER: usize = 8;
const CHUNK_JSON: &[u8; 4] = b"JSON";
const CHUNK_BIN: &[u8; 4] = b"BIN\0";

/// Splits `bytes` into JSON and BIN. A file is binary glTF when it starts
/// with the magic; a `.glb` that does not is reported as such rather than
/// being parsed as JSON.
pub fn split<'a>(bytes: &'a [u8], path: &Path) -> Result<Container<'a>, Fault> {
    if bytes.starts_with(GLB_MAGIC) {
        return split_glb(bytes);
    }
    let named_glb = path
        .extension()
        .is_some_and(|ext| ext.eq_ignore_ascii_case("glb"));
    if named_glb {
        let found = String::from_utf8_lossy(&bytes[..bytes.len().min(4)]).into_owned();
        return Err(Fault::GlbMagic { found });
    }
    Ok(Container {
        json: bytes,
        bin: None,
    })
}

fn split_glb(bytes: &[u8]) -> Result<Container<'_>, Fault> {
    let layout = |problem: String| Fault::GlbLayout(problem);
    if bytes.len() < GLB_HEADER {
        return Err(layout(format!(
            "is {} bytes long, shorter than its {GLB_HEADER}-byte header",
            bytes.len()
        )));
    }
    let version = read_u32(bytes, 4);
    if version != 2 {
        return Err(layout(format!(
            "has version {version}; only 2 is supported"
        )));
    }
    let length = read_u32(bytes, 8) as usize;
    if length > bytes.len() || length < GLB_HEADER {
        return Err(layout(format!(
            "header gives a length of {length} bytes but the file has {}",
            bytes.len()
        )));
    }
    let mut rest = &bytes[GLB_HEADER..length];
    let mut json = None;
    let mut bin = None;
    while !rest.is_empty() {
        if rest.len() < CHUNK_HEADER {
            return Err(layout(format!(
                "ends with {} stray bytes after its chunks",
                rest.len()
            )));
        }
        let chunk_length = read_u32(rest, 0) as usize;
        let kind = &rest[4..8];
        let body = &rest[CHUNK_HEADER..];
        if chunk_length > body.len() {
            return Err(layout(format!(
                "chunk {:?} claims {chunk_length} bytes but only {} remain",
                String::from_utf8_lossy(kind),
                body.len()
            )));
        }
        let (data, after) = body.split_at(chunk_length);
        match (kind, json.is_some()) {
            (k, false) if k == CHUNK_JSON => json = Some(data),
            (k, false) => {
                return Err(layout(format!(
                    "starts with chunk {:?}; the first chunk must be JSON",
                    String::from_utf8_lossy(k)
                )))
            }
            (k, true) if k == CHUNK_BIN && bin.is_none() => bin = Some(data),
            // The spec asks readers to skip chunks they do not know.
            _ => {}
        }
        rest = after;
    }
    let json = json.ok_or_else(|| layout("has no JSON chunk".to_owned()))?;
    Ok(Container { json, bin })
}

fn read_u32(bytes: &[u8], at: usize) -> u32 {
    let mut word = [0; 4];
    word.copy_from_slice(&bytes[at..at + 4]);
    u32::from_le_bytes(word)
}

/// A validated document and the animation channels it could not hold.
pub struct Parsed {
    pub document: gltf::Document,
    pub pointers: PointerChannels,
}

/// Parses and validates the JSON. Checks that the glTF crate's own
/// validation relies on (it indexes a primitive's POSITION accessor without a
/// bounds check) run first.
pub fn parse_document(json_bytes: &[u8]) -> Result<Parsed, Fault> {
    let (mut root, pointers): (json::Root, _) = match json::deserialize::from_slice(json_bytes) {
        Ok(root) => (root, PointerChannels::default()),
        Err(error) => without_pointer_channels(json_bytes).unwrap_or(Err(Fault::Json(error)))?,
    };
    if let Some(extension) = root
        .extensions_required
        .iter()
        .find(|name| !SUPPORTED_EXTENSIONS.contains(&name.as_str()))
    {
        return Err(Fault::UnsupportedExtension(extension.clone()));
    }
    // The crate refuses required extensions it does not implement itself;
    // lmanim reads KHR_animation_pointer apart from it (see `pointer.rs`).
    root.extensions_required
        .retain(|name| name != ANIMATION_POINTER);
    check_primitive_accessors(&root)?;
    let document = gltf::Document::from_json(root).map_err(|error| {
        // The crate's message starts with "invalid glTF:" too.
        let message = error.to_string();
        let details = message.trim_start_matches("invalid glTF:").trim();
        Fault::Invalid(details.trim_end_matches(';').to_owned())
    })?;
    Ok(Parsed { document, pointers })
}

/// The document without its KHR_animation_pointer channels, and those
/// channels; None when it has none, so that the crate's own error stands.
/// Such a channel has no `target.node`, which the glTF crate's schema
/// requires, so the whole file would otherwise be refused.
fn without_pointer_channels(
    json_bytes: &[u8],
) -> Option<Result<(json::Root, PointerChannels), Fault>> {
    let mut document: serde_json::Value = serde_json::from_slice(json_bytes).ok()?;
    let pointers = match PointerChannels::take(&mut document) {
        Ok(pointers) if pointers.is_empty() => return None,
        Ok(pointers) => pointers,
        Err(fault) => return Some(Err(fault)),
    };
    Some(
        serde_json::from_value(document)
            .map(|root| (root, pointers))
            .map_err(Fault::Json),
    )
}

fn check_primitive_accessors(root: &json::Root) -> Result<(), Fault> {
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, primitive) in mesh.primitives.iter().enumerate() {
            let references = primitive
                .attributes
                .values()
                .chain(primitive.indices.iter());
            for accessor in references {
                if accessor.value() >= root.accessors.len() {
                    return Err(Fault::Invalid(format!(
                        "mesh {m} primitive {p} names accessor {} but the file has {}",
                        accessor.value(),
                        root.accessors.len()
                    )));
                }
            }
        }
    }
    Ok(())
}
