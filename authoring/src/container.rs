//! The three ways a [`GltfBuilder`] leaves memory: `.gltf` with the buffer
//! embedded as base64, `.gltf` beside an external `.bin`, and binary `.glb`.
//! All files are written atomically.

use std::io::Write;
use std::path::Path;

use base64::Engine;
use serde_json::{json, Map, Value};

use lmanim::output::{write_atomically, OutputError};

use super::json::LIGHTS_PUNCTUAL;
use super::{AuthoringError, GltfBuilder};

/// GLB header and chunk type magic numbers (glTF 2.0 spec, "GLB File
/// Format Specification").
const GLB_MAGIC: u32 = 0x4654_6C67;
const GLB_VERSION: u32 = 2;
const CHUNK_JSON: u32 = 0x4E4F_534A;
const CHUNK_BIN: u32 = 0x004E_4942;

/// Where the binary buffer lives, which decides its `uri`.
enum BufferUri<'a> {
    /// A `data:` URI holding the buffer in base64.
    Embedded,
    /// A file beside the `.gltf`, by its (already URI-encoded) name.
    External(&'a str),
    /// The GLB's BIN chunk: no URI.
    Glb,
}

impl GltfBuilder {
    /// The glTF JSON with the buffer embedded as base64: one self-contained
    /// file, handy for small test scenes.
    pub fn to_embedded_json(&self) -> Value {
        self.document(BufferUri::Embedded)
    }

    /// The bytes of a binary `.glb`.
    pub fn to_glb(&self) -> Vec<u8> {
        let mut json = self.document(BufferUri::Glb).to_string().into_bytes();
        json.resize(json.len().next_multiple_of(4), b' ');
        let mut bin = self.buffer.clone();
        bin.resize(bin.len().next_multiple_of(4), 0);
        let chunk_header = 8;
        let mut total = 12 + chunk_header + json.len();
        if !bin.is_empty() {
            total += chunk_header + bin.len();
        }
        let mut glb = Vec::with_capacity(total);
        // Sizes are u32 by the format; a scene near 4 GiB is not a test scene.
        for word in [
            GLB_MAGIC,
            GLB_VERSION,
            total as u32,
            json.len() as u32,
            CHUNK_JSON,
        ] {
            glb.extend_from_slice(&word.to_le_bytes());
        }
        glb.extend_from_slice(&json);
        if !bin.is_empty() {
            glb.extend_from_slice(&(bin.len() as u32).to_le_bytes());
            glb.extend_from_slice(&CHUNK_BIN.to_le_bytes());
            glb.extend_from_slice(&bin);
        }
        glb
    }

    /// Writes a `.gltf` with the buffer embedded.
    pub fn write_gltf(&self, path: &Path) -> Result<(), AuthoringError> {
        write_bytes(path, self.to_embedded_json().to_string().as_bytes())
    }

    /// Writes a `.gltf` and its buffer as a `.bin` of the same stem beside
    /// it (the `.bin` first, so the `.gltf` never points at a missing file).
    pub fn write_gltf_with_bin(&self, path: &Path) -> Result<(), AuthoringError> {
        let bin_path = path.with_extension("bin");
        let bin_name = bin_path
            .file_name()
            .map(|name| encode_uri_component(&name.to_string_lossy()))
            .unwrap_or_default();
        if !self.buffer.is_empty() {
            write_bytes(&bin_path, &self.buffer)?;
        }
        let json = self.document(BufferUri::External(&bin_name));
        write_bytes(path, json.to_string().as_bytes())
    }

    /// Writes a binary `.glb`.
    pub fn write_glb(&self, path: &Path) -> Result<(), AuthoringError> {
        write_bytes(path, &self.to_glb())
    }

    /// The whole glTF document. Empty arrays are left out, as the spec
    /// requires (`minItems: 1`).
    fn document(&self, uri: BufferUri) -> Value {
        let mut root = Map::new();
        root.insert(
            "asset".into(),
            json!({ "version": "2.0", "generator": "lmanim authoring" }),
        );
        if !self.extensions_used.is_empty() {
            root.insert("extensionsUsed".into(), json!(self.extensions_used));
        }
        // A scene without nodes is legal glTF, but the `gltf` crate
        // refuses it; a builder without nodes writes no scene at all.
        let roots = self.roots();
        if !roots.is_empty() {
            root.insert("scene".into(), json!(0));
            root.insert("scenes".into(), json!([{ "nodes": roots }]));
        }
        let arrays = [
            ("nodes", &self.nodes),
            ("meshes", &self.meshes),
            ("materials", &self.materials),
            ("cameras", &self.cameras),
            ("skins", &self.skins),
            ("animations", &self.animations),
            ("accessors", &self.accessors),
            ("bufferViews", &self.buffer_views),
        ];
        for (key, items) in arrays {
            if !items.is_empty() {
                root.insert(key.into(), json!(items));
            }
        }
        if !self.buffer.is_empty() {
            let mut buffer = json!({ "byteLength": self.buffer.len() });
            match uri {
                BufferUri::Embedded => {
                    let data = base64::engine::general_purpose::STANDARD.encode(&self.buffer);
                    buffer["uri"] = json!(format!("data:application/octet-stream;base64,{data}"));
                }
                BufferUri::External(name) => buffer["uri"] = json!(name),
                BufferUri::Glb => {}
            }
            root.insert("buffers".into(), json!([buffer]));
        }
        if !self.lights.is_empty() {
            root.insert(
                "extensions".into(),
                json!({ LIGHTS_PUNCTUAL: { "lights": self.lights } }),
            );
        }
        Value::Object(root)
    }
}

fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), AuthoringError> {
    write_atomically(path, |writer| {
        writer
            .write_all(bytes)
            .map_err(|source| OutputError::Write {
                path: path.to_path_buf(),
                source,
            })
    })?;
    Ok(())
}

/// Percent-encodes a file name for a relative URI (RFC 3986: everything but
/// unreserved characters), so names with spaces resolve.
fn encode_uri_component(name: &str) -> String {
    name.bytes()
        .map(|b| match b {
            b'A'..=b'Z' | b'a'..=b'z' | b'0'..=b'9' | b'-' | b'.' | b'_' | b'~' => {
                (b as char).to_string()
            }
            _ => format!("%{b:02X}"),
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn uri_components_escape_reserved_bytes() {
        assert_eq!(encode_uri_component("scene.bin"), "scene.bin");
        assert_eq!(encode_uri_component("my scene#1.bin"), "my%20scene%231.bin");
    }

    #[test]
    fn an_empty_builder_is_a_minimal_document() {
        let json = GltfBuilder::new().to_embedded_json();
        assert_eq!(json["asset"]["version"], "2.0");
        assert!(json.get("buffers").is_none());
        assert!(gltf::Gltf::from_slice(json.to_string().as_bytes()).is_ok());
        let glb = GltfBuilder::new().to_glb();
        assert_eq!(glb.len() % 4, 0);
        assert!(gltf::Gltf::from_slice(&glb).is_ok());
    }
}
