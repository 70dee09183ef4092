//! The GPU's pipelines: a run compiles those its method needs before its
//! first frame, reports each (`--stats`: `gpu.pipelines`), and keeps the
//! driver's compiled code in lmanim's cache folder, so that the next run
//! on the machine makes them from the cache; a damaged cache file is
//! ignored with a warning; frames are the same bits with and without it.

mod common;

use std::path::{Path, PathBuf};

use common::cli::lmanim;
use common::*;

use lmanim::backend::Backend;
use lmanim::sequence::Sequence;
use lmanim::settings::{Method, Settings};
use lmanim::stats::FrameStats;

/// What the CLI runs below render: the courtyard's first frame, tiny,
/// by Whitted (its pipelines are the fewest to compile on lavapipe).
fn render(dir: &Path, name: &str, cache: &[&str]) -> (std::process::Output, serde_json::Value) {
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf");
    let out = dir.join(format!("{name}.####.exr"));
    let stats = dir.join(format!("{name}.json"));
    let mut args = vec![
        scene.to_str().expect("UTF-8 path"),
        "--frames",
        "0",
        "--width",
        "32",
        "--height",
        "18",
        "--backend",
        "gpu",
        "--method",
        "whitted",
        "--out",
        out.to_str().expect("UTF-8 path"),
        "--stats",
        stats.to_str().expect("UTF-8 path"),
    ];
    args.extend(cache);
    let run = lmanim(&args);
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    let stats = std::fs::read(&stats).expect("stats written");
    (run, serde_json::from_slice(&stats).expect("stats are JSON"))
}

/// The first frame's `gpu.pipelines`: (name, cached) of each.
fn pipelines(stats: &serde_json::Value) -> Vec<(String, bool)> {
    let list = stats["frames"][0]["gpu"]["pipelines"]
        .as_array()
        .expect("gpu.pipelines");
    (list.iter())
        .map(|made| {
            let name = made["name"].as_str().expect("name").to_owned();
            assert!(made["ms"].as_f64().expect("ms") >= 0.0);
            (name, made["cached"].as_bool().expect("cached"))
        })
        .collect()
}

fn exr(dir: &Path, name: &str) -> Vec<u8> {
    std::fs::read(dir.join(format!("{name}.0000.exr"))).expect("the frame is written")
}

/// The pipeline cache files in `cache`.
fn cache_files(cache: &Path) -> Vec<PathBuf> {
    let Ok(entries) = std::fs::read_dir(cache) else {
        return Vec::new();
    };
    (entries.map(|entry| entry.expect("entry").path()))
        .filter(|path| path.to_string_lossy().contains("gpu-pipelines-"))
        .collect()
}

/// Whether the run's adapter keeps a pipeline cache (wgpu's is Vulkan's).
fn keeps_a_pipeline_cache(stats: &serde_json::Value) -> bool {
    let adapter = stats["adapter"].as_str().unwrap_or_default();
    adapter.contains("(Vulkan")
}

#[test]
fn a_second_run_makes_its_pipelines_from_the_cache_and_a_damaged_one_is_ignored() {
    if common::gpu::backend().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let cache = dir.path().join("cache");
    let with_cache = ["--cache", cache.to_str().expect("UTF-8 path")];

    let (_, first) = render(dir.path(), "first", &with_cache);
    let made = pipelines(&first);
    let names: Vec<&str> = made.iter().map(|(name, _)| name.as_str()).collect();
    for needed in [
        "camera_rays",
        "closest_hit",
        "surface",
        "direct_light",
        "resolve",
    ] {
        assert!(names.contains(&needed), "{needed} in {names:?}");
    }
    for unneeded in ["light_mesh", "fill_segments", "any_hit", "first_hits"] {
        assert!(!names.contains(&unneeded), "a Whitted run made {unneeded}");
    }
    assert!(made.iter().all(|(_, cached)| !cached), "{made:?}");
    if !keeps_a_pipeline_cache(&first) {
        eprintln!(
            "skipped the cache's checks: {} keeps none",
            first["adapter"]
        );
        return;
    }
    let files = cache_files(&cache);
    assert_eq!(files.len(), 1, "{files:?}");

    let (_, second) = render(dir.path(), "second", &with_cache);
    let again = pipelines(&second);
    assert_eq!(again.len(), made.len(), "{again:?}");
    assert!(again.iter().all(|(_, cached)| *cached), "{again:?}");
    assert_eq!(exr(dir.path(), "second"), exr(dir.path(), "first"));

    std::fs::write(&files[0], b"LMANIMPC but torn").expect("damage the file");
    let (run, damaged) = render(dir.path(), "damaged", &with_cache);
    let stderr = String::from_utf8_lossy(&run.stderr);
    let warning = format!("ignoring the GPU pipeline cache {}", files[0].display());
    assert!(stderr.contains(&warning), "{stderr}");
    assert!(pipelines(&damaged).iter().all(|(_, cached)| !cached));
    assert_eq!(exr(dir.path(), "damaged"), exr(dir.path(), "first"));
    let rewritten = std::fs::read(&files[0]).expect("the file is written anew");
    assert!(rewritten.starts_with(b"LMANIMPC") && rewritten.len() > 20);

    let no_cache = dir.path().join("no-cache");
    std::fs::create_dir(&no_cache).expect("dir");
    let (_, _) = render(&no_cache, "uncached", &["--no-cache"]);
    assert_eq!(exr(&no_cache, "uncached"), exr(dir.path(), "first"));
    assert!(cache_files(&no_cache.join("cache")).is_empty());
}

/// The names of the pipelines made for a frame.
fn made_in(stats: &FrameStats) -> Vec<&'static str> {
    let gpu = stats.gpu.as_ref().expect("the GPU backend reports");
    gpu.pipelines.iter().map(|made| made.name).collect()
}

/// The scene's frame rendered anew (a sequence of its own: no frame is
/// a copy of the last) on `gpu`, which keeps its pipelines.
fn render_frame(gpu: &mut Backend, settings: &Settings) -> FrameStats {
    let mut sequence = Sequence::new(box_under_a_lamp().0, "box".into()).unwrap();
    let mut stats = FrameStats::default();
    let placed = sequence.advance(0.0, settings, &mut stats).unwrap();
    sequence.render(gpu, &placed, settings, &mut stats).unwrap();
    stats
}

/// Preparing compiles what the method's frames record: the first frame
/// reports them, and neither it nor the next compiles another. A pass the
/// preparation left out (another method's) is compiled where it is first
/// recorded, and reported with that frame.
#[test]
fn a_run_compiles_what_its_frames_need_before_the_first() {
    let Some((mut gpu, _)) = common::gpu::backend_to_compare() else {
        return;
    };
    let mut settings = settings(24, 16);
    settings.method = Method::Lmm1;
    settings.lightmesh.h = Some(0.25);
    let sequence = Sequence::new(box_under_a_lamp().0, "box".into()).unwrap();
    let mut reported = Vec::new();
    sequence.prepare_pipelines(&gpu, &settings, |compiled, of| {
        reported.push((compiled, of))
    });
    let of = reported.last().expect("progress").1;
    let expected: Vec<(usize, usize)> = (0..=of).map(|compiled| (compiled, of)).collect();
    assert_eq!(reported, expected, "0 of n first, then one by one");

    let first = render_frame(&mut gpu, &settings);
    let prepared = made_in(&first);
    assert_eq!(prepared.len(), of, "{prepared:?}");
    for needed in [
        "light_mesh_coverage",
        "gather_points",
        "patch_pool",
        "fill_segments",
        "summarise_tiles",
        "summarise_around",
        "light_mesh",
    ] {
        assert!(prepared.contains(&needed), "{needed} in {prepared:?}");
    }
    assert!(!prepared.contains(&"direct_light"), "{prepared:?}");
    assert_eq!(
        made_in(&render_frame(&mut gpu, &settings)),
        Vec::<&str>::new()
    );

    settings.method = Method::Whitted;
    let whitted = render_frame(&mut gpu, &settings);
    assert_eq!(made_in(&whitted), ["direct_light"]);
}
