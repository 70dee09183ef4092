//! `lmanim warm`: a farm job's first task computes the light-mesh masks
//! the frames will need and saves them to the disk cache, so that render
//! tasks start warm and write the frames a cold run writes.

mod common;

use std::path::{Path, PathBuf};

use common::cli::{assert_bad_input, lmanim};
use lmanim::output::read_exr;

/// The shot both the warm step and the renders take: the courtyard's
/// first three frames, small, by LMM1.
const SHOT: [&str; 8] = [
    "--frames", "0..3", "--width", "80", "--height", "45", "--method", "lmm1",
];

fn courtyard() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf")
}

/// Renders the courtyard's first three frames small with the cache in
/// `cache` (or none); the frames and the per-frame stats.
fn render(
    dir: &Path,
    name: &str,
    cache: Option<&Path>,
) -> (Vec<lmanim::output::Image>, serde_json::Value) {
    let scene = courtyard();
    let out = dir.join(format!("{name}.####.exr"));
    let stats = dir.join(format!("{name}.json"));
    let mut args = vec![scene.to_str().unwrap()];
    args.extend(SHOT);
    args.extend([
        "--exr-float",
        "--quiet",
        "--out",
        out.to_str().unwrap(),
        "--stats",
        stats.to_str().unwrap(),
    ]);
    match cache {
        Some(cache) => args.extend(["--cache", cache.to_str().unwrap()]),
        None => args.push("--no-cache"),
    }
    let run = lmanim(&args);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let frames = (0..3)
        .map(|frame| read_exr(&dir.join(format!("{name}.{frame:04}.exr"))).unwrap())
        .collect();
    let stats = serde_json::from_slice(&std::fs::read(stats).unwrap()).unwrap();
    (frames, stats)
}

#[test]
fn a_warmed_cache_gives_the_cold_frames_with_less_fill() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let scene = courtyard();
    let mut args = vec!["warm", scene.to_str().unwrap()];
    args.extend(SHOT);
    args.extend(["--cache", cache.to_str().unwrap()]);
    let warm = lmanim(&args);
    let report = String::from_utf8_lossy(&warm.stderr);
    assert!(warm.status.success(), "{report}");
    assert!(
        report.contains("warmed 3 frame(s)") && report.contains("mask bits computed"),
        "{report}"
    );
    assert!(!dir.path().read_dir().unwrap().any(|entry| {
        entry
            .unwrap()
            .path()
            .extension()
            .is_some_and(|ext| ext == "exr")
    }));

    let (cold, cold_stats) = render(dir.path(), "cold", None);
    let (warmed, warm_stats) = render(dir.path(), "warm", Some(&cache));
    assert_eq!(cold, warmed, "a warm start changes no pixel");
    let first = |stats: &serde_json::Value, field: &str| {
        stats["frames"][0]["lightmesh"][field].as_u64().unwrap()
    };
    assert!(first(&warm_stats, "bits_loaded") > 0);
    // LMM1's enclosure flags come from the warm task too.
    assert!(first(&cold_stats, "nodes_probed") > 0);
    assert_eq!(first(&warm_stats, "nodes_probed"), 0);
    // Only the dynamic layer (the rolling ball) is left to test.
    assert!(
        2 * first(&warm_stats, "fill_segments") < first(&cold_stats, "fill_segments"),
        "{} against {}",
        first(&warm_stats, "fill_segments"),
        first(&cold_stats, "fill_segments")
    );
}

#[test]
fn warm_refuses_a_run_with_nothing_to_warm() {
    let scene = courtyard();
    let scene = scene.to_str().unwrap();
    assert_bad_input(&lmanim(&["warm", scene, "--no-cache"]), "--no-cache");
    assert_bad_input(
        &lmanim(&["warm", scene, "--method", "whitted"]),
        "--method whitted",
    );
}
