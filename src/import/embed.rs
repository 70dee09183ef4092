//! A glTF file's own JSON made to stand alone: every buffer and image it
//! reads from elsewhere (the GLB's BIN chunk, files beside it) embedded as
//! a base64 data URI. `lmanim bake-camera` adds its camera to this JSON and
//! writes it wherever `--out` says, so the copy must not depend on files
//! at paths relative to the input. The file is imported first, so
//! anything import refuses is refused here with the same line.

use std::path::Path;

use base64::Engine;
use serde_json::Value;

use super::error::{Fault, ImportError};
use super::{container, uri};

/// The JSON of the glTF file at `path`, with its external and GLB data
/// embedded (see the module's doc).
pub fn self_contained_json(path: &Path) -> Result<Value, ImportError> {
    super::load(path)?;
    embedded(path).map_err(|fault| ImportError {
        file: path.to_path_buf(),
        fault,
    })
}

fn embedded(path: &Path) -> Result<Value, Fault> {
    let bytes = std::fs::read(path).map_err(Fault::Read)?;
    let container = container::split(&bytes, path)?;
    let mut json: Value = serde_json::from_slice(container.json).map_err(Fault::Json)?;
    let base = path.parent().unwrap_or(Path::new("."));
    let buffers = json.get_mut("buffers").and_then(Value::as_array_mut);
    for (index, buffer) in buffers.into_iter().flatten().enumerate() {
        let length = buffer["byteLength"].as_u64().unwrap_or(0) as usize;
        let data = match buffer.get("uri").and_then(Value::as_str) {
            Some(text) if text.starts_with("data:") => continue,
            Some(text) => read(text, base, uri::Resource::Buffer)?,
            // Import checked that the BIN chunk holds byteLength bytes.
            None => container.bin.unwrap_or_default().to_vec(),
        };
        let data = data.get(..length).ok_or(Fault::BufferLength {
            buffer: index,
            declared: length,
            actual: data.len(),
        })?;
        buffer["uri"] = data_uri("application/octet-stream", data).into();
    }
    let images = json.get_mut("images").and_then(Value::as_array_mut);
    for image in images.into_iter().flatten() {
        let Some(text) = image.get("uri").and_then(Value::as_str) else {
            continue;
        };
        if !text.starts_with("data:") {
            let data = read(text, base, uri::Resource::Image)?;
            let media = match data.starts_with(b"\x89PNG") {
                true => "image/png",
                false => "image/jpeg",
            };
            image["uri"] = data_uri(media, &data).into();
        }
    }
    Ok(json)
}

fn read(text: &str, base: &Path, resource: uri::Resource) -> Result<Vec<u8>, Fault> {
    uri::read(text, base, resource).map_err(|reason| Fault::Invalid(format!("{text}: {reason}")))
}

fn data_uri(media: &str, data: &[u8]) -> String {
    let encoded = base64::engine::general_purpose::STANDARD.encode(data);
    format!("data:{media};base64,{encoded}")
}
