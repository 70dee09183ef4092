//! Running the `lmanim` binary in a test, and what such a test asserts
//! of its failures.

use std::process::{Command, Output};

/// Runs the binary outside the repository, so that its default light-mesh
/// cache (`cache/` in the current directory) never lands in the tree.
pub fn lmanim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args(args)
        .current_dir(std::env::temp_dir())
        .output()
        .expect("the binary runs")
}

/// Asserts a refusal of bad input or bad usage: exit code 2 and one line
/// on stderr holding `needle`.
pub fn assert_bad_input(output: &Output, needle: &str) {
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert_eq!(output.status.code(), Some(2), "{stderr}");
    let lines: Vec<&str> = stderr
        .lines()
        .filter(|line| !line.trim().is_empty())
        .collect();
    assert_eq!(lines.len(), 1, "one line: {stderr}");
    assert!(lines[0].contains(needle), "'{needle}' in {stderr}");
}

/// Renders the courtyard's `frames` (`--frames` text) by LMM1 in one run, without the
/// disk cache, with `settings`, to `dir`/frame.####.exr: what a farm's
/// chunks of the same frames must write.
pub fn courtyard_in_one_run(frames: &str, settings: &std::path::Path, dir: &std::path::Path) {
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf");
    let out = dir.join("frame.####.exr");
    let run = lmanim(&[
        scene.to_str().expect("UTF-8 path"),
        "--frames",
        frames,
        "--method",
        "lmm1",
        "--no-cache",
        "--quiet",
        "--settings",
        settings.to_str().expect("UTF-8 path"),
        "--out",
        out.to_str().expect("UTF-8 path"),
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
}
