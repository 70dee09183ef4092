//! Bad files never panic: each file of a corpus the test writes gives an
//! `ImportError` whose one-line message names the file and the fault (by
//! JSON path and rule where the file breaks a rule of the glTF spec), both
//! from the library and from the `lmanim` binary (exit code 2, one line on
//! stderr, no panic text). Refusing a file holds little memory: no
//! gigabyte is allocated on a count's word.

mod alloc_meter;
mod anim_support;
mod import_support;
mod node_support;

use std::path::{Path, PathBuf};
use std::process::Command;

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
        "images[0]",
    ));
    cases.extend(animation_cases(dir));
    cases.extend(pointer_cases(dir));
    cases.extend(spec_rule_cases(dir));
    cases
}

/// Files that break a rule of the glTF 2.0 spec which the glTF crate does
/// not check: each message names the JSON path and the rule. (The Khronos
/// validator agrees that each is an error: see
/// `the_khronos_validator_also_refuses_every_spec_rule_case`.)
fn spec_rule_cases(dir: &Path) -> Vec<Case> {
    let case = |path: PathBuf, fault_word| Case { path, fault_word };
    let asset =
        |name, asset: Value| triangle_with(dir, name, &TRIANGLE, |doc| doc["asset"] = asset);
    vec![
        case(
            asset("version_1_0.gltf", json!({ "version": "1.0" })),
            "asset.version: is \"1.0\": lmanim reads glTF 2.x files",
        ),
        case(
            asset("version_3_0.gltf", json!({ "version": "3.0" })),
            "asset.version: is \"3.0\"",
        ),
        case(
            asset("min_version_2_1.gltf", json!({ "version": "2.1", "minVersion": "2.1" })),
            "asset.minVersion: is \"2.1\": the file needs a glTF \"2.1\" reader",
        ),
        case(
            asset("min_version_past_version.gltf", json!({ "version": "2.0", "minVersion": "2.1" })),
            "asset.minVersion: is \"2.1\", later than asset.version \"2.0\"",
        ),
        case(
            asset("version_not_major_minor.gltf", json!({ "version": "2" })),
            "asset.version: is \"2\", not a version of the form",
        ),
        case(
            triangle_with(dir, "no_asset.gltf", &TRIANGLE, |doc| {
                doc.as_object_mut().expect("object").remove("asset");
            }),
            "asset: is missing",
        ),
        // A real glTF 1.0 file: objects keyed by id where 2.0 has arrays.
        case(
            write_json(dir, "gltf_1_shape.gltf", &json!({
                "asset": { "version": "1.0" },
                "scene": "main",
                "scenes": { "main": { "nodes": ["root"] } },
                "nodes": { "root": { "meshes": [] } },
            })),
            "asset.version: is \"1.0\"",
        ),
        case(
            triangle_with(dir, "text_plain_buffer.gltf", &TRIANGLE, |doc| {
                let uri = doc["buffers"][0]["uri"].as_str().expect("data URI");
                let text = uri.replace("application/octet-stream", "text/plain");
                doc["buffers"][0]["uri"] = json!(text);
            }),
            "buffers[0].uri (data:text/plain;base64,",
        ),
        case(
            triangle_with(dir, "buffer_not_base64.gltf", &TRIANGLE, |doc| {
                doc["buffers"][0]["uri"] = json!("data:application/octet-stream,%00%00%00");
            }),
            "its data URI is not base64",
        ),
        case(
            triangle_with(dir, "stride_4_for_vec3.gltf", &TRIANGLE, |doc| {
                doc["bufferViews"][0]["byteStride"] = json!(4);
            }),
            "bufferViews[0].byteStride: is 4, smaller than the 12-byte elements of accessors[0] (VEC3 of FLOAT)",
        ),
        case(
            animated_triangle(dir, "negative_time.gltf", &[-1.0, 0.0, 1.0], &[[0.0; 3]; 3], |_| {}),
            "animations[0].samplers[0]: input key 0 is at -1 s; animation times must not be negative",
        ),
        case(
            zero_rotation_key(dir),
            "animations[0].samplers[0]: output key 1 is the rotation [0.0, 0.0, 0.0, 0.0], of length 0; rotations must be unit quaternions",
        ),
        case(
            animated_triangle(dir, "channel_node_out_of_range.gltf", &[0.0], &[[1.0; 3]], |doc| {
                let channel = doc["animations"][0]["channels"][0].clone();
                let mut far = channel.clone();
                far["target"]["node"] = json!(9);
                doc["animations"][0]["channels"] = json!([channel.clone(), channel, far]);
            }),
            "animations[0].channels[2].target.node: is 9, but the file has 1 node",
        ),
        case(
            triangle_with(dir, "camera_type_mismatch.gltf", &TRIANGLE, |doc| {
                doc["cameras"] = json!([{ "type": "perspective",
                    "orthographic": { "xmag": 1.0, "ymag": 1.0, "znear": 0.0, "zfar": 9.0 } }]);
            }),
            "cameras[0].perspective: is missing; a camera of type \"perspective\" must have it",
        ),
        case(
            textured_triangle_with(dir, "image_without_source.gltf", json!({})),
            "images[0]: has neither a uri nor a bufferView",
        ),
        case(
            textured_triangle_with(dir, "image_view_without_mime.gltf", json!({ "bufferView": 0 })),
            "images[0].mimeType: is missing",
        ),
        case(
            textured_triangle_with(
                dir,
                "image_octet_stream.gltf",
                json!({ "uri": "data:application/octet-stream;base64,AAAA" }),
            ),
            "images[0] cannot be read or decoded: its data URI has media type \"application/octet-stream\"",
        ),
    ]
}

/// The one-triangle file with a base-colour texture whose image is `image`.
fn textured_triangle_with(dir: &Path, name: &str, image: Value) -> PathBuf {
    triangle_with(dir, name, &TRIANGLE, |doc| {
        doc["materials"] =
            json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
        doc["meshes"][0]["primitives"][0]["material"] = json!(0);
        doc["textures"] = json!([{ "source": 0 }]);
        doc["images"] = json!([image]);
    })
}

/// A rotation channel whose second LINEAR key is the quaternion (0, 0, 0, 0).
fn zero_rotation_key(dir: &Path) -> PathBuf {
    let mut bin = Bin::default();
    let positions = bin.vec3(&TRIANGLE);
    let input = bin.scalars(&[0.0, 1.0]);
    let keys: Vec<u8> = [0.0f32, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0]
        .iter()
        .flat_map(|x| x.to_le_bytes())
        .collect();
    let output = bin.add(&keys, import_support::F32, "VEC4", 2, json!({}));
    let mut doc = one_triangle_document(json!({ "attributes": { "POSITION": positions } }));
    doc["animations"] = json!([{
        "channels": [{ "sampler": 0, "target": { "node": 0, "path": "rotation" } }],
        "samplers": [{ "input": input, "output": output }],
    }]);
    bin.write_embedded(doc, dir, "zero_rotation_key.gltf")
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
            "animations[0].samplers[1]: has 3 output values for 2 keys of width 1; expected 2 (read by channel 1)",
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

/// Refusing a file of a few kilobytes holds at most this much memory.
const MEMORY_BOUND: usize = 16 << 20;

#[test]
fn every_bad_file_is_an_import_error_naming_file_and_fault() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut failures = Vec::new();
    for case in corpus(dir.path()) {
        let (outcome, peak) = alloc_meter::peak_bytes(|| lmanim::import::load(&case.path));
        let message = match outcome {
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
        if peak > MEMORY_BOUND {
            failures.push(format!("{name}: held {peak} bytes at once"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

#[test]
fn the_binary_exits_2_with_one_line_naming_the_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut failures = Vec::new();
    for case in corpus(dir.path()) {
        let output = lmanim_on(&case.path, dir.path());
        let stderr = String::from_utf8_lossy(&output.stderr);
        let lines: Vec<_> = stderr
            .lines()
            .filter(|line| !line.trim().is_empty())
            .collect();
        let name = file_name(&case.path);
        let ok = output.status.code() == Some(2)
            && lines.len() == 1
            && lines[0].contains(&name)
            && !stderr.contains("panicked");
        if !ok {
            failures.push(format!(
                "{name}: exit {:?}, stderr {stderr:?}",
                output.status.code()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// `lmanim FILE` in `dir`, with backtraces asked for, so that panic text
/// would show if any were printed.
fn lmanim_on(file: &Path, dir: &Path) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .arg(file)
        .current_dir(dir)
        .env("RUST_BACKTRACE", "1")
        .output()
        .expect("run lmanim")
}

#[test]
fn a_scene_without_nodes_is_valid_and_has_nothing_to_render() {
    let dir = tempfile::tempdir().expect("tempdir");
    // `nodes` is optional in a scene; this one has none at all.
    let path = write_json(
        dir.path(),
        "empty_scene.gltf",
        &json!({ "asset": { "version": "2.0" }, "scene": 0, "scenes": [{ "name": "empty" }] }),
    );
    let scene = lmanim::import::load(&path).expect("a valid file");
    assert!(scene.roots.is_empty() && scene.nodes.is_empty());

    let output = lmanim_on(&path, dir.path());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert_eq!(
        stderr.trim(),
        format!(
            "lmanim: error: {}: nothing to render: the scene has no geometry and no camera",
            path.display()
        )
    );

    // Inspecting it is no error: its poses are empty.
    let output = Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args(["inspect", "empty_scene.gltf"])
        .current_dir(dir.path())
        .output()
        .expect("run lmanim inspect");
    assert_eq!(output.status.code(), Some(0));
    let report: Value = serde_json::from_slice(&output.stdout).expect("JSON");
    assert_eq!(report["samples"][0]["nodes"], json!([]));
}

#[test]
fn a_library_of_entities_says_so_and_exits_2() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = triangle_with(dir.path(), "library.gltf", &TRIANGLE, |doc| {
        let doc = doc.as_object_mut().expect("object");
        doc.remove("scene");
        doc.remove("scenes");
    });
    let output = lmanim_on(&path, dir.path());
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    assert_eq!(
        stderr.trim(),
        format!(
            "lmanim: error: {}: the file holds no scene: it is a library of entities \
             for other files to use, with nothing to render",
            path.display()
        )
    );
}

/// A channel whose `target.path` glTF 2.0 does not define belongs to an
/// extension: the spec lets a reader ignore it, and the validator only
/// warns. lmanim skips that channel with a warning naming it.
#[test]
fn a_channel_with_an_extension_s_path_is_skipped_with_a_warning() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = animated_triangle(
        dir.path(),
        "unknown_path.gltf",
        &[0.0, 1.0],
        &[[0.0; 3], [1.0; 3]],
        |doc| {
            let channel = doc["animations"][0]["channels"][0].clone();
            let mut unknown = channel.clone();
            unknown["target"]["path"] = json!("visibility");
            doc["animations"][0]["channels"] = json!([unknown, channel]);
        },
    );
    let scene = lmanim::import::load(&path).expect("the file imports");
    let targets: Vec<_> = scene.animations[0]
        .channels
        .iter()
        .map(|c| c.target)
        .collect();
    assert_eq!(targets, [lmanim::scene::Target::Translation(0)]);

    let output = Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args(["inspect", "unknown_path.gltf", "--times", "1"])
        .current_dir(dir.path())
        .output()
        .expect("run lmanim inspect");
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(0), "{stderr}");
    assert_eq!(
        stderr.trim(),
        "lmanim: warn: unknown_path.gltf: animation 0 channel 0: target.path is not one glTF 2.0 \
         defines (an extension's, which lmanim does not read); the channel is skipped"
    );
    let report: Value = serde_json::from_slice(&output.stdout).expect("JSON");
    assert_eq!(
        report["samples"][0]["nodes"][0]["translation"],
        json!([1.0, 1.0, 1.0])
    );
}

/// The rules lmanim enforces are the spec's: the Khronos validator finds
/// an error in every spec-rule case, and none in the two valid files that
/// have nothing to render.
#[test]
fn the_khronos_validator_also_refuses_every_spec_rule_case() {
    let dir = tempfile::tempdir().expect("tempdir");
    // The validator, a 2.0 reader itself, only warns of the unknown minor
    // version of a 2.1 file; the spec (§3.2) tells a reader not to load an
    // asset whose minVersion it does not support.
    let warned_only = ["min_version_2_1.gltf"];
    let mut disagreements = Vec::new();
    for case in spec_rule_cases(dir.path()) {
        let name = file_name(&case.path);
        let report = node_support::khronos_report(&case.path);
        let count = |kind: &str| report["issues"][kind].as_u64().unwrap_or(0);
        let agrees = if warned_only.contains(&name.as_str()) {
            count("numWarnings") > 0
        } else {
            count("numErrors") > 0
        };
        if !agrees {
            disagreements.push(format!("{name}: the validator does not object"));
        }
    }
    let valid = [
        write_json(
            dir.path(),
            "empty_scene.gltf",
            &json!({ "asset": { "version": "2.0" }, "scene": 0, "scenes": [{}] }),
        ),
        triangle_with(dir.path(), "library.gltf", &TRIANGLE, |doc| {
            let doc = doc.as_object_mut().expect("object");
            doc.remove("scene");
            doc.remove("scenes");
        }),
    ];
    for path in valid {
        let report = node_support::khronos_report(&path);
        if report["issues"]["numErrors"].as_u64() != Some(0) {
            disagreements.push(format!("{}: the validator finds errors", file_name(&path)));
        }
    }
    assert!(disagreements.is_empty(), "{}", disagreements.join("\n"));
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
