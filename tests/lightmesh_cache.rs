//! The disk cache of static masks: a sequence started with a warm cache
//! renders the same pixels as a cold one while tracing fewer bits; another
//! geometry or lattice gets another file; damaged files are reported and
//! ignored; concurrent savers leave the union; the CLI flags steer it.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Barrier, Mutex, OnceLock};

use common::*;
use glam::{DMat4, DVec3, Vec3};

use lmanim::lightmesh::cache::{CacheKey, StaticMaskCache};
use lmanim::output::Image;
use lmanim::scene::{LightKind, SceneDesc};
use lmanim::sequence::Sequence;
use lmanim::settings::{Method, Settings};
use lmanim::stats::FrameStats;

const TIMES: [f64; 2] = [0.0, 2.0];

/// A yard: a floor, a wall and a block (static), a box sliding past
/// (dynamic), two lamps and a camera that moves, so frames see different
/// nodes. `wall_x` moves the wall, changing the static geometry;
/// `lamp_moves` animates the second lamp.
fn yard(wall_x: f32, lamp_moves: bool) -> SceneDesc {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.6)));
    let wall = [
        Vec3::new(wall_x, 0.0, -6.0),
        Vec3::new(wall_x, 0.0, 6.0),
        Vec3::new(wall_x, 5.0, 6.0),
        Vec3::new(wall_x, 5.0, -6.0),
    ];
    add_quads(&mut scene, &[floor_quad(0.0, 12.0), wall], 4, m);
    add_quads(&mut scene, &box_quads(Vec3::new(2.0, 1.0, 2.0), 1.0), 1, m);
    let mover = add_quads(&mut scene, &box_quads(Vec3::new(0.0, 0.5, 0.0), 0.5), 1, m);
    add_light(
        &mut scene,
        LightKind::Point,
        200.0,
        DMat4::from_translation(DVec3::new(0.0, 4.0, 0.0)),
    );
    let lamp = add_light(
        &mut scene,
        LightKind::Point,
        100.0,
        DMat4::from_translation(DVec3::new(4.0, 3.0, -3.0)),
    );
    let camera = add_camera(
        &mut scene,
        perspective(0.9),
        look_at(DVec3::new(-6.0, 5.0, 8.0), DVec3::new(2.0, 0.0, 0.0)),
    );
    for light in &mut scene.lights {
        light.radius = Some(0.2);
    }
    add_clip(
        &mut scene,
        "yard",
        vec![
            linear_translation(
                mover,
                Vec3::new(-4.0, 0.0, 1.0),
                Vec3::new(-1.0, 0.0, 3.0),
                2.0,
            ),
            linear_translation(
                camera,
                Vec3::new(-6.0, 5.0, 8.0),
                Vec3::new(-2.0, 6.0, 9.0),
                2.0,
            ),
        ],
    );
    scene.nodes[mover].animated = true;
    scene.nodes[camera].animated = true;
    if lamp_moves {
        scene.animations[0].channels.push(linear_translation(
            lamp,
            Vec3::new(4.0, 3.0, -3.0),
            Vec3::new(3.0, 3.5, -1.0),
            2.0,
        ));
        scene.nodes[lamp].animated = true;
    }
    scene
}

fn lmm_settings(h: f32) -> Settings {
    let mut settings = settings(40, 24);
    settings.method = Method::Lmm;
    settings.lightmesh.h = Some(h);
    settings
}

/// Renders `times` in one sequence using the disk cache in `cache` (or
/// none); returns the images, the stats and the sequence (to save).
fn render(
    scene: &SceneDesc,
    settings: &Settings,
    cache: Option<&Path>,
    times: &[f64],
) -> (Vec<Image>, Vec<FrameStats>, Sequence) {
    let mut backend =
        lmanim::backend::Backend::new(lmanim::settings::BackendKind::Cpu, Some(2)).unwrap();
    let mut sequence = Sequence::new(scene.clone(), "yard".into()).unwrap();
    sequence.set_cache_dir(cache.map(Path::to_path_buf));
    let mut images = Vec::new();
    let mut all_stats = Vec::new();
    for &time in times {
        let mut stats = FrameStats::default();
        let placed = sequence.advance(time, settings, &mut stats).unwrap();
        images.push(
            sequence
                .render(&mut backend, &placed, settings, &mut stats)
                .unwrap(),
        );
        all_stats.push(stats);
    }
    (images, all_stats, sequence)
}

fn cache_files(dir: &Path) -> Vec<PathBuf> {
    let mut files: Vec<PathBuf> = std::fs::read_dir(dir)
        .map(|entries| entries.map(|entry| entry.unwrap().path()).collect())
        .unwrap_or_default();
    files.sort();
    files
}

/// The key a cache file is named by.
fn key_of(file: &Path) -> CacheKey {
    let stem = file.file_stem().unwrap().to_str().unwrap();
    CacheKey(u128::from_str_radix(stem, 16).unwrap())
}

fn mesh_stats(stats: &FrameStats) -> lmanim::lightmesh::LightMeshStats {
    stats.lightmesh.unwrap()
}

/// Warnings logged by the library, so tests can see a file reported.
fn warnings() -> &'static Mutex<Vec<String>> {
    static WARNINGS: OnceLock<Mutex<Vec<String>>> = OnceLock::new();
    struct Recorder;
    impl log::Log for Recorder {
        fn enabled(&self, metadata: &log::Metadata) -> bool {
            metadata.level() <= log::Level::Warn
        }
        fn log(&self, record: &log::Record) {
            if self.enabled(record.metadata()) {
                warnings().lock().unwrap().push(record.args().to_string());
            }
        }
        fn flush(&self) {}
    }
    static RECORDER: Recorder = Recorder;
    WARNINGS.get_or_init(|| {
        let _ = log::set_logger(&RECORDER);
        log::set_max_level(log::LevelFilter::Warn);
        Mutex::new(Vec::new())
    })
}

#[test]
fn a_warm_cache_gives_the_same_pixels_for_fewer_bits() {
    let dir = tempfile::tempdir().unwrap();
    // The second lamp moves: its bits where it started are saved too.
    let scene = yard(6.0, true);
    let settings = lmm_settings(0.25);
    let (cold, cold_stats, _) = render(&scene, &settings, None, &TIMES);
    let first_frame_bits = render(&scene, &settings, None, &TIMES[..1])
        .2
        .light_mesh()
        .unwrap()
        .masks()
        .static_bits();

    let (first, first_stats, sequence) = render(&scene, &settings, Some(dir.path()), &TIMES);
    assert_eq!(first, cold, "an empty cache changes nothing");
    assert_eq!(mesh_stats(&first_stats[0]).bits_loaded, 0);
    assert!(
        cache_files(dir.path()).is_empty(),
        "nothing is written before the save"
    );
    sequence.save_cache().unwrap();
    let files = cache_files(dir.path());
    assert_eq!(files.len(), 1, "{files:?}");
    assert_eq!(files[0].extension().unwrap(), "lmcache");

    let (warm, warm_stats, _) = render(&scene, &settings, Some(dir.path()), &TIMES);
    assert_eq!(warm, cold, "a warm cache renders the same pixels");
    let (cold0, warm0) = (mesh_stats(&cold_stats[0]), mesh_stats(&warm_stats[0]));
    assert!(
        warm0.bits_loaded >= first_frame_bits,
        "every static bit of the first frame is loaded, the moved lamp's too: {} of {first_frame_bits}",
        warm0.bits_loaded
    );
    assert!(
        warm0.bits_computed < cold0.bits_computed,
        "{} bits traced warm, {} cold",
        warm0.bits_computed,
        cold0.bits_computed
    );
    assert_eq!(
        mesh_stats(&warm_stats[1]).bits_loaded,
        0,
        "only the first frame loads"
    );
    assert!(warm_stats[0].stages.contains_key("cache_load"));
    assert!(!warm_stats[1].stages.contains_key("cache_load"));
    assert!(!cold_stats[0].stages.contains_key("cache_load"));

    // A run whose every static bit came from the file writes nothing: the
    // file removed after the load stays away.
    let (_, stats, sequence) = render(&scene, &settings, Some(dir.path()), &TIMES[..1]);
    assert!(mesh_stats(&stats[0]).bits_loaded > 0);
    std::fs::remove_file(&files[0]).unwrap();
    sequence.save_cache().unwrap();
    assert!(
        cache_files(dir.path()).is_empty(),
        "a warm run rewrote the file"
    );
}

/// LMM1's enclosure flags depend on the static geometry, the lattice and
/// the probes' reach alone: a warm run takes them from the file and probes
/// no node its first frame needs, for the same pixels; a run of another kI
/// (another reach) probes its own.
#[test]
fn a_warm_cache_holds_lmm1s_enclosure_flags() {
    let dir = tempfile::tempdir().unwrap();
    let scene = yard(6.0, false);
    let mut settings = lmm_settings(0.25);
    settings.method = Method::Lmm1;
    let (cold, cold_stats, _) = render(&scene, &settings, None, &TIMES[..1]);
    assert!(
        mesh_stats(&cold_stats[0]).nodes_probed > 0,
        "the yard has enclosed nodes to probe"
    );
    let (_, _, sequence) = render(&scene, &settings, Some(dir.path()), &TIMES[..1]);
    sequence.save_cache().unwrap();

    let (warm, warm_stats, _) = render(&scene, &settings, Some(dir.path()), &TIMES[..1]);
    assert_eq!(warm, cold, "flags from the file give the same pixels");
    assert_eq!(mesh_stats(&warm_stats[0]).nodes_probed, 0);

    settings.lightmesh.ki += 0.5;
    let (wider_cold, wider_cold_stats, _) = render(&scene, &settings, None, &TIMES[..1]);
    let (wider, wider_stats, _) = render(&scene, &settings, Some(dir.path()), &TIMES[..1]);
    assert_eq!(wider, wider_cold);
    assert!(
        mesh_stats(&wider_stats[0]).bits_loaded > 0,
        "the bits still serve"
    );
    assert_eq!(
        mesh_stats(&wider_stats[0]).nodes_probed,
        mesh_stats(&wider_cold_stats[0]).nodes_probed,
        "flags of another reach are not taken"
    );
}

#[test]
fn another_geometry_or_lattice_uses_another_file() {
    let dir = tempfile::tempdir().unwrap();
    let settings = lmm_settings(0.25);
    let (_, _, sequence) = render(&yard(6.0, false), &settings, Some(dir.path()), &TIMES[..1]);
    sequence.save_cache().unwrap();

    let moved_wall = yard(6.5, false);
    let (images, stats, sequence) = render(&moved_wall, &settings, Some(dir.path()), &TIMES[..1]);
    assert_eq!(mesh_stats(&stats[0]).bits_loaded, 0, "another geometry");
    assert_eq!(images, render(&moved_wall, &settings, None, &TIMES[..1]).0);
    sequence.save_cache().unwrap();

    let finer = lmm_settings(0.2);
    let (_, stats, sequence) = render(&yard(6.0, false), &finer, Some(dir.path()), &TIMES[..1]);
    assert_eq!(mesh_stats(&stats[0]).bits_loaded, 0, "another h");
    sequence.save_cache().unwrap();
    assert_eq!(cache_files(dir.path()).len(), 3);
}

#[test]
fn damaged_files_are_reported_and_ignored() {
    let warnings = warnings();
    let scene = yard(6.0, false);
    let settings = lmm_settings(0.25);
    let (cold, _, _) = render(&scene, &settings, None, &TIMES[..1]);
    let source = tempfile::tempdir().unwrap();
    let (_, _, sequence) = render(&scene, &settings, Some(source.path()), &TIMES[..1]);
    sequence.save_cache().unwrap();
    let good_file = cache_files(source.path()).remove(0);
    let good = std::fs::read(&good_file).unwrap();

    let mut flipped = good.clone();
    let middle = flipped.len() / 2;
    flipped[middle] ^= 0x01;
    let mut magic = good.clone();
    magic[..8].copy_from_slice(b"NOTMASKS");
    let damages: [(&str, Vec<u8>); 4] = [
        ("truncated", good[..good.len() - 9].to_vec()),
        ("flipped", flipped),
        ("magic", magic),
        ("empty", Vec::new()),
    ];
    for (name, bytes) in damages {
        let dir = tempfile::tempdir().unwrap();
        let file = dir.path().join(good_file.file_name().unwrap());
        std::fs::write(&file, bytes).unwrap();
        let (images, stats, _) = render(&scene, &settings, Some(dir.path()), &TIMES[..1]);
        assert_eq!(images, cold, "{name}");
        assert_eq!(mesh_stats(&stats[0]).bits_loaded, 0, "{name}");
        let reported = warnings
            .lock()
            .unwrap()
            .iter()
            .any(|w| w.contains(&file.display().to_string()) && w.contains("ignored"));
        assert!(reported, "{name}: {:?}", warnings.lock().unwrap());
    }
}

#[test]
fn concurrent_savers_leave_the_union() {
    let scene = yard(6.0, false);
    let settings = lmm_settings(0.25);
    // Two workers rendering different frames see different nodes.
    let workers: Vec<(Sequence, Vec<lmanim::render::light::RenderLight>)> = TIMES
        .iter()
        .map(|&time| {
            let (_, _, mut sequence) = render(&scene, &settings, None, &[time]);
            let lights = sequence.place(&settings).unwrap().lights;
            (sequence, lights)
        })
        .collect();
    let mut expected = StaticMaskCache::default();
    for (sequence, lights) in &workers {
        expected.merge(StaticMaskCache::from_store(
            sequence.light_mesh().unwrap().masks(),
            lights,
        ));
    }
    let alone =
        StaticMaskCache::from_store(workers[0].0.light_mesh().unwrap().masks(), &workers[0].1);
    assert!(expected.bits() > alone.bits(), "the workers' bits differ");

    for _ in 0..4 {
        let dir = tempfile::tempdir().unwrap();
        // Both render before either saves, so neither loads anything.
        let workers: Vec<Sequence> = TIMES
            .iter()
            .map(|&time| render(&scene, &settings, Some(dir.path()), &[time]).2)
            .collect();
        let barrier = Barrier::new(workers.len());
        std::thread::scope(|scope| {
            for sequence in &workers {
                let barrier = &barrier;
                scope.spawn(move || {
                    barrier.wait();
                    sequence.save_cache().unwrap();
                });
            }
        });
        let files = cache_files(dir.path());
        assert_eq!(
            files.len(),
            1,
            "no lock or temporary file is left: {files:?}"
        );
        let saved = std::fs::read(&files[0]).unwrap();
        let saved = StaticMaskCache::decode(&saved, key_of(&files[0])).unwrap();
        assert!(
            saved == expected,
            "the file holds {} bits, the union {}",
            saved.bits(),
            expected.bits()
        );
    }
}

fn courtyard() -> String {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("animations/courtyard.gltf")
        .display()
        .to_string()
}

/// Runs the binary in `cwd` with a small LMM1 render of the courtyard.
fn lmanim(cwd: &Path, extra: &[&str]) -> std::process::Output {
    let output = Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args([
            courtyard().as_str(),
            "--width",
            "32",
            "--height",
            "18",
            "--method",
            "lmm1",
            "--out",
            cwd.join("f.#.exr").to_str().unwrap(),
            "--stats",
            cwd.join("stats.json").to_str().unwrap(),
        ])
        .args(extra)
        .current_dir(cwd)
        .output()
        .expect("the binary runs");
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

fn bits_loaded(cwd: &Path) -> u64 {
    let stats: serde_json::Value =
        serde_json::from_slice(&std::fs::read(cwd.join("stats.json")).unwrap()).unwrap();
    stats["frames"][0]["lightmesh"]["bits_loaded"]
        .as_u64()
        .unwrap()
}

#[test]
fn cli_flags_choose_the_cache_directory_or_none() {
    let cwd = tempfile::tempdir().unwrap();
    lmanim(cwd.path(), &["--no-cache"]);
    assert!(
        !cwd.path().join("cache").exists(),
        "--no-cache writes nothing"
    );

    lmanim(cwd.path(), &[]);
    assert_eq!(
        cache_files(&cwd.path().join("cache")).len(),
        1,
        "the default"
    );

    let elsewhere = cwd.path().join("elsewhere");
    let dir = elsewhere.to_str().unwrap();
    lmanim(cwd.path(), &["--cache", dir]);
    assert_eq!(bits_loaded(cwd.path()), 0);
    assert_eq!(cache_files(&elsewhere).len(), 1);
    lmanim(cwd.path(), &["--cache", dir]);
    assert!(bits_loaded(cwd.path()) > 0, "the second run loads");
    lmanim(cwd.path(), &["--no-cache"]);
    assert_eq!(bits_loaded(cwd.path()), 0, "--no-cache reads nothing");
}
