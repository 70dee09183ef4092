//! Bad files never panic: each file of a corpus the test writes gives an
//! `ImportError` whose one-line message names the file and the fault, both
//! from the library and from the `lmanim` binary (exit code 2, one line on
//! stderr).

mod anim_support;
mod import_support;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use serde_json::{json, Value};

use import_support::{glb, one_triangle_document, write, write_json, Bin, TRIANGLE};

/// A bad file and a word its error message must contain.
struct Case {
    path: PathBuf,
    fault_word: &'static str,
}

/// A one-triangle .gltf with the buffer embedded, after `edit` has changed
/// its document (buffers, views and accessors included).
fn triangle_with(
    dir: &Path,
    name: &str,
    positions: &[[f32; 3]],
    edit: impl FnOnce(&mut Value),
) -> PathBuf {
    let mut bin = Bin::default();
    let accessor = bin.vec3(positions);
    let mut doc = bin.embed(one_triangle_document(
        json!({ "attributes": { "POSITION": accessor } }),
    ));
    edit(&mut doc);
    write_json(dir, name, &doc)
}

fn corpus(dir: &Path) -> Vec<Case> {
    let case = |path: PathBuf, fault_word| Case { path, fault_word };
    let mut cases = vec![
        case(
            write(dir, "malformed.gltf", b"{ \"asset\": { \"version\": "),
            "JSON",
        ),
        case(write(dir, "empty.gltf", b""), "JSON"),
        case(
            write(dir, "not_a_glb.glb", b"{\"asset\":{\"version\":\"2.0\"}}"),
            "magic",
        ),
        case(dir.join("does_not_exist.gltf"), "cannot read"),
    ];

    // A .glb whose header claims more bytes than the file has, and one cut
    // inside its header.
    let json = serde_json::to_vec(&json!({ "asset": { "version": "2.0" } })).expect("JSON");
    let mut long = glb(&json, &[0; 4]);
    long[8..12].copy_from_slice(&10_000u32.to_le_bytes());
    cases.push(case(write(dir, "length_too_long.glb", &long), "length"));
    cases.push(case(
        write(dir, "cut_header.glb", b"glTF\x02\x00"),
        "header",
    ));
    let mut chunk = glb(&json, &[0; 4]);
    chunk[12..16].copy_from_slice(&5_000u32.to_le_bytes());
    cases.push(case(write(dir, "chunk_too_long.glb", &chunk), "chunk"));

    // Buffers.
    cases.push(case(
        triangle_with(dir, "missing_buffer.gltf", &TRIANGLE, |doc| {
            doc["buffers"] = json!([{ "uri": "nowhere.bin", "byteLength": 36 }]);
        }),
        "nowhere.bin",
    ));
    cases.push(case(
        triangle_with(dir, "short_buffer.gltf", &TRIANGLE, |doc| {
            let twelve_bytes = import_support::base64(&[0; 12]);
            let uri = format!("data:application/octet-stream;base64,{twelve_bytes}");
            doc["buffers"] = json!([{ "uri": uri, "byteLength": 36 }]);
        }),
        "declares 36 bytes",
    ));
    cases.push(case(
        triangle_with(dir, "view_past_buffer.gltf", &TRIANGLE, |doc| {
            doc["bufferViews"] = json!([{ "buffer": 0, "byteOffset": 24, "byteLength": 1000 }]);
        }),
        "buffer view 0 reads bytes 24..1024",
    ));

    // Accessors.
    cases.push(case(
        triangle_with(dir, "accessor_past_view.gltf", &TRIANGLE, |doc| {
            doc["accessors"][0]["count"] = json!(100);
        }),
        "reads bytes 0..1200 but buffer view 0 has 36",
    ));
    cases.push(case(
        triangle_with(dir, "gigabyte_count.gltf", &TRIANGLE, |doc| {
            doc["accessors"][0]["count"] = json!(4_000_000_000u64);
        }),
        "reads bytes",
    ));
    cases.push(case(
        triangle_with(dir, "accessor_offset_past_view.gltf", &TRIANGLE, |doc| {
            doc["accessors"][0]["byteOffset"] = json!(4);
        }),
        "reads bytes 4..40",
    ));
    cases.push(case(
        triangle_with(dir, "position_accessor_missing.gltf", &TRIANGLE, |doc| {
            doc["meshes"][0]["primitives"][0]["attributes"]["POSITION"] = json!(5);
        }),
        "accessor 5",
    ));
    cases.push(case(
        triangle_with(dir, "position_is_vec2.gltf", &TRIANGLE, |doc| {
            doc["accessors"][0]["type"] = json!("VEC2");
            doc["accessors"][0]["min"] = json!([0.0, 0.0, 0.0]);
        }),
        "VEC2 of FLOAT, expected VEC3",
    ));
    cases.push(case(indices_past_vertices(dir), "index 7"));
    let nan = [[0.0, 0.0, 0.0], [f32::NAN, 0.0, 0.0], [0.0, 1.0, 0.0]];
    cases.push(case(
        triangle_with(dir, "nan_position.gltf", &nan, |_| {}),
        "non-finite",
    ));
    cases.push(case(infinite_normal(dir), "NORMAL"));
    cases.push(case(nan_uv(dir), "TEXCOORD_0"));

    // Nodes.
    cases.push(case(
        triangle_with(dir, "infinite_translation.gltf", &TRIANGLE, |doc| {
            doc["nodes"][0]["translation"] = json!([1e39, 0.0, 0.0]);
        }),
        "transform",
    ));
    cases.push(case(
        triangle_with(dir, "cycle.gltf", &TRIANGLE, |doc| {
            doc["nodes"] = json!([{ "mesh": 0 }, { "children": [2] }, { "children": [1] }]);
        }),
        "cycle",
    ));
    cases.push(case(
        triangle_with(dir, "two_parents.gltf", &TRIANGLE, |doc| {
            doc["nodes"] = json!([{ "children": [2] }, { "children": [2] }, { "mesh": 0 }]);
            doc["scenes"] = json!([{ "nodes": [0, 1] }]);
        }),
        "two parents",
    ));
    cases.push(case(
        triangle_with(dir, "child_as_root.gltf", &TRIANGLE, |doc| {
            doc["nodes"] = json!([{ "children": [1] }, { "mesh": 0 }]);
            doc["scenes"] = json!([{ "nodes": [0, 1] }]);
        }),
        "is its parent",
    ));
    cases.push(case(
        triangle_with(dir, "no_scene.gltf", &TRIANGLE, |doc| {
            let doc = doc.as_object_mut().expect("object");
            doc.remove("scene");
            doc.remove("scenes");
        }),
        "no scene",
    ));

    // Extensions and the rest of the document.
    cases.push(case(
        triangle_with(dir, "draco.gltf", &TRIANGLE, |doc| {
            doc["extensionsUsed"] = json!(["KHR_draco_mesh_compression"]);
            doc["extensionsRequired"] = json!(["KHR_draco_mesh_compression"]);
        }),
        "KHR_draco_mesh_compression",
    ));
    cases.push(case(
        triangle_with(dir, "bad_reference.gltf", &TRIANGLE, |doc| {
            doc["nodes"][0]["mesh"] = json!(3);
        }),
        "invalid glTF",
    ));
    cases.push(case(
        triangle_with(dir, "light_reference.gltf", &TRIANGLE, |doc| {
            doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
            doc["nodes"][0]["extensions"] = json!({ "KHR_lights_punctual": { "light": 4 } });
        }),
        "invalid glTF",
    ));
    cases.push(case(
        triangle_with(dir, "camera_reference.gltf", &TRIANGLE, |doc| {
            doc["nodes"][0]["camera"] = json!(2);
        }),
        "invalid glTF",
    ));
    cases.push(case(
        triangle_with(dir, "bad_light_radius.gltf", &TRIANGLE, |doc| {
            doc["extensionsUsed"] = json!(["KHR_lights_punctual"]);
            doc["extensions"] = json!({ "KHR_lights_punctual": { "lights": [
                { "type": "point", "extras": { "radius": "big" } } ] } });
        }),
        "extras.radius",
    ));
    cases.push(case(
        triangle_with(dir, "bad_camera.gltf", &TRIANGLE, |doc| {
            doc["cameras"] = json!([{ "type": "perspective",
                "perspective": { "yfov": 0.0, "znear": 0.1 } }]);
        }),
        "yfov",
    ));
    cases.push(case(
        triangle_with(dir, "bad_image.gltf", &TRIANGLE, |doc| {
            doc["materials"] =
                json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
            doc["textures"] = json!([{ "source": 0 }]);
            doc["images"] = json!([{ "uri": "data:image/png;base64,AAAA" }]);
        }),
        "image 0",
    ));
    cases.extend(animation_cases(dir));
    cases.extend(pointer_cases(dir));
    cases
}

/// A one-triangle file whose node 0 is animated by one channel, after
/// `edit`; `output` holds VEC3 values.
fn animated_triangle(
    dir: &Path,
    name: &str,
    times: &[f32],
    output: &[[f32; 3]],
    edit: impl FnOnce(&mut Value),
) -> PathBuf {
    let mut bin = Bin::default();
    let positions = bin.vec3(&TRIANGLE);
    let input = bin.scalars(times);
    let output = bin.vec3(output);
    let mut doc = one_triangle_document(json!({ "attributes": { "POSITION": positions } }));
    doc["animations"] = json!([{
        "channels": [{ "sampler": 0, "target": { "node": 0, "path": "translation" } }],
        "samplers": [{ "input": input, "output": output }],
    }]);
    edit(&mut doc);
    bin.write_embedded(doc, dir, name)
}

fn animation_cases(dir: &Path) -> Vec<Case> {
    let case = |path: PathBuf, fault_word| Case { path, fault_word };
    let three = [[0.0; 3], [1.0; 3], [2.0; 3]];
    vec![
        case(
            animated_triangle(
                dir,
                "times_not_increasing.gltf",
                &[0.0, 1.0, 1.0],
                &three,
                |_| {},
            ),
            "strictly increasing",
        ),
        case(
            animated_triangle(dir, "nan_time.gltf", &[0.0, f32::NAN, 2.0], &three, |_| {}),
            "non-finite",
        ),
        case(
            animated_triangle(
                dir,
                "too_few_values.gltf",
                &[0.0, 1.0, 2.0, 3.0],
                &three,
                |_| {},
            ),
            "expected 12",
        ),
        case(
            animated_triangle(dir, "cubic_count.gltf", &[0.0, 1.0, 2.0], &three, |doc| {
                doc["animations"][0]["samplers"][0]["interpolation"] = json!("CUBICSPLINE");
            }),
            "CUBICSPLINE",
        ),
        case(
            animated_triangle(
                dir,
                "rotation_as_vec3.gltf",
                &[0.0, 1.0, 2.0],
                &three,
                |doc| {
                    doc["animations"][0]["channels"][0]["target"]["path"] = json!("rotation");
                },
            ),
            "VEC3 of FLOAT, expected VEC4",
        ),
        case(
            animated_triangle(dir, "weights_without_targets.gltf", &[0.0], &three, |doc| {
                doc["animations"][0]["channels"][0]["target"]["path"] = json!("weights");
            }),
            "no mesh with morph targets",
        ),
        case(
            anim_support::edited(dir, "joint_past_skin.gltf", anim_support::skinned, |doc| {
                doc["skins"][0]["joints"] = json!([0, 1]);
            }),
            "to joint 2",
        ),
        case(
            anim_support::edited(
                dir,
                "inverse_bind_vec3.gltf",
                anim_support::skinned,
                |doc| {
                    // Accessor 0 is the strip's POSITION, a VEC3.
                    doc["skins"][0]["inverseBindMatrices"] = json!(0);
                },
            ),
            "expected MAT4 of FLOAT",
        ),
        case(
            anim_support::edited(
                dir,
                "joints_without_weights.gltf",
                anim_support::skinned,
                |doc| {
                    let attributes = &mut doc["meshes"][0]["primitives"][0]["attributes"];
                    attributes
                        .as_object_mut()
                        .expect("attributes")
                        .remove("WEIGHTS_0");
                },
            ),
            "JOINTS_0 without WEIGHTS_0",
        ),
        case(
            anim_support::edited(dir, "mesh_weights_count.gltf", anim_support::morph, |doc| {
                doc["meshes"][0]["weights"] = json!([0.5, 0.5, 0.5]);
            }),
            "3 default weights",
        ),
        case(
            anim_support::edited(dir, "node_weights_count.gltf", anim_support::morph, |doc| {
                doc["nodes"][0]["weights"] = json!([0.5]);
            }),
            "node 0 has 1 weights",
        ),
    ]
}

/// KHR_animation_pointer channels that cannot be read. (Pointers lmanim
/// does not animate are skipped with a warning: see `anim_pointer.rs`.)
fn pointer_cases(dir: &Path) -> Vec<Case> {
    let case = |path: PathBuf, fault_word| Case { path, fault_word };
    let pointers =
        |name, edit: fn(&mut Value)| anim_support::edited(dir, name, anim_support::pointers, edit);
    vec![
        // The base colour (VEC4) read from the colour's VEC3 sampler.
        case(
            pointers("pointer_wrong_width.gltf", |doc| {
                doc["animations"][0]["channels"][5]["sampler"] = json!(0);
            }),
            "animation 0 sampler 0, read by channel 5",
        ),
        case(
            pointers("pointer_scalar_for_colour.gltf", |doc| {
                let scalar = doc["animations"][0]["samplers"][1]["output"].clone();
                doc["animations"][0]["samplers"][0]["output"] = scalar;
            }),
            "SCALAR of FLOAT, expected VEC3",
        ),
        case(
            pointers("pointer_missing_sampler.gltf", |doc| {
                doc["animations"][0]["channels"][2]["sampler"] = json!(9);
            }),
            "animation 0 channel 2: names sampler 9, but the animation has 6",
        ),
        case(
            pointers("pointer_output_past_accessors.gltf", |doc| {
                doc["animations"][0]["samplers"][3]["output"] = json!(999);
            }),
            "samplers[3].output",
        ),
        case(
            pointers("pointer_without_pointer.gltf", |doc| {
                doc["animations"][0]["channels"][4]["target"] = json!({ "path": "pointer" });
            }),
            "channel 4: has path \"pointer\" but no KHR_animation_pointer pointer",
        ),
        // Three STEP intensities for the colour's two key times.
        case(
            pointers("pointer_too_few_keys.gltf", |doc| {
                let times = doc["animations"][0]["samplers"][0]["input"].clone();
                doc["animations"][0]["samplers"][1]["input"] = times;
            }),
            "animation 0 channel 1: sampler 1 has 3 output values for 2 keys",
        ),
    ]
}

fn indices_past_vertices(dir: &Path) -> PathBuf {
    let mut bin = Bin::default();
    let positions = bin.vec3(&TRIANGLE);
    let indices = bin.indices_u16(&[0, 1, 7]);
    let doc = one_triangle_document(json!({
        "attributes": { "POSITION": positions }, "indices": indices }));
    bin.write_embedded(doc, dir, "index_past_vertices.gltf")
}

fn infinite_normal(dir: &Path) -> PathBuf {
    let mut bin = Bin::default();
    let positions = bin.vec3(&TRIANGLE);
    let normals = bin.vec3(&[[0.0, 0.0, 1.0], [0.0, f32::INFINITY, 1.0], [0.0, 0.0, 1.0]]);
    let doc = one_triangle_document(json!({
        "attributes": { "POSITION": positions, "NORMAL": normals } }));
    bin.write_embedded(doc, dir, "infinite_normal.gltf")
}

fn nan_uv(dir: &Path) -> PathBuf {
    let mut bin = Bin::default();
    let positions = bin.vec3(&TRIANGLE);
    let uvs = bin.vec2(&[[0.0, 0.0], [1.0, 0.0], [0.0, f32::NAN]]);
    let doc = one_triangle_document(json!({
        "attributes": { "POSITION": positions, "TEXCOORD_0": uvs } }));
    bin.write_embedded(doc, dir, "nan_uv.gltf")
}

fn file_name(path: &Path) -> String {
    path.file_name()
        .expect("file name")
        .to_string_lossy()
        .into_owned()
}

#[test]
fn every_bad_file_is_an_import_error_naming_file_and_fault() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut failures = Vec::new();
    for case in corpus(dir.path()) {
        let started = Instant::now();
        let message = match lmanim::import::load(&case.path) {
            Ok(_) => {
                failures.push(format!("{}: imported without error", case.path.display()));
                continue;
            }
            Err(error) => error.to_string(),
        };
        // Shown with --nocapture, to read the messages a user would see.
        println!("{message}");
        let name = file_name(&case.path);
        let well_formed = message.contains(&name)
            && message.contains(case.fault_word)
            && message.lines().count() == 1
            && !message.contains("internal error");
        if !well_formed {
            failures.push(format!(
                "{name}: expected {:?} in {message:?}",
                case.fault_word
            ));
        }
        // Rejecting must be cheap: no gigabyte allocation happened first.
        if started.elapsed() > Duration::from_secs(2) {
            failures.push(format!("{name}: took {:?}", started.elapsed()));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_binary_exits_2_with_one_line_naming_the_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut failures = Vec::new();
    for case in corpus(dir.path()) {
        let output = Command::new(env!("CARGO_BIN_EXE_lmanim"))
            .arg(&case.path)
            .current_dir(dir.path())
            .output()
            .expect("run lmanim");
        let stderr = String::from_utf8_lossy(&output.stderr);
        let lines: Vec<_> = stderr
            .lines()
            .filter(|line| !line.trim().is_empty())
            .collect();
        let name = file_name(&case.path);
        let ok = output.status.code() == Some(2) && lines.len() == 1 && lines[0].contains(&name);
        if !ok {
            failures.push(format!(
                "{name}: exit {:?}, stderr {stderr:?}",
                output.status.code()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn a_sparse_accessor_with_indices_past_its_count_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut bin = Bin::default();
    let positions = bin.vec3(&TRIANGLE);
    bin.sparse(positions, &[9], &[[5.0, 5.0, 5.0]]);
    let doc = one_triangle_document(json!({ "attributes": { "POSITION": positions } }));
    let path = bin.write_embedded(doc, dir.path(), "sparse.gltf");
    let message = lmanim::import::load(&path)
        .expect_err("sparse index 9 of 3")
        .to_string();
    assert!(
        message.contains("sparse.gltf") && message.contains("index 9"),
        "{message}"
    );
}

/// A small xorshift generator: the corruption test is reproducible without
/// a dependency.
struct XorShift(u64);

impl XorShift {
    fn below(&mut self, bound: usize) -> usize {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 % bound as u64) as usize
    }
}

#[test]
fn randomly_corrupted_files_never_panic() {
    let mut bin = Bin::default();
    let positions = bin.vec3(&[
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [0.0, 1.0, 0.0],
        [1.0, 1.0, 0.0],
    ]);
    let normals = bin.vec3(&[[0.0, 0.0, 1.0]; 4]);
    let uvs = bin.vec2(&[[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0]]);
    let indices = bin.indices_u16(&[0, 1, 2, 2, 1, 3]);
    let mut doc = one_triangle_document(json!({
        "attributes": { "POSITION": positions, "NORMAL": normals, "TEXCOORD_0": uvs },
        "indices": indices, "mode": 5 }));
    doc["nodes"] = json!([{ "children": [1], "translation": [1.0, 2.0, 3.0] }, { "mesh": 0 }]);
    let dir = tempfile::tempdir().expect("tempdir");
    let original = std::fs::read(bin.write_glb(doc, dir.path(), "original.glb")).expect("read");
    let json_end =
        20 + u32::from_le_bytes([original[12], original[13], original[14], original[15]]) as usize;
    let digits: Vec<usize> = (20..json_end)
        .filter(|&i| original[i].is_ascii_digit())
        .collect();

    let panics = corruption_panics(&original, &digits, &dir.path().join("corrupt.glb"));
    assert!(panics.is_empty(), "{}", panics.join("\n"));
}

#[test]
fn randomly_corrupted_pointer_channels_never_panic() {
    let dir = tempfile::tempdir().expect("tempdir");
    let original = std::fs::read(anim_support::pointers(dir.path())).expect("read");
    // The digits of the JSON's structure: the embedded buffer's base64 is
    // data, which other tests corrupt.
    let text = String::from_utf8_lossy(&original);
    let buffer_start = text.find("data:").expect("embedded buffer");
    let buffer_end = buffer_start + text[buffer_start..].find('"').expect("end of the URI");
    let digits: Vec<usize> = (0..original.len())
        .filter(|&i| original[i].is_ascii_digit() && !(buffer_start..buffer_end).contains(&i))
        .collect();
    let panics = corruption_panics(&original, &digits, &dir.path().join("corrupt.gltf"));
    assert!(panics.is_empty(), "{}", panics.join("\n"));
}

/// Imports 600 corruptions of `original` written to `path`, half changing
/// one to three of its `digits` into other digits (still JSON, different
/// counts, offsets, lengths and indices), half setting random bytes; the
/// errors that are panics.
fn corruption_panics(original: &[u8], digits: &[usize], path: &Path) -> Vec<String> {
    let mut rng = XorShift(0x2545_f491_4f6c_dd1d);
    let mut panics = Vec::new();
    for trial in 0..600 {
        let mut bytes = original.to_vec();
        for _ in 0..1 + rng.below(3) {
            if trial % 2 == 0 {
                let at = digits[rng.below(digits.len())];
                bytes[at] = b'0' + rng.below(10) as u8;
            } else {
                let at = rng.below(bytes.len());
                bytes[at] = rng.below(256) as u8;
            }
        }
        std::fs::write(path, &bytes).expect("write");
        if let Err(error) = lmanim::import::load(path) {
            if matches!(error.fault, lmanim::import::Fault::Panic(_)) {
                panics.push(format!("trial {trial}: {error}"));
            }
        }
    }
    panics
}
