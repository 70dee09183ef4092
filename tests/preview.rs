//! `--preview`: a quarter of the settings' size, LMM1 on the coarse
//! lattice the accuracy study puts on its Pareto front, PNG frames only;
//! other flags still override it.

mod common;

use std::path::Path;

use common::cli::lmanim;
use lmanim::settings::{Method, Settings};

fn courtyard() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf");
    path.to_str().expect("UTF-8").to_owned()
}

#[test]
fn the_preset_is_small_coarse_and_png_only() {
    let full = Settings {
        width: 1280,
        height: 720,
        spp: 4,
        method: Method::Area,
        ..Settings::default()
    };
    let preview = full.clone().preview();
    assert_eq!((preview.width, preview.height, preview.spp), (320, 180, 1));
    assert_eq!(preview.method, Method::Lmm1);
    assert_eq!(
        (preview.lightmesh.ki, preview.lightmesh.coarseness),
        (2.1, 1.5)
    );
    assert!(!preview.exr && preview.png);
    assert!(preview.validate().is_ok());
    // What the preset does not touch stays the scene's.
    assert_eq!((preview.fps, preview.max_depth), (full.fps, full.max_depth));
}

#[test]
fn a_preview_writes_pngs_at_a_quarter_size_and_no_exr() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("frame.####.exr");
    let stats = dir.path().join("stats.json");
    // The courtyard's settings ask for 640×360 and LMM.
    let run = lmanim(&[
        &courtyard(),
        "--preview",
        "--frames",
        "0..2",
        "--out",
        out.to_str().expect("UTF-8"),
        "--stats",
        stats.to_str().expect("UTF-8"),
        "--no-cache",
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let mut names: Vec<String> = std::fs::read_dir(dir.path())
        .expect("dir")
        .filter_map(|entry| entry.ok()?.file_name().into_string().ok())
        .collect();
    names.sort();
    assert_eq!(names, ["frame.0000.png", "frame.0001.png", "stats.json"]);
    let png = image::open(dir.path().join("frame.0000.png")).expect("PNG");
    assert_eq!((png.width(), png.height()), (160, 90));
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&stats).expect("stats")).expect("JSON");
    assert_eq!(stats["method"], "lmm1");
    // The courtyard's lamps have a median radius of 0.15 m: h = 1.5 R / 2.1.
    let h = stats["frames"][0]["lightmesh"]["h"].as_f64().expect("h");
    assert!((h - 1.5 * 0.15 / 2.1).abs() < 1e-6, "h = {h}");
}

#[test]
fn flags_override_the_preset() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("frame.####.exr");
    let run = lmanim(&[
        &courtyard(),
        "--preview",
        "--width",
        "48",
        "--height",
        "24",
        "--method",
        "whitted",
        "--out",
        out.to_str().expect("UTF-8"),
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let png = image::open(dir.path().join("frame.0000.png")).expect("PNG");
    assert_eq!((png.width(), png.height()), (48, 24));
    assert!(!dir.path().join("frame.0000.exr").exists());
}

#[test]
fn a_run_that_would_write_nothing_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let settings = dir.path().join("none.ron");
    std::fs::write(&settings, "(exr: false, png: false)").expect("write");
    let run = lmanim(&[
        &courtyard(),
        "--settings",
        settings.to_str().expect("UTF-8"),
    ]);
    common::cli::assert_bad_input(&run, "would write nothing");
    std::fs::write(&settings, "(lightmesh: (coarseness: 0.0))").expect("write");
    let run = lmanim(&[
        &courtyard(),
        "--settings",
        settings.to_str().expect("UTF-8"),
    ]);
    common::cli::assert_bad_input(&run, "lightmesh.coarseness");
}
