//! Camera paths end to end: the README's example flight over the city
//! is the file in `animations/`, parses and renders; the frame loop places the path's camera at each
//! frame's time; bad path files and `--orbit` values stop with one
//! line naming the file and the fault; a moving path camera drops no
//! light-mesh bit; and `bake-camera` writes a glTF the Khronos validator
//! accepts, whose clip `lmanim inspect` plays back as the spline's poses
//! and lmanim renders as it renders the path, also from scenes whose
//! buffer lies in an external `.bin` or a `.glb`.
//!
//! The validator needs Node and npm (see `tests/node_support`).

mod common;
mod node_support;

use std::path::{Path, PathBuf};

use common::cli::{assert_bad_input, lmanim};
use glam::{DVec3, Vec3};
use lmanim::camera_path::CameraPath;
use lmanim::plan::Plan;
use lmanim::sequence::Sequence;
use lmanim::settings::Settings;
use lmanim::stats::FrameStats;
use lmanim_authoring::{shapes, GltfBuilder, NodeDesc, Primitive};
use serde_json::Value;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn flight() -> PathBuf {
    root().join("animations/city-flight.ron")
}

fn text(path: &Path) -> &str {
    path.to_str().expect("UTF-8 path")
}

/// The path file the README's "Camera paths" section shows.
fn readme_path(dir: &Path) -> CameraPath {
    let readme = std::fs::read_to_string(root().join("README.md")).unwrap();
    let section = &readme[readme.find("### Camera paths").unwrap()..];
    let block = section.split("```ron\n").nth(1).unwrap();
    let block = &block[..block.find("```").unwrap()];
    let file = dir.join("readme.ron");
    std::fs::write(&file, block).unwrap();
    CameraPath::load(&file).unwrap()
}

#[test]
fn the_city_flight_parses_and_renders_a_small_frame() {
    let path = CameraPath::load(&flight()).unwrap();
    assert_eq!((path.start(), path.end()), (0.0, 10.0));
    let dir = tempfile::tempdir().unwrap();
    assert!(readme_path(dir.path()) == path, "the README shows the file");
    let out = dir.path().join("frame.####.exr");
    let run = lmanim(&[
        text(&root().join("animations/city.gltf")),
        "--camera-path",
        text(&flight()),
        "--frames",
        "120",
        "--width",
        "48",
        "--height",
        "27",
        "--no-cache",
        "--out",
        text(&out),
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    // city.ron names its own camera; the path wins, and says so.
    assert!(
        stderr.contains("camera 'flythrough' is not used"),
        "{stderr}"
    );
    let image = lmanim::output::read_exr(&dir.path().join("frame.0120.exr")).unwrap();
    let lit = (image.pixels.iter()).filter(|p| p.truncate().max_element() > 1e-3);
    assert!(
        lit.count() > image.pixels.len() / 2,
        "the city fills the view"
    );
}

#[test]
fn every_frame_is_seen_from_the_path_at_its_time() {
    let scene_file = root().join("animations/study-box.gltf");
    let mut sequence = Sequence::load(&scene_file).unwrap();
    let anchor = Plan::anchor(sequence.scene());
    let path = CameraPath::load(&flight()).unwrap();
    let settings = Settings {
        camera_path: Some(path.clone()),
        ..Settings::default()
    };
    for frame in [0, 7, 100, 239, 300] {
        let time = frame as f64 / settings.fps;
        let placed = sequence
            .advance(time, &settings, &mut FrameStats::default())
            .unwrap();
        let pose = path.pose_at(time);
        let origin = (pose.position - anchor).as_vec3();
        assert!(
            placed.camera.origin.abs_diff_eq(origin, 1e-4),
            "frame {frame}"
        );
        let backward = (pose.rotation * DVec3::Z).as_vec3();
        assert!(
            placed.camera.backward.abs_diff_eq(backward, 1e-6),
            "frame {frame}"
        );
        assert_eq!(placed.camera.projection, pose.projection());
        assert!(!placed.automatic_camera);
    }
}

#[test]
fn bad_paths_stop_with_one_line_naming_the_file_and_fault() {
    let dir = tempfile::tempdir().unwrap();
    let scene = root().join("animations/study-box.gltf");
    let cases = [
        ("(waypoints: [(position: (0, 1, 5), yaw: 0)], duration: 2)", "at least two waypoints"),
        (
            "(waypoints: [(position: (0, 1, 5), yaw: 0, time: 1), (position: (1, 1, 5), yaw: 0, time: 1)])",
            "times must increase",
        ),
        (
            "(waypoints: [(position: (0, 1, 5), look_at: (0, 1, 5)), (position: (1, 1, 5), yaw: 0)], duration: 1)",
            "look_at equals position",
        ),
        (
            "(waypoints: [(position: (0, NaN, 5), yaw: 0), (position: (1, 1, 5), yaw: 0)], duration: 1)",
            "not finite",
        ),
        (
            "(waypoints: [(position: (0, 1, 5), yaw: 0), (position: (1, 1, 5), yaw: 0)], duration: 1, speed: 3)",
            "speed",
        ),
    ];
    for (index, (body, fault)) in cases.iter().enumerate() {
        let file = dir.path().join(format!("bad-{index}.ron"));
        std::fs::write(&file, body).unwrap();
        let run = lmanim(&[text(&scene), "--camera-path", text(&file), "--no-cache"]);
        assert_bad_input(&run, &format!("{}: ", file.display()));
        assert_bad_input(&run, fault);
    }
    let run = lmanim(&[text(&scene), "--orbit", "0,0,0,0,1,5"]);
    assert_bad_input(
        &run,
        "--orbit 0,0,0,0,1,5: RADIUS and SECONDS must be above 0",
    );
}

#[test]
fn a_moving_path_camera_drops_no_light_mesh_bit() {
    let dir = tempfile::tempdir().unwrap();
    let stats = dir.path().join("stats.json");
    let run = lmanim(&[
        text(&root().join("animations/study-box.gltf")),
        "--orbit",
        "0,0.5,0,4,2,1",
        "--frames",
        "0..4",
        "--method",
        "lmm",
        "--width",
        "32",
        "--height",
        "18",
        "--no-cache",
        "--quiet",
        "--stats",
        text(&stats),
        "--out",
        text(&dir.path().join("frame.####.exr")),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let stats: Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    let frames = stats["frames"].as_array().unwrap();
    assert!(frames[0]["lightmesh"]["bits_computed"].as_u64().unwrap() > 0);
    for frame in &frames[1..] {
        assert_eq!(frame["camera_moved"], true, "{frame}");
        assert_eq!(frame["copied"], false, "{frame}");
        assert_eq!(frame["bits_invalidated"], 0, "{frame}");
    }
}

/// `lmanim inspect`'s camera named `camera-path` at frames 0..=frames.
fn inspected(scene: &Path, fps: f64, frames: u32) -> Vec<Value> {
    let range = format!("0..={frames}");
    let fps = fps.to_string();
    let run = lmanim(&["inspect", text(scene), "--frames", &range, "--fps", &fps]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let report: Value = serde_json::from_slice(&run.stdout).unwrap();
    (report["samples"].as_array().unwrap().iter())
        .map(|sample| {
            let cameras = sample["cameras"].as_array().unwrap();
            let baked = cameras.iter().find(|c| c["name"] == "camera-path");
            baked.expect("the baked camera").clone()
        })
        .collect()
}

fn vector(value: &Value) -> DVec3 {
    let xyz: Vec<f64> = (value.as_array().unwrap().iter())
        .map(|x| x.as_f64().unwrap())
        .collect();
    DVec3::new(xyz[0], xyz[1], xyz[2])
}

/// Bakes `path` into `scene` at `fps`, checks the validator's verdict and
/// that inspect gives the path's poses at every frame time.
fn check_bake(scene: &Path, path: &CameraPath, path_args: &[&str], fps: f64) {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("elsewhere/with camera.gltf");
    let fps_text = fps.to_string();
    let mut args = vec!["bake-camera", text(scene)];
    args.extend_from_slice(path_args);
    args.extend_from_slice(&["--out", text(&out), "--fps", &fps_text]);
    let run = lmanim(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );

    let report = node_support::khronos_report(&out);
    assert_eq!(
        report["issues"]["numErrors"].as_u64(),
        Some(0),
        "validator errors"
    );

    let frames = (path.end() * fps).ceil() as u32 + 2;
    for (frame, camera) in inspected(&out, fps, frames).iter().enumerate() {
        let pose = path.pose_at(frame as f64 / fps);
        let position = vector(&camera["position"]);
        let error = position.distance(pose.position);
        assert!(
            error < 1e-5,
            "frame {frame}: {position} vs {} ({error} m)",
            pose.position
        );
        let direction = vector(&camera["direction"]);
        assert!(
            direction.angle_between(pose.rotation * DVec3::NEG_Z) < 1e-5,
            "frame {frame}"
        );
        let up = vector(&camera["up"]);
        assert!(
            up.angle_between(pose.rotation * DVec3::Y) < 1e-5,
            "frame {frame}"
        );
        let yfov = camera["yfov"].as_f64().unwrap();
        assert!(
            (yfov - pose.yfov).abs() < 1e-6,
            "frame {frame}: {yfov} vs {}",
            pose.yfov
        );
    }
}

#[test]
fn a_baked_flight_plays_back_as_the_spline_and_passes_the_validator() {
    let scene = root().join("animations/study-box.gltf");
    let path = CameraPath::load(&flight()).unwrap();
    let zooms = path.pose_at(0.0).yfov != path.pose_at(10.0).yfov;
    assert!(
        zooms,
        "the flight's field of view changes, so a pointer channel is baked"
    );
    check_bake(&scene, &path, &["--camera-path", text(&flight())], 24.0);
}

/// Renders frame 30 of `scene` at 64×36 with `flags`, returning its image.
fn render_frame_30(scene: &Path, flags: &[&str], out: &Path) -> lmanim::output::Image {
    let pattern = out.join("frame.####.exr");
    let mut args = vec![
        text(scene),
        "--frames",
        "30",
        "--width",
        "64",
        "--height",
        "36",
    ];
    args.extend_from_slice(flags);
    args.extend_from_slice(&["--no-cache", "--quiet", "--out", text(&pattern)]);
    let run = lmanim(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    lmanim::output::read_exr(&out.join("frame.0030.exr")).unwrap()
}

#[test]
fn lmanim_renders_the_baked_camera_as_it_renders_the_path() {
    let dir = tempfile::tempdir().unwrap();
    let scene = root().join("animations/study-box.gltf");
    let orbit = ["--orbit", "0,0.5,0,4,2,2"];
    let baked = dir.path().join("baked.gltf");
    let run = lmanim(&[
        "bake-camera",
        text(&scene),
        orbit[0],
        orbit[1],
        "--out",
        text(&baked),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let flown = render_frame_30(&scene, &orbit, &dir.path().join("flown"));
    let played = render_frame_30(
        &baked,
        &["--camera", "camera-path"],
        &dir.path().join("played"),
    );
    let lit = (flown.pixels.iter()).filter(|p| p.truncate().max_element() > 1e-3);
    assert!(lit.count() > flown.pixels.len() / 10, "the box is in view");
    // The baked camera is the path's pose rounded to f32: a pixel whose
    // centre lies on an edge may fall the other way, no more.
    let differing = (flown.pixels.iter().zip(&played.pixels))
        .filter(|(a, b)| (**a - **b).abs().max_element() > 1e-3)
        .count();
    println!("{differing} of {} pixels differ", flown.pixels.len());
    assert!(
        differing <= flown.pixels.len() / 100,
        "{differing} pixels differ"
    );
}

#[test]
fn orbits_baked_from_an_external_bin_and_a_glb_stand_alone() {
    let dir = tempfile::tempdir().unwrap();
    let mut builder = GltfBuilder::new();
    let cube = builder.add_geometry(&shapes::cuboid(Vec3::ONE)).unwrap();
    let primitive = Primitive {
        geometry: cube,
        material: None,
    };
    let mesh = builder.add_mesh("Box", &[primitive]).unwrap();
    let node = NodeDesc {
        mesh: Some(mesh),
        ..NodeDesc::named("Box")
    };
    builder.add_node(node).unwrap();
    let with_bin = dir.path().join("input/box.gltf");
    builder.write_gltf_with_bin(&with_bin).unwrap();
    assert!(dir.path().join("input/box.bin").exists());
    let glb = dir.path().join("input/box.glb");
    builder.write_glb(&glb).unwrap();

    let orbit = "0,0,0,6,3,2.5";
    let path = CameraPath::orbit(orbit).unwrap();
    for scene in [with_bin, glb] {
        check_bake(&scene, &path, &["--orbit", orbit], 30.0);
    }
}
