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
use super::{asset, channel_targets, preflight};

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

/// Parses and validates the JSON: first as plain JSON, where the rules
/// that must hold before glTF's shape can be trusted are checked (the
/// asset's version, channel targets) and KHR_animation_pointer channels
/// are taken out; then as a glTF document, where every reference and
/// property the glTF crate's accessors assume is checked (see
/// `preflight.rs`) before the crate validates the rest.
pub fn parse_document(json_bytes: &[u8]) -> Result<Parsed, Fault> {
    let mut raw: serde_json::Value = serde_json::from_slice(json_bytes).map_err(Fault::Json)?;
    asset::check(&raw)?;
    channel_targets::check(&raw)?;
    let pointers = PointerChannels::take(&mut raw)?;
    let filled = fill_scene_nodes(&mut raw);
    // Parsing the bytes again keeps the line and column in a schema error;
    // only a document that was changed must be parsed from its value.
    let parsed = if pointers.is_empty() && !filled {
        json::deserialize::from_slice(json_bytes)
    } else {
        serde_json::from_value(raw)
    };
    let mut root: json::Root = parsed.map_err(Fault::Schema)?;
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
    preflight::check(&root)?;
    let document = gltf::Document::from_json(root).map_err(|error| {
        // The crate's message starts with "invalid glTF:" too.
        let message = error.to_string();
        let details = message.trim_start_matches("invalid glTF:").trim();
        Fault::Invalid(details.trim_end_matches(';').to_owned())
    })?;
    Ok(Parsed { document, pointers })
}

/// A scene's `nodes` is optional in glTF 2.0 (a scene may be empty), but
/// the glTF crate requires it: a scene without it gets an empty list.
/// True when some scene lacked it.
fn fill_scene_nodes(raw: &mut serde_json::Value) -> bool {
    let Some(scenes) = raw.get_mut("scenes").and_then(|s| s.as_array_mut()) else {
        return false;
    };
    let mut filled = false;
    for scene in scenes.iter_mut().filter_map(|scene| scene.as_object_mut()) {
        if !scene.contains_key("nodes") {
            scene.insert("nodes".to_owned(), serde_json::Value::Array(Vec::new()));
            filled = true;
        }
    }
    filled
}
