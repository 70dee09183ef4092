//! KHR_animation_pointer end to end: a file the authoring builder writes
//! with pointer channels on lights, a camera and a material passes the
//! Khronos validator, imports, and `lmanim inspect` reports hand-computed
//! values before, between, on and after the keys; node channels written as
//! pointers pose like plain ones; pointers lmanim does not animate are
//! skipped with a warning naming the file, animation, channel and pointer.
//!
//! The validator needs Node and npm (see `node_support`).

mod anim_support;
mod node_support;

use std::path::Path;

use lmanim::scene::{CameraProperty, LightProperty, MaterialProperty, Target};
use serde_json::{json, Value};

/// `lmanim inspect PATH --times TIMES`, its JSON and its stderr.
fn inspect(path: &Path, times: &str) -> (Value, String) {
    let dir = path.parent().expect("directory");
    let path = path.to_str().expect("utf-8 path");
    let output = anim_support::lmanim(&["inspect", path, "--times", times], dir);
    let stderr = String::from_utf8_lossy(&output.stderr).into_owned();
    assert!(output.status.success(), "{stderr}");
    let report = serde_json::from_slice(&output.stdout).expect("JSON on stdout");
    (report, stderr)
}

fn numbers(value: &Value) -> Vec<f64> {
    match value {
        Value::Array(items) => items.iter().flat_map(numbers).collect(),
        Value::Number(number) => vec![number.as_f64().expect("number")],
        other => panic!("not a number: {other}"),
    }
}

fn assert_close(what: &str, time: f64, found: &Value, expected: &[f64]) {
    let found = numbers(found);
    let close = found.len() == expected.len()
        && found
            .iter()
            .zip(expected)
            .all(|(a, b)| (a - b).abs() < 1e-6);
    assert!(
        close,
        "{what} at t = {time}: {found:?}, expected {expected:?}"
    );
}

fn by_name<'a>(items: &'a Value, name: &str) -> &'a Value {
    items
        .as_array()
        .expect("array")
        .iter()
        .find(|item| item["name"] == name)
        .unwrap_or_else(|| panic!("no {name}"))
}

const TIMES: &str = "0,0.25,1,1.25,2,3";

/// The animated values at one time.
struct Expected {
    time: f64,
    color: [f64; 3],
    intensity: f64,
    range: f64,
    outer_cone: f64,
    yfov: f64,
    base_color: [f64; 4],
}

/// Per time of [`TIMES`], worked by hand from the keys of
/// `anim_support::pointers`.
const EXPECTED: [Expected; 6] = [
    // Before the colour's and the intensity's first keys: each holds its
    // first value.
    Expected {
        time: 0.0,
        color: [1.0, 0.0, 0.0],
        intensity: 10.0,
        range: 4.0,
        outer_cone: 0.5,
        yfov: 0.5,
        base_color: [1.0, 1.0, 1.0, 1.0],
    },
    // yfov: Hermite at s = 1/8 over a 2 s span, out-tangent 0.25 and
    // in-tangent 0.125: 0.5·h00 + 0.5·h10 + h01 + 0.25·h11. The base
    // colour a quarter of the way, component by component (no slerp).
    Expected {
        time: 0.25,
        color: [1.0, 0.0, 0.0],
        intensity: 10.0,
        range: 4.5,
        outer_cone: 0.53125,
        yfov: 0.565_917_968_75,
        base_color: [0.8, 0.85, 0.9, 0.95],
    },
    // On the colour's first key; STEP still holds the 0.5 s key.
    Expected {
        time: 1.0,
        color: [1.0, 0.0, 0.0],
        intensity: 10.0,
        range: 6.0,
        outer_cone: 0.625,
        yfov: 0.78125,
        base_color: [0.2, 0.4, 0.6, 0.8],
    },
    Expected {
        time: 1.25,
        color: [0.75, 0.125, 0.25],
        intensity: 10.0,
        range: 6.5,
        outer_cone: 0.65625,
        yfov: 0.849_121_093_75,
        base_color: [0.2, 0.4, 0.6, 0.8],
    },
    Expected {
        time: 2.0,
        color: [0.0, 0.5, 1.0],
        intensity: 20.0,
        range: 8.0,
        outer_cone: 0.75,
        yfov: 1.0,
        base_color: [0.2, 0.4, 0.6, 0.8],
    },
    // After every last key: each holds its last value.
    Expected {
        time: 3.0,
        color: [0.0, 0.5, 1.0],
        intensity: 5.0,
        range: 8.0,
        outer_cone: 0.75,
        yfov: 1.0,
        base_color: [0.2, 0.4, 0.6, 0.8],
    },
];

#[test]
fn inspect_reports_hand_computed_light_camera_and_material_values() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = anim_support::pointers(dir.path());
    let scene = lmanim::import::load(&path).expect("import");
    let targets: Vec<Target> = scene.animations[0]
        .channels
        .iter()
        .map(|channel| channel.target)
        .collect();
    assert_eq!(
        targets,
        vec![
            Target::Light(0, LightProperty::Color),
            Target::Light(0, LightProperty::Intensity),
            Target::Light(0, LightProperty::Range),
            Target::Light(1, LightProperty::OuterConeAngle),
            Target::Camera(0, CameraProperty::Yfov),
            Target::Material(0, MaterialProperty::BaseColor),
        ]
    );
    // Nothing that moves: no node is animated.
    assert!(scene
        .nodes
        .iter()
        .all(|node| !node.animated && !node.deforms));

    let (report, stderr) = inspect(&path, TIMES);
    assert!(!stderr.contains("warn"), "{stderr}");
    let samples = report["samples"].as_array().expect("samples");
    assert_eq!(samples.len(), EXPECTED.len());
    for (sample, expected) in samples.iter().zip(&EXPECTED) {
        let time = expected.time;
        assert_eq!(sample["time"], json!(time));
        let lamp = by_name(&sample["lights"], "lamp");
        assert_close("colour", time, &lamp["color"], &expected.color);
        assert_close("intensity", time, &lamp["intensity"], &[expected.intensity]);
        assert_close("range", time, &lamp["range"], &[expected.range]);
        let spot = by_name(&sample["lights"], "spot");
        let outer = &spot["outer_cone_angle"];
        assert_close("outer cone", time, outer, &[expected.outer_cone]);
        assert_close("inner cone", time, &spot["inner_cone_angle"], &[0.25]);
        let camera = by_name(&sample["cameras"], "eye");
        assert_close("yfov", time, &camera["yfov"], &[expected.yfov]);
        let paint = by_name(&sample["materials"], "paint");
        assert_close(
            "base colour",
            time,
            &paint["base_color"],
            &expected.base_color,
        );
        assert_close("metallic", time, &paint["metallic"], &[0.0]);
    }
}

#[test]
fn the_builder_writes_pointer_channels_the_khronos_validator_accepts() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = anim_support::pointers(dir.path());
    let report = node_support::khronos_report(&path);
    let issues = &report["issues"];
    assert_eq!(issues["numErrors"].as_u64(), Some(0), "errors");
    assert_eq!(issues["numWarnings"].as_u64(), Some(0), "warnings");
    let used = &report["info"]["extensionsUsed"];
    assert!(
        used.as_array()
            .is_some_and(|used| used.contains(&json!("KHR_animation_pointer"))),
        "{used}"
    );
}

#[test]
fn reports_without_material_animation_have_no_materials() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = anim_support::interpolations(dir.path());
    let (report, _) = inspect(&path, "0,1");
    for sample in report["samples"].as_array().expect("samples") {
        assert!(sample.get("materials").is_none(), "{sample}");
        let lamp = by_name(&sample["lights"], "lamp");
        assert!(lamp.get("outer_cone_angle").is_none(), "{lamp}");
    }
}

fn pointer_target(pointer: &str) -> Value {
    json!({ "path": "pointer",
        "extensions": { "KHR_animation_pointer": { "pointer": pointer } } })
}

#[test]
fn node_channels_written_as_pointers_pose_like_plain_ones() {
    let dir = tempfile::tempdir().expect("tempdir");
    let plain = anim_support::interpolations(dir.path());
    let as_pointers = anim_support::edited(
        dir.path(),
        "as_pointers.gltf",
        anim_support::interpolations,
        |doc| {
            // Every other channel, so plain and pointer channels interleave.
            let channels = doc["animations"][0]["channels"]
                .as_array_mut()
                .expect("channels");
            for channel in channels.iter_mut().step_by(2) {
                let node = channel["target"]["node"].as_u64().expect("node");
                let path = channel["target"]["path"].as_str().expect("path").to_owned();
                channel["target"] = pointer_target(&format!("/nodes/{node}/{path}"));
            }
            doc["extensionsUsed"]
                .as_array_mut()
                .expect("extensionsUsed")
                .push(json!("KHR_animation_pointer"));
        },
    );
    let a = lmanim::import::load(&plain).expect("plain");
    let b = lmanim::import::load(&as_pointers).expect("pointers");
    assert_eq!(a.animations, b.animations);
    let moved = |scene: &lmanim::scene::SceneDesc| -> Vec<bool> {
        scene.nodes.iter().map(|node| node.animated).collect()
    };
    assert_eq!(moved(&a), moved(&b));
    assert!(moved(&b).iter().any(|&animated| animated));
    let times = "0,0.4,1.1,3";
    assert_eq!(inspect(&plain, times).0, inspect(&as_pointers, times).0);
}

#[test]
fn pointers_lmanim_does_not_animate_are_skipped_with_a_warning() {
    let dir = tempfile::tempdir().expect("tempdir");
    let cases = [
        (
            "missing_light.gltf",
            1,
            "/extensions/KHR_lights_punctual/lights/7/color",
            "light 7",
        ),
        (
            "unsupported.gltf",
            2,
            "/materials/0/alphaCutoff",
            "does not animate",
        ),
        (
            "point_cone.gltf",
            3,
            "/extensions/KHR_lights_punctual/lights/0/spot/outerConeAngle",
            "not a spot light",
        ),
        ("missing_node.gltf", 5, "/nodes/40/scale", "node 40"),
    ];
    for (name, channel, pointer, reason) in cases {
        let path = anim_support::edited(dir.path(), name, anim_support::pointers, |doc| {
            doc["animations"][0]["channels"][channel]["target"] = pointer_target(pointer);
        });
        let scene = lmanim::import::load(&path).expect("the file imports");
        let clip = &scene.animations[0];
        assert_eq!(clip.channels.len(), 5, "{name}: one channel skipped");
        // The channels after the skipped one keep their order.
        let last = match channel {
            5 => Target::Camera(0, CameraProperty::Yfov),
            _ => Target::Material(0, MaterialProperty::BaseColor),
        };
        assert_eq!(clip.channels.last().map(|c| c.target), Some(last), "{name}");
        let (report, stderr) = inspect(&path, "1");
        assert_eq!(report["samples"].as_array().map(Vec::len), Some(1));
        let warnings: Vec<&str> = stderr
            .lines()
            .filter(|line| line.contains("warn"))
            .collect();
        assert_eq!(warnings.len(), 1, "{name}: {stderr}");
        let warning = warnings[0];
        for word in [
            name,
            &format!("animation 0 channel {channel}"),
            pointer,
            reason,
            "skipped",
        ] {
            assert!(
                warning.contains(word),
                "{name}: {word:?} not in {warning:?}"
            );
        }
    }
}

#[test]
fn an_animation_of_pointer_channels_only_imports_and_the_extension_may_be_required() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = anim_support::edited(
        dir.path(),
        "one_clip_each.gltf",
        anim_support::pointers,
        |doc| {
            // A second animation holding only the yfov channel, which leaves
            // the first.
            let animation = &mut doc["animations"][0];
            let mut channel = animation["channels"]
                .as_array_mut()
                .expect("channels")
                .remove(4);
            let sampler = animation["samplers"][4].clone();
            channel["sampler"] = json!(0);
            doc["animations"]
                .as_array_mut()
                .expect("animations")
                .push(json!({ "name": "zoom", "channels": [channel], "samplers": [sampler] }));
            // lmanim honours the extension, so a file may require it.
            doc["extensionsRequired"] = json!(["KHR_animation_pointer"]);
        },
    );
    let scene = lmanim::import::load(&path).expect("import");
    assert_eq!(scene.animations.len(), 2);
    assert_eq!(scene.animations[0].channels.len(), 5);
    assert_eq!(
        scene.animations[1].channels[0].target,
        Target::Camera(0, CameraProperty::Yfov)
    );
    let (report, _) = inspect(&path, "1");
    let camera = by_name(&report["samples"][0]["cameras"], "eye");
    assert_close("yfov", 1.0, &camera["yfov"], &[0.78125]);
}
