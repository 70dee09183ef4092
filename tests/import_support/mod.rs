//! glTF files written by the import tests themselves: a binary buffer built
//! accessor by accessor, and the three ways to store it (data URI, external
//! .bin, .glb). No binary fixtures live in the repository.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

/// glTF component types.
pub const F32: u32 = 5126;
pub const U8: u32 = 5121;
pub const U16: u32 = 5123;
pub const U32: u32 = 5125;

/// A binary buffer and the buffer views and accessors that read it.
#[derive(Default)]
pub struct Bin {
    pub bytes: Vec<u8>,
    pub views: Vec<Value>,
    pub accessors: Vec<Value>,
}

impl Bin {
    /// Appends `data` as a buffer view and an accessor over all of it;
    /// returns the accessor's index. `extra` is merged into the accessor.
    pub fn add(
        &mut self,
        data: &[u8],
        component: u32,
        kind: &str,
        count: usize,
        extra: Value,
    ) -> usize {
        let view = self.view(data);
        let mut accessor = json!({
            "bufferView": view,
            "componentType": component,
            "type": kind,
            "count": count,
        });
        if let (Some(accessor), Value::Object(extra)) = (accessor.as_object_mut(), extra) {
            accessor.extend(extra);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Appends `data` as a buffer view (4-byte aligned); returns its index.
    pub fn view(&mut self, data: &[u8]) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.views.push(json!({
            "buffer": 0,
            "byteOffset": self.bytes.len(),
            "byteLength": data.len(),
        }));
        self.bytes.extend_from_slice(data);
        self.views.len() - 1
    }

    /// VEC3 floats with the min/max that POSITION accessors must carry.
    pub fn vec3(&mut self, data: &[[f32; 3]]) -> usize {
        let mut min = [f32::MAX; 3];
        let mut max = [f32::MIN; 3];
        for v in data {
            for axis in 0..3 {
                // NaN and infinities stay out of the JSON, which cannot hold them.
                if v[axis].is_finite() {
                    min[axis] = min[axis].min(v[axis]);
                    max[axis] = max[axis].max(v[axis]);
                }
            }
        }
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        self.add(
            &bytes,
            F32,
            "VEC3",
            data.len(),
            json!({ "min": min, "max": max }),
        )
    }

    pub fn vec2(&mut self, data: &[[f32; 2]]) -> usize {
        let bytes: Vec<u8> = data
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        self.add(&bytes, F32, "VEC2", data.len(), json!({}))
    }

    pub fn scalars(&mut self, data: &[f32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let min = data.iter().copied().fold(f32::MAX, f32::min);
        let max = data.iter().copied().fold(f32::MIN, f32::max);
        self.add(
            &bytes,
            F32,
            "SCALAR",
            data.len(),
            json!({ "min": [min], "max": [max] }),
        )
    }

    pub fn indices_u8(&mut self, data: &[u8]) -> usize {
        self.add(data, U8, "SCALAR", data.len(), json!({}))
    }

    pub fn indices_u16(&mut self, data: &[u16]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.add(&bytes, U16, "SCALAR", data.len(), json!({}))
    }

    pub fn indices_u32(&mut self, data: &[u32]) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        self.add(&bytes, U32, "SCALAR", data.len(), json!({}))
    }

    /// `doc` with this buffer's views and accessors and a buffer entry
    /// `buffer` (its `uri`, or none for a .glb).
    fn into_document(mut self, mut doc: Value, buffer: Value) -> (Value, Vec<u8>) {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        let mut buffer = buffer;
        buffer["byteLength"] = json!(self.bytes.len());
        doc["buffers"] = json!([buffer]);
        doc["bufferViews"] = Value::Array(self.views);
        doc["accessors"] = Value::Array(self.accessors);
        (doc, self.bytes)
    }

    /// Makes `accessor` sparse: element `indices[i]` becomes `values[i]`.
    pub fn sparse(&mut self, accessor: usize, indices: &[u16], values: &[[f32; 3]]) {
        let index_bytes: Vec<u8> = indices.iter().flat_map(|x| x.to_le_bytes()).collect();
        let value_bytes: Vec<u8> = values
            .iter()
            .flatten()
            .flat_map(|x| x.to_le_bytes())
            .collect();
        let index_view = self.view(&index_bytes);
        let value_view = self.view(&value_bytes);
        self.accessors[accessor]["sparse"] = json!({
            "count": indices.len(),
            "indices": { "bufferView": index_view, "componentType": U16 },
            "values": { "bufferView": value_view },
        });
    }

    /// `doc` with this buffer in a data URI, its views and its accessors.
    pub fn embed(self, doc: Value) -> Value {
        let uri = format!(
            "data:application/octet-stream;base64,{}",
            base64(&self.bytes)
        );
        self.into_document(doc, json!({ "uri": uri })).0
    }

    /// Writes `dir/name` as .gltf with the buffer in a data URI.
    pub fn write_embedded(self, doc: Value, dir: &Path, name: &str) -> PathBuf {
        write_json(dir, name, &self.embed(doc))
    }

    /// Writes `dir/name` as .gltf and the buffer beside it as `bin_name`
    /// (percent-encoded in the URI, as glTF asks).
    pub fn write_external(self, doc: Value, dir: &Path, name: &str, bin_name: &str) -> PathBuf {
        let uri = bin_name.replace(' ', "%20");
        let (doc, bytes) = self.into_document(doc, json!({ "uri": uri }));
        write(dir, bin_name, &bytes);
        write_json(dir, name, &doc)
    }

    /// Writes `dir/name` as binary glTF.
    pub fn write_glb(self, doc: Value, dir: &Path, name: &str) -> PathBuf {
        let (doc, bytes) = self.into_document(doc, json!({}));
        write(
            dir,
            name,
            &glb(&serde_json::to_vec(&doc).expect("JSON"), &bytes),
        )
    }
}

/// A .glb container: header, JSON chunk (space-padded), BIN chunk.
pub fn glb(json: &[u8], bin: &[u8]) -> Vec<u8> {
    let mut json = json.to_vec();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    let length = 12 + 8 + json.len() + 8 + bin.len();
    let mut out = Vec::with_capacity(length);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(length as u32).to_le_bytes());
    out.extend_from_slice(&(json.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&json);
    out.extend_from_slice(&(bin.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(bin);
    out
}

pub fn write_json(dir: &Path, name: &str, doc: &Value) -> PathBuf {
    write(dir, name, &serde_json::to_vec_pretty(doc).expect("JSON"))
}

pub fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, bytes).expect("write test file");
    path
}

/// Standard base64 with padding (RFC 4648), for data URIs.
pub fn base64(bytes: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let word = chunk.iter().enumerate().fold(0u32, |word, (i, &byte)| {
            word | u32::from(byte) << (16 - 8 * i)
        });
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[(word >> (18 - 6 * i) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// The smallest scene: one node with one triangle mesh, in scene 0.
pub fn one_triangle_document(mesh_primitive: Value) -> Value {
    json!({
        "asset": { "version": "2.0" },
        "scene": 0,
        "scenes": [{ "nodes": [0] }],
        "nodes": [{ "mesh": 0 }],
        "meshes": [{ "primitives": [mesh_primitive] }],
    })
}

pub const TRIANGLE: [[f32; 3]; 3] = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];

#[test]
fn base64_matches_the_rfc_examples() {
    assert_eq!(base64(b""), "");
    assert_eq!(base64(b"f"), "Zg==");
    assert_eq!(base64(b"fo"), "Zm8=");
    assert_eq!(base64(b"foo"), "Zm9v");
    assert_eq!(base64(b"foobar"), "Zm9vYmFy");
}
