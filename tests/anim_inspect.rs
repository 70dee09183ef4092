//! `lmanim inspect`: the subcommand beside the render form, its JSON, clip
//! selection, frames to times, and one-line errors with exit code 2.

mod anim_support;

use std::path::Path;

use serde_json::Value;

fn inspect(args: &[&str], dir: &Path) -> Value {
    let mut all = vec!["inspect"];
    all.extend(args);
    let output = anim_support::lmanim(&all, dir);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("JSON on stdout")
}

fn numbers(value: &Value) -> Vec<f64> {
    value
        .as_array()
        .expect("array")
        .iter()
        .map(|v| v.as_f64().expect("number"))
        .collect()
}

fn close(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-5)
}

fn node<'a>(sample: &'a Value, name: &str) -> &'a Value {
    sample["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .find(|node| node["name"] == name)
        .expect("node by name")
}

#[test]
fn inspect_reports_hand_computed_poses() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = anim_support::interpolations(dir.path());
    let path = path.to_str().expect("utf-8 path");
    let report = inspect(&[path, "--times", "0,0.625,5"], dir.path());
    let samples = report["samples"].as_array().expect("samples");
    assert_eq!(samples.len(), 3);
    assert_eq!(samples[1]["time"], 0.625);

    // mover: translation LINEAR from 0 at 0.25 s to (3, 1, −2) at 1 s.
    let mover = node(&samples[1], "mover");
    assert!(close(&numbers(&mover["translation"]), &[1.5, 0.5, -1.0]));
    // Before the first key the first value holds, after the last the last.
    assert!(close(
        &numbers(&node(&samples[0], "mover")["translation"]),
        &[0.0; 3]
    ));
    assert!(close(
        &numbers(&node(&samples[2], "mover")["translation"]),
        &[1.0, 1.0, 1.0]
    ));
    // stepper: STEP scale is still the first key's until 1 s.
    assert!(close(
        &numbers(&node(&samples[1], "stepper")["scale"]),
        &[1.0; 3]
    ));
    assert!(close(
        &numbers(&node(&samples[2], "stepper")["scale"]),
        &[2.0, 0.5, 1.5]
    ));
    // World matrices are column-major: the translation is elements 12..15.
    let world = numbers(&node(&samples[2], "stepper")["world"]);
    assert!(close(&world[12..15], &[-2.0, 0.0, 0.0]));
    // The lamp moves linearly from (0, 3, 0) to (4, 3, −4) over 2 s; the
    // light is reported in world space.
    let lamp = &samples[1]["lights"][0];
    assert_eq!(lamp["name"], "lamp");
    assert!(close(&numbers(&lamp["position"]), &[1.25, 3.0, -1.25]));
    assert!(close(&numbers(&lamp["direction"]), &[0.0, 0.0, -1.0]));
    let eye = &samples[0]["cameras"][0];
    assert_eq!(eye["projection"], "perspective");
    assert!((eye["yfov"].as_f64().expect("yfov") - 0.8).abs() < 1e-6);
    // No morph mesh, no weights key.
    assert!(mover.get("weights").is_none());
}

#[test]
fn clips_are_selected_by_name_or_index() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = anim_support::morph(dir.path());
    let path = path.to_str().expect("utf-8 path");
    let all = inspect(&[path, "--times", "0.5"], dir.path());
    let sample = &all["samples"][0];
    // wobble: (0, 0) at 0.25 s → (1, 0.5) at 0.75 s.
    assert!(close(
        &numbers(&node(sample, "own_weights")["weights"]),
        &[0.5, 0.25]
    ));
    // hop: STEP to (3, 1, 0) at 0.5 s.
    assert!(close(
        &numbers(&node(sample, "mesh_weights")["translation"]),
        &[3.0, 1.0, 0.0]
    ));

    for selection in ["hop", "2"] {
        let one = inspect(&[path, "--times", "0.5", "--clip", selection], dir.path());
        let sample = &one["samples"][0];
        // Without wobble the node keeps its own default weights.
        assert!(close(
            &numbers(&node(sample, "own_weights")["weights"]),
            &[0.3, 0.0]
        ));
        assert!(close(
            &numbers(&node(sample, "mesh_weights")["weights"]),
            &[0.1, 0.2]
        ));
        assert!(close(
            &numbers(&node(sample, "mesh_weights")["translation"]),
            &[3.0, 1.0, 0.0]
        ));
    }
}

#[test]
fn frames_become_times_at_the_given_rate() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = anim_support::morph(dir.path());
    let path = path.to_str().expect("utf-8 path");
    let report = inspect(&[path, "--frames", "0..3", "--fps", "4"], dir.path());
    let times: Vec<f64> = report["samples"]
        .as_array()
        .expect("samples")
        .iter()
        .map(|sample| sample["time"].as_f64().expect("time"))
        .collect();
    assert_eq!(times, vec![0.0, 0.25, 0.5]);
}

#[test]
fn bad_input_exits_2_with_one_line_and_rendering_keeps_its_form() {
    let dir = tempfile::tempdir().expect("tempdir");
    let path = anim_support::morph(dir.path());
    let path = path.to_str().expect("utf-8 path");
    let missing = dir.path().join("missing.gltf");
    let missing = missing.to_str().expect("utf-8 path");
    let cases: [&[&str]; 5] = [
        &["inspect", missing],
        &["inspect", path, "--clip", "dance"],
        &["inspect", path, "--times", "0,nan"],
        &["inspect", path, "--frames", "5..2"],
        // The render form still takes the scene first.
        &[missing, "--frames", "0"],
    ];
    for args in cases {
        let output = anim_support::lmanim(args, dir.path());
        let stderr = String::from_utf8_lossy(&output.stderr);
        let lines: Vec<_> = stderr.lines().filter(|l| !l.trim().is_empty()).collect();
        assert_eq!(output.status.code(), Some(2), "{args:?}: {stderr}");
        assert_eq!(lines.len(), 1, "{args:?}: {stderr}");
        assert!(output.stdout.is_empty(), "{args:?}");
    }
    let clip_error = anim_support::lmanim(&["inspect", path, "--clip", "dance"], dir.path());
    let stderr = String::from_utf8_lossy(&clip_error.stderr);
    assert!(
        stderr.contains("0 (wobble), 1 (pulse), 2 (hop)"),
        "{stderr}"
    );
}
