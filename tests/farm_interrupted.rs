//! A farm worker killed in the middle of its chunk (SIGKILL: no chance to
//! clean up) leaves no half-written frame under a frame's name and no
//! damaged cache: every frame it finished reads back whole, and running
//! the chunk again completes the shot with the frames of one clean run.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::{Duration, Instant};

use lmanim::output::read_exr;

fn courtyard() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf")
}

fn lmanim(dir: &Path, out: &str, cache: &[&str]) -> Command {
    let mut command = Command::new(env!("CARGO_BIN_EXE_lmanim"));
    command
        .arg(courtyard())
        .args([
            "--frames", "0-11", "--method", "lmm1", "--width", "160", "--height", "90",
        ])
        .args(["--exr-float", "--quiet", "--out", out])
        .args(cache)
        .current_dir(dir);
    command
}

fn frames(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> = (std::fs::read_dir(dir).unwrap())
        .map(|entry| entry.unwrap().file_name().into_string().unwrap())
        .filter(|name| name.starts_with("frame.") && name.ends_with(".exr"))
        .collect();
    names.sort();
    names
}

#[test]
fn a_worker_killed_midway_leaves_whole_frames_and_its_rerun_completes_the_shot() {
    let dir = tempfile::tempdir().unwrap();
    let shot = dir.path().join("shot");
    let cache = ["--cache", "cache"];
    // Kill the worker once it has written a few frames.
    let mut worker = lmanim(dir.path(), "shot/frame.####.exr", &cache)
        .spawn()
        .unwrap();
    let started = Instant::now();
    while (!shot.exists() || frames(&shot).len() < 3) && started.elapsed() < Duration::from_secs(60)
    {
        std::thread::sleep(Duration::from_millis(5));
    }
    worker.kill().unwrap();
    worker.wait().unwrap();
    let written = frames(&shot);
    assert!(
        !written.is_empty() && written.len() < 12,
        "killed midway: {written:?}"
    );
    for name in &written {
        read_exr(&shot.join(name)).unwrap_or_else(|error| panic!("{name} is damaged: {error}"));
    }

    // The rerun reads the cache the killed worker left (if any) and
    // writes the whole shot.
    let rerun = lmanim(dir.path(), "shot/frame.####.exr", &cache)
        .output()
        .unwrap();
    assert!(
        rerun.status.success(),
        "{}",
        String::from_utf8_lossy(&rerun.stderr)
    );
    let clean = lmanim(dir.path(), "clean/frame.####.exr", &["--no-cache"])
        .output()
        .unwrap();
    assert!(clean.status.success());
    let (shot_frames, clean_frames) = (frames(&shot), frames(&dir.path().join("clean")));
    assert_eq!(shot_frames, clean_frames);
    for name in &shot_frames {
        let (a, b) = (
            read_exr(&shot.join(name)).unwrap(),
            read_exr(&dir.path().join("clean").join(name)).unwrap(),
        );
        assert!(a == b, "{name} differs from the clean run's");
    }
}
