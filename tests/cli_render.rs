//! The `lmanim` binary end to end: frames and previews on disk, the stats
//! JSON, exit codes and one-line errors for bad usage.

use std::path::{Path, PathBuf};
use std::process::Output;

use glam::{Vec2, Vec3};
use lmanim::scene::{Light, LightKind, Material};
use lmanim_authoring::{shapes, GltfBuilder, NodeDesc, Primitive};

mod common;

use common::cli::{assert_bad_input, lmanim};

fn courtyard() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("animations/courtyard.gltf")
        .display()
        .to_string()
}

fn stderr(output: &Output) -> String {
    String::from_utf8_lossy(&output.stderr).into_owned()
}

#[test]
fn renders_frames_previews_and_stats() {
    let dir = tempfile::tempdir().unwrap();
    let pattern = dir.path().join("shot/frame.####.exr");
    let stats = dir.path().join("stats.json");
    let output = lmanim(&[
        &courtyard(),
        "--frames",
        "0..2",
        "--width",
        "64",
        "--height",
        "36",
        "--method",
        "whitted",
        "--out",
        pattern.to_str().unwrap(),
        "--png",
        "--exr-float",
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("rendered 2 frame(s) with whitted"),
        "{}",
        stderr(&output)
    );

    for frame in ["0000", "0001"] {
        let exr: PathBuf = dir.path().join(format!("shot/frame.{frame}.exr"));
        let image = lmanim::output::read_exr(&exr).unwrap();
        assert_eq!((image.width, image.height), (64, 36));
        assert!(image.pixels.iter().all(|p| p.is_finite()));
        assert!(
            image.pixels.iter().any(|p| p.x > 0.0),
            "the courtyard is lit"
        );
        assert!(dir.path().join(format!("shot/frame.{frame}.png")).is_file());
    }
    let leftovers: Vec<_> = std::fs::read_dir(dir.path().join("shot"))
        .unwrap()
        .filter_map(|entry| entry.ok())
        .filter(|entry| entry.file_name().to_string_lossy().ends_with(".tmp"))
        .collect();
    assert!(leftovers.is_empty(), "no temporary files remain");

    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    assert_eq!(json["method"], "whitted");
    assert!(json["threads"].as_u64().unwrap() >= 1);
    assert!(json["total_seconds"].as_f64().unwrap() > 0.0);
    let frames = json["frames"].as_array().unwrap();
    assert_eq!(frames.len(), 2);
    assert_eq!(frames[1]["frame"], 1);
    assert_eq!(frames[0]["rays"]["primary"], 64 * 36);
    for key in ["shadow", "secondary"] {
        assert!(
            frames[0]["rays"][key].as_u64().unwrap() > 0,
            "{key} rays (mirror, glass, lamps)"
        );
    }
    assert!(frames[0]["shading_points"].as_u64().unwrap() > 0);
    for stage in ["primary", "secondary", "shade", "resolve", "output"] {
        assert!(
            frames[0]["stages"][stage].as_f64().is_some(),
            "stage {stage}"
        );
    }
    assert!(
        frames[0].get("lightmesh").is_none(),
        "Whitted has no light mesh"
    );
}

#[test]
fn light_mesh_methods_report_h_and_their_statistics() {
    let dir = tempfile::tempdir().unwrap();
    let stats = dir.path().join("stats.json");
    let output = lmanim(&[
        &courtyard(),
        "--width",
        "48",
        "--height",
        "27",
        "--method",
        "lmm1",
        "--out",
        dir.path().join("f.#.exr").to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("light mesh: h = "),
        "{}",
        stderr(&output)
    );
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    let mesh = &json["frames"][0]["lightmesh"];
    assert_eq!(mesh["ki"], 2.5);
    assert!(mesh["h"].as_f64().unwrap() > 0.0);
    assert!(mesh["nodes_computed"].as_u64().unwrap() > 0);
    assert_eq!(
        mesh["mean_p2n_tests"], 0.0,
        "LMM1 makes no point-to-node tests"
    );
    assert!(dir.path().join("f.0.exr").is_file());
}

#[test]
fn bad_usage_exits_2_with_one_line() {
    let scene = courtyard();
    assert_bad_input(
        &lmanim(&[&scene, "--frames", "5..5", "--out", "/tmp/x.#.exr"]),
        "--frames",
    );
    assert_bad_input(&lmanim(&[&scene, "--width", "0"]), "width");
    assert_bad_input(
        &lmanim(&[&scene, "--camera", "nope", "--out", "/tmp/x.#.exr"]),
        "main",
    );
    assert_bad_input(
        &lmanim(&[&scene, "--frames", "0..2", "--out", "/tmp/single.exr"]),
        "#",
    );
    assert_bad_input(&lmanim(&["/no/such/scene.gltf"]), "/no/such/scene.gltf");
    assert_bad_input(
        &lmanim(&[&scene, "--clip", "Nope", "--out", "/tmp/x.#.exr"]),
        "--clip",
    );
    assert_bad_input(&lmanim(&[&scene, "--h", "-1"]), "--h -1");
    assert_bad_input(&lmanim(&[&scene, "--ki", "9"]), "--ki 9");
    // Clap's own usage errors keep its exit code 2 (several lines of help).
    assert_eq!(lmanim(&[&scene, "--spp", "many"]).status.code(), Some(2));
}

#[test]
fn lattice_flags_set_h_and_ki() {
    let dir = tempfile::tempdir().unwrap();
    let stats = dir.path().join("stats.json");
    let pattern = dir.path().join("f.#.exr");
    let output = lmanim(&[
        &courtyard(),
        "--width",
        "32",
        "--height",
        "18",
        "--method",
        "lmm1",
        "--h",
        "0.2",
        "--ki",
        "2.1",
        "--no-cache",
        "--stats",
        stats.to_str().unwrap(),
        "--out",
        pattern.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(stderr(&output).contains("h = 0.2000 m (set), kI = 2.1"));
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    let mesh = &json["frames"][0]["lightmesh"];
    assert_eq!(mesh["h"].as_f64().map(|h| h as f32), Some(0.2));
    assert_eq!(mesh["ki"].as_f64().map(|k| k as f32), Some(2.1));
}

#[test]
fn a_bad_settings_file_is_named_with_its_line() {
    let dir = tempfile::tempdir().unwrap();
    let settings = dir.path().join("bad.ron");
    std::fs::write(&settings, "(\n  width: 64,\n  colour: true,\n)\n").unwrap();
    let output = lmanim(&[&courtyard(), "--settings", settings.to_str().unwrap()]);
    assert_bad_input(&output, "bad.ron:3");
}

#[test]
fn a_scene_without_a_camera_gets_a_framing_camera() {
    let dir = tempfile::tempdir().unwrap();
    let mut builder = GltfBuilder::new();
    let grey = builder
        .add_material(&Material {
            base_color: Vec3::splat(0.5).extend(1.0),
            metallic: 0.0,
            ..Material::default()
        })
        .unwrap();
    let floor = builder
        .add_geometry(&shapes::plane(Vec2::splat(2.0)))
        .unwrap();
    let cube = builder
        .add_geometry(&shapes::cuboid(Vec3::splat(0.3)))
        .unwrap();
    for (name, geometry, y) in [("floor", floor, 0.0), ("cube", cube, 0.3)] {
        let mesh = builder
            .add_mesh(
                name,
                &[Primitive {
                    geometry,
                    material: Some(grey),
                }],
            )
            .unwrap();
        builder
            .add_node(NodeDesc {
                translation: Vec3::new(0.0, y, 0.0),
                mesh: Some(mesh),
                ..NodeDesc::named(name)
            })
            .unwrap();
    }
    let lamp = builder
        .add_light(&Light {
            name: Some("lamp".into()),
            kind: LightKind::Point,
            color: Vec3::ONE,
            intensity: 20.0,
            range: None,
            radius: None,
            group: None,
        })
        .unwrap();
    builder
        .add_node(NodeDesc {
            translation: Vec3::new(1.0, 2.0, 1.0),
            light: Some(lamp),
            ..NodeDesc::named("lamp")
        })
        .unwrap();
    let scene = dir.path().join("nocamera.glb");
    builder.write_glb(&scene).unwrap();
    let frame = dir.path().join("frame.#.exr");
    let output = lmanim(&[
        scene.to_str().unwrap(),
        "--width",
        "32",
        "--height",
        "32",
        "--out",
        frame.to_str().unwrap(),
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    assert!(
        stderr(&output).contains("automatic framing camera"),
        "{}",
        stderr(&output)
    );
    let image = lmanim::output::read_exr(&dir.path().join("frame.0.exr")).unwrap();
    // The framing camera sees the whole floor: the centre is covered and lit.
    let centre = image.pixels[(16 * 32 + 16) as usize];
    assert_eq!(centre.w, 1.0);
    assert!(centre.x > 0.0);
}

/// `--contact-sheet` writes one labelled sheet of the run's frames at its
/// end, in the grid `--sheet-columns` and `--sheet-every` ask for; an
/// impossible grid is bad usage.
#[test]
fn a_contact_sheet_shows_the_runs_frames() {
    let dir = tempfile::tempdir().unwrap();
    let pattern = dir.path().join("frame.####.exr");
    let sheet = dir.path().join("sheet.png");
    let output = lmanim(&[
        &courtyard(),
        "--frames",
        "0..5",
        "--width",
        "120",
        "--height",
        "60",
        "--method",
        "whitted",
        "--out",
        pattern.to_str().unwrap(),
        "--contact-sheet",
        sheet.to_str().unwrap(),
        "--sheet-columns",
        "2",
        "--sheet-every",
        "2",
        "--sheet-thumb-width",
        "60",
        "--exposure",
        "1",
        "--quiet",
    ]);
    assert!(output.status.success(), "{}", stderr(&output));
    // Frames 0, 2 and 4: two rows of two cells of 60×30.
    let image = image::open(&sheet).expect("the sheet").to_rgba8();
    assert_eq!(image.dimensions(), (120, 60));
    let lit = |x: u32, y: u32| image.get_pixel(x, y).0[..3].iter().any(|&c| c > 0);
    assert!(lit(30, 45), "the third frame's cell holds its picture");
    assert_eq!(image.get_pixel(90, 45).0, [0, 0, 0, 0], "no fourth frame");

    for (flag, value) in [("--sheet-columns", "0"), ("--sheet-every", "0")] {
        let output = lmanim(&[&courtyard(), "--contact-sheet", "x.png", flag, value]);
        assert_bad_input(&output, &flag[2..].replace('-', "_"));
    }
}

/// A stopped shot resumed with `--skip-existing`: frames 4–6 are on disk
/// whole, frame 2 was cut short. Only 0–3 and 7 render; every frame then
/// equals the one of a whole run, and frame 7, rendered after the gap of
/// skipped frames, equals frame 7 rendered alone, bit for bit (the masks
/// reused across the gap are invalidated as a farm chunk's are).
#[test]
fn skip_existing_renders_only_missing_and_damaged_frames() {
    let dir = tempfile::tempdir().unwrap();
    let scene = courtyard();
    let render = |out: &Path, frames: &str, extra: &[&str]| -> Output {
        let pattern = out.join("frame.####.exr");
        let mut args = vec![scene.as_str(), "--frames", frames, "--width", "48"];
        args.extend(["--height", "27", "--method", "lmm1", "--no-cache"]);
        args.extend(["--out", pattern.to_str().unwrap()]);
        args.extend(extra);
        let output = lmanim(&args);
        assert!(output.status.success(), "{}", stderr(&output));
        output
    };
    let (whole, alone, resumed) = (
        dir.path().join("whole"),
        dir.path().join("alone"),
        dir.path().join("resumed"),
    );
    render(&whole, "0..8", &["--quiet"]);
    render(&alone, "7", &["--quiet"]);
    std::fs::create_dir_all(&resumed).unwrap();
    // The courtyard's settings ask for PNG previews: a frame is its EXR and its PNG.
    let name = |frame: u32, extension: &str| format!("frame.{frame:04}.{extension}");
    for frame in 4..=6 {
        for extension in ["exr", "png"] {
            let file = name(frame, extension);
            std::fs::copy(whole.join(&file), resumed.join(&file)).unwrap();
        }
    }
    let cut = std::fs::read(whole.join(name(2, "exr"))).unwrap();
    std::fs::write(resumed.join(name(2, "exr")), &cut[..cut.len() / 2]).unwrap();
    std::fs::copy(whole.join(name(2, "png")), resumed.join(name(2, "png"))).unwrap();

    let stats = dir.path().join("stats.json");
    let sheet = dir.path().join("sheet.png");
    let output = render(
        &resumed,
        "0..8",
        &[
            "--skip-existing",
            "--stats",
            stats.to_str().unwrap(),
            "--contact-sheet",
            sheet.to_str().unwrap(),
        ],
    );
    let said = stderr(&output);
    assert!(
        said.contains("rendered 5 frame(s)") && said.contains("skipped 3 frame(s) already on disk"),
        "{said}"
    );
    let json: serde_json::Value = serde_json::from_slice(&std::fs::read(&stats).unwrap()).unwrap();
    let rendered: Vec<u64> = (json["frames"].as_array().unwrap().iter())
        .map(|f| f["frame"].as_u64().unwrap())
        .collect();
    assert_eq!(rendered, [0, 1, 2, 3, 7]);
    assert_eq!(json["skipped"], serde_json::json!([4, 5, 6]));

    let read =
        |dir: &Path, frame: u32| lmanim::output::read_exr(&dir.join(name(frame, "exr"))).unwrap();
    for frame in 0..8 {
        assert_eq!(read(&resumed, frame), read(&whole, frame), "frame {frame}");
    }
    assert_eq!(
        read(&resumed, 7),
        read(&alone, 7),
        "frame 7 after the gap, and alone"
    );
    // The sheet shows all eight, the skipped ones read from disk: two
    // rows of six cells of 48×27.
    let image = image::open(&sheet).expect("the sheet").to_rgba8();
    assert_eq!(image.dimensions(), (6 * 48, 2 * 27));
    let lit = |x: u32, y: u32| image.get_pixel(x, y).0[3] > 0;
    assert!(
        (0..48).any(|x| (27..54).any(|y| lit(x + 48, y))),
        "frame 7's cell holds its picture"
    );
    assert!(
        (0..48).any(|x| (0..27).any(|y| lit(x + 5 * 48, y))),
        "skipped frame 5's cell holds its picture"
    );

    // A PNG-only run has no EXR to put a skipped frame on the sheet from.
    let preview = [
        scene.as_str(),
        "--preview",
        "--skip-existing",
        "--contact-sheet",
        "x.png",
    ];
    assert_bad_input(&lmanim(&preview), "skip_existing puts skipped frames");

    // Nothing missing: nothing rendered.
    let again = render(&resumed, "0..8", &["--skip-existing"]);
    assert!(
        stderr(&again).contains("rendered 0 frame(s)") && stderr(&again).contains("skipped 8"),
        "{}",
        stderr(&again)
    );
}
