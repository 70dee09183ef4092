//! Poses against an independent player: the test models of
//! `anim_support` (every interpolation mode, a skin, morph targets) are
//! posed by `lmanim inspect` and by three.js (GLTFLoader + AnimationMixer
//! under Node, `tests/threejs/sample.mjs`) at the same times; node world
//! matrices, morph weights and deformed vertex positions must agree to
//! 1e-4.
//!
//! Node and npm are required: without them the test fails and says so. The
//! pinned three.js is installed with `npm ci` on first use.

mod anim_support;
mod node_support;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use serde_json::{json, Value};

use lmanim::anim::{deformed_mesh, ClipSelection};
use lmanim::scene::pose::Pose;

const TOLERANCE: f64 = 1e-4;

/// One file posed with one clip selection.
struct Case {
    file: PathBuf,
    clip: Option<&'static str>,
}

fn times_arg() -> String {
    anim_support::TIMES
        .iter()
        .map(f64::to_string)
        .collect::<Vec<_>>()
        .join(",")
}

fn lmanim_inspect(case: &Case) -> Value {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lmanim"));
    command
        .arg("inspect")
        .arg(&case.file)
        .args(["--times", &times_arg()]);
    if let Some(clip) = case.clip {
        command.args(["--clip", clip]);
    }
    let output = command.output().expect("run lmanim inspect");
    assert!(
        output.status.success(),
        "lmanim inspect {}: {}",
        case.file.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("inspect JSON")
}

fn threejs_poses(package_dir: &Path, cases: &[Case]) -> Value {
    let request: Vec<Value> = cases
        .iter()
        .map(|case| json!({ "file": case.file, "clip": case.clip, "times": anim_support::TIMES }))
        .collect();
    let mut child = Command::new("node")
        .arg(package_dir.join("sample.mjs"))
        .current_dir(package_dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("start node");
    child
        .stdin
        .take()
        .expect("stdin")
        .write_all(json!(request).to_string().as_bytes())
        .expect("write the request");
    let output = child.wait_with_output().expect("node output");
    assert!(
        output.status.success(),
        "three.js sampling failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    serde_json::from_slice(&output.stdout).expect("three.js JSON")
}

fn numbers(value: &Value) -> Vec<f64> {
    value
        .as_array()
        .map(|items| items.iter().filter_map(Value::as_f64).collect())
        .unwrap_or_default()
}

/// The largest differences seen, per quantity.
#[derive(Default)]
struct Errors {
    world: f64,
    weights: f64,
    positions: f64,
    /// How many vertex sets were compared: the skinned and morphed meshes
    /// must be among them.
    meshes: usize,
    failures: Vec<String>,
}

impl Errors {
    fn compare(
        &mut self,
        what: &str,
        ours: &[f64],
        theirs: &[f64],
        slot: fn(&mut Errors) -> &mut f64,
    ) {
        if ours.len() != theirs.len() {
            self.failures.push(format!(
                "{what}: {} values against three.js's {}",
                ours.len(),
                theirs.len()
            ));
            return;
        }
        let error = ours
            .iter()
            .zip(theirs)
            .map(|(a, b)| (a - b).abs())
            .fold(0.0, f64::max);
        let worst = slot(self);
        *worst = worst.max(error);
        if error > TOLERANCE {
            self.failures.push(format!(
                "{what}: off by {error:.2e}\n  lmanim  {ours:?}\n  three.js {theirs:?}"
            ));
        }
    }
}

fn compare_case(case: &Case, ours: &Value, theirs: &Value, errors: &mut Errors) {
    let scene = lmanim::import::load(&case.file).expect("import");
    let selection = match case.clip {
        Some(clip) => ClipSelection::parse(&scene, clip).expect("clip"),
        None => ClipSelection::All,
    };
    let name = case
        .file
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let our_samples = ours["samples"].as_array().expect("samples");
    let their_samples = theirs["samples"].as_array().expect("samples");
    assert_eq!(our_samples.len(), their_samples.len());
    for (our, their) in our_samples.iter().zip(their_samples) {
        let time = our["time"].as_f64().expect("time");
        let pose = Pose::at(&scene, selection, time);
        let their_nodes = their["nodes"].as_array().expect("nodes");
        assert_eq!(
            their_nodes.len(),
            scene.nodes.len(),
            "{name}: three.js saw other nodes"
        );
        for their_node in their_nodes {
            let index = their_node["index"].as_u64().expect("index") as usize;
            let our_node = &our["nodes"][index];
            let at = format!("{name} clip {:?} t = {time} node {index}", case.clip);
            errors.compare(
                &format!("{at} world"),
                &numbers(&our_node["world"]),
                &numbers(&their_node["world"]),
                |e| &mut e.world,
            );
            if let Some(weights) = their_node.get("weights") {
                errors.compare(
                    &format!("{at} weights"),
                    &numbers(&our_node["weights"]),
                    &numbers(weights),
                    |e| &mut e.weights,
                );
            }
            if let Some(positions) = their_node["positions"].as_array() {
                let deformed = deformed_mesh(&scene, &pose, index).expect("a mesh node");
                let ours: Vec<f64> = deformed
                    .positions
                    .iter()
                    .flat_map(|p| p.as_dvec3().to_array())
                    .collect();
                let theirs: Vec<f64> = positions.iter().flat_map(numbers).collect();
                errors.compare(&format!("{at} positions"), &ours, &theirs, |e| {
                    &mut e.positions
                });
                errors.meshes += 1;
            }
        }
    }
}

#[test]
fn poses_match_threejs() {
    let package_dir = node_support::node_package_dir("threejs", "three", "the three.js comparison");
    let dir = tempfile::tempdir().expect("tempdir");
    let morph = anim_support::morph(dir.path());
    let cases = [
        Case {
            file: anim_support::interpolations(dir.path()),
            clip: None,
        },
        Case {
            file: anim_support::skinned(dir.path()),
            clip: None,
        },
        Case {
            file: morph.clone(),
            clip: None,
        },
        Case {
            file: morph,
            clip: Some("pulse"),
        },
    ];
    let theirs = threejs_poses(&package_dir, &cases);
    let mut errors = Errors::default();
    for (index, case) in cases.iter().enumerate() {
        compare_case(case, &lmanim_inspect(case), &theirs[index], &mut errors);
    }
    println!(
        "largest differences from three.js: world {:.2e}, weights {:.2e}, positions {:.2e}",
        errors.world, errors.weights, errors.positions
    );
    assert!(errors.failures.is_empty(), "{}", errors.failures.join("\n"));
    // interpolations: 2 cubes; skinned: 1 strip; morph: 2 sheets, twice.
    assert_eq!(errors.meshes, 7 * anim_support::TIMES.len());
}
