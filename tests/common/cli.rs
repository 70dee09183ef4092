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
