//! `lmanim bake-camera`: a scene written back with a camera path as an
//! ordinary glTF camera node and animation clip, so Blender, three.js and
//! lmanim play the same shot. The renderer has no glTF writer (that is
//! `authoring/`'s), so the input's own JSON is extended: one root node
//! carrying a new perspective camera, one buffer (a data URI) holding the
//! keys, its views and accessors, and one clip. Keys are the path's poses
//! at every frame time f / fps up to its end (and at its end), LINEAR, so
//! a player that samples at the frames shows the spline's poses exactly
//! (to f32). A field of view that changes along the path is keyed through
//! KHR_animation_pointer. The input's buffers and images are embedded
//! (`import::self_contained_json`), so the output stands alone anywhere.

use std::path::{Path, PathBuf};

use base64::Engine;
use serde_json::{json, Value};

use super::CameraPath;
use crate::import::{self, ImportError};
use crate::output::{self, OutputError};

/// The name given to the baked camera and its node and clip (with a
/// number appended where the scene already uses it).
pub const CAMERA_NAME: &str = "camera-path";

const FLOAT: u32 = 5126;
const POINTER: &str = "KHR_animation_pointer";

#[derive(Debug, thiserror::Error)]
pub enum BakeError {
    #[error(transparent)]
    Import(#[from] ImportError),
    #[error("--out {}: bake-camera writes a .gltf file (JSON with embedded data)", .0.display())]
    OutNotGltf(PathBuf),
    #[error(transparent)]
    Output(#[from] OutputError),
}

impl BakeError {
    pub fn is_bad_input(&self) -> bool {
        matches!(self, BakeError::Import(_) | BakeError::OutNotGltf(_))
    }
}

/// Writes `scene` with `path` baked in (keys at `fps`) to `out`,
/// atomically. Returns the name the camera got.
pub fn bake(scene: &Path, path: &CameraPath, fps: f64, out: &Path) -> Result<String, BakeError> {
    let is_gltf = out
        .extension()
        .is_some_and(|ext| ext.eq_ignore_ascii_case("gltf"));
    if !is_gltf {
        return Err(BakeError::OutNotGltf(out.to_path_buf()));
    }
    let mut json = import::self_contained_json(scene)?;
    let name = unique_name(&json);
    add_camera(&mut json, &Keys::sample(path, fps), &name);
    output::write_atomically(out, |file| {
        serde_json::to_writer(file, &json).map_err(|error| OutputError::Write {
            path: out.to_path_buf(),
            source: error.into(),
        })
    })?;
    Ok(name)
}

/// The path's poses at the key times, as glTF stores them.
struct Keys {
    times: Vec<f32>,
    translations: Vec<[f32; 3]>,
    /// x, y, z, w; each on the same side as the one before, so LINEAR
    /// (a slerp) turns the short way.
    rotations: Vec<[f32; 4]>,
    yfovs: Vec<f32>,
}

impl Keys {
    /// Every frame time f / fps from 0 until the path's end, and the end.
    fn sample(path: &CameraPath, fps: f64) -> Keys {
        let mut times: Vec<f64> = (0u64..)
            .map(|frame| frame as f64 / fps)
            .take_while(|&time| time < path.end())
            .collect();
        if times
            .last()
            .is_none_or(|&last| (last as f32) < path.end() as f32)
        {
            times.push(path.end().max(0.0));
        }
        // Each key holds the pose at its own time as stored (f32), so a
        // player's frame time, which rounds differently, lands within a
        // linear step of the curve rather than a rounding step behind it.
        let times: Vec<f32> = times.iter().map(|&time| time as f32).collect();
        let poses: Vec<_> = (times.iter())
            .map(|&time| path.pose_at(f64::from(time)))
            .collect();
        let mut rotations: Vec<[f32; 4]> = Vec::with_capacity(poses.len());
        for pose in &poses {
            let mut rotation = pose.rotation.normalize().as_quat();
            if let Some(&[x, y, z, w]) = rotations.last() {
                if rotation.dot(glam::Quat::from_xyzw(x, y, z, w)) < 0.0 {
                    rotation = -rotation;
                }
            }
            rotations.push(rotation.to_array());
        }
        Keys {
            times,
            translations: poses
                .iter()
                .map(|p| p.position.as_vec3().to_array())
                .collect(),
            rotations,
            yfovs: poses.iter().map(|p| p.yfov as f32).collect(),
        }
    }

    /// Whether the field of view changes along the path (and so needs a
    /// pointer channel).
    fn zooms(&self) -> bool {
        self.yfovs.iter().any(|&yfov| yfov != self.yfovs[0])
    }
}

/// Adds the camera, its node (a root of the default scene), the keys'
/// buffer, views and accessors, and the clip to `json`.
fn add_camera(json: &mut Value, keys: &Keys, name: &str) {
    let mut data = Vec::new();
    let mut columns: Vec<(&str, Vec<f32>)> = vec![
        ("SCALAR", keys.times.clone()),
        ("VEC3", keys.translations.concat()),
        ("VEC4", keys.rotations.concat()),
    ];
    if keys.zooms() {
        columns.push(("SCALAR", keys.yfovs.clone()));
    }
    let buffer = array(json, "buffers").len();
    let first_view = array(json, "bufferViews").len();
    let first_accessor = array(json, "accessors").len();
    for (index, (kind, values)) in columns.iter().enumerate() {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        array(json, "bufferViews").push(json!({
            "buffer": buffer, "byteOffset": data.len(), "byteLength": bytes.len(),
        }));
        let mut accessor = json!({
            "bufferView": first_view + index, "componentType": FLOAT,
            "count": keys.times.len(), "type": kind,
        });
        if index == 0 {
            // Animation inputs must carry their bounds.
            accessor["min"] = json!([keys.times[0]]);
            accessor["max"] = json!([keys.times[keys.times.len() - 1]]);
        }
        array(json, "accessors").push(accessor);
        data.extend(bytes);
    }
    let encoded = base64::engine::general_purpose::STANDARD.encode(&data);
    array(json, "buffers").push(json!({
        "name": name, "byteLength": data.len(),
        "uri": format!("data:application/octet-stream;base64,{encoded}"),
    }));

    let camera = array(json, "cameras").len();
    array(json, "cameras").push(json!({
        "name": name, "type": "perspective",
        "perspective": { "yfov": keys.yfovs[0], "znear": super::ZNEAR },
    }));
    let node = array(json, "nodes").len();
    array(json, "nodes").push(json!({
        "name": name, "camera": camera,
        "translation": keys.translations[0], "rotation": keys.rotations[0],
    }));
    let scene = json["scene"].as_u64().unwrap_or(0) as usize;
    if let Some(scene) = json["scenes"].get_mut(scene) {
        let roots = scene
            .as_object_mut()
            .map(|s| s.entry("nodes").or_insert(json!([])));
        if let Some(Value::Array(roots)) = roots {
            roots.push(json!(node));
        }
    }

    let sampler = |output: usize| {
        json!({
            "input": first_accessor, "output": first_accessor + output, "interpolation": "LINEAR",
        })
    };
    let mut samplers = vec![sampler(1), sampler(2)];
    let mut channels = vec![
        json!({ "sampler": 0, "target": { "node": node, "path": "translation" } }),
        json!({ "sampler": 1, "target": { "node": node, "path": "rotation" } }),
    ];
    if keys.zooms() {
        samplers.push(sampler(3));
        let mut extensions = serde_json::Map::new();
        let pointer = format!("/cameras/{camera}/perspective/yfov");
        extensions.insert(POINTER.to_owned(), json!({ "pointer": pointer }));
        channels.push(json!({ "sampler": 2, "target": {
            "path": "pointer", "extensions": extensions,
        } }));
        let used = array(json, "extensionsUsed");
        if !used.iter().any(|e| e == POINTER) {
            used.push(json!(POINTER));
        }
    }
    array(json, "animations").push(json!({
        "name": name, "samplers": samplers, "channels": channels,
    }));
}

/// The top-level array `key` of `json`, made empty where the file has none.
fn array<'a>(json: &'a mut Value, key: &str) -> &'a mut Vec<Value> {
    let slot = &mut json[key];
    if !slot.is_array() {
        *slot = json!([]);
    }
    match slot {
        Value::Array(items) => items,
        _ => unreachable!("made an array above"),
    }
}

/// [`CAMERA_NAME`], or with the first number that no node, camera or
/// clip of `json` is named already, so `--camera` finds the baked one.
fn unique_name(json: &Value) -> String {
    let taken = |name: &str| {
        ["nodes", "cameras", "animations"].iter().any(|key| {
            let items = json[*key].as_array().into_iter().flatten();
            items.into_iter().any(|item| item["name"] == name)
        })
    };
    (1..)
        .map(|n| match n {
            1 => CAMERA_NAME.to_owned(),
            n => format!("{CAMERA_NAME}-{n}"),
        })
        .find(|name| !taken(name))
        .expect("some number is free")
}
