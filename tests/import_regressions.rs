//! Every file the fuzzer (`import_fuzz.rs`) found making import panic,
//! kept under `tests/import_regressions/` as it was shrunk, and replayed
//! here through the `lmanim` binary: each is now refused with one line
//! that names its fault, exit code 2, and no panic text.
//!
//! A file's name says what was wrong with it (`<fault>-<fingerprint>.gltf`);
//! `EXPECTED` gives the words its message must have.

use std::path::Path;
use std::process::Command;

/// Fault names (the file name's prefix) and words of their message.
const EXPECTED: &[(&str, &str)] = &[
    ("channel_node_out_of_range", ".target.node: is "),
    (
        "pointer_path_without_pointer",
        "has path \"pointer\" but no KHR_animation_pointer pointer string",
    ),
];

#[test]
fn every_kept_crash_is_refused_in_one_line_without_panic_text() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/import_regressions");
    let mut files: Vec<_> = std::fs::read_dir(&dir)
        .expect("tests/import_regressions")
        .map(|entry| entry.expect("entry").path())
        .collect();
    files.sort();
    assert!(files.len() >= 8, "the kept crashes are gone: {files:?}");
    let mut failures = Vec::new();
    for file in &files {
        let name = file
            .file_name()
            .expect("name")
            .to_string_lossy()
            .into_owned();
        let Some(&(_, words)) = EXPECTED.iter().find(|(fault, _)| name.starts_with(fault)) else {
            failures.push(format!("{name}: no expected message for this fault name"));
            continue;
        };
        let output = Command::new(env!("CARGO_BIN_EXE_lmanim"))
            .arg(file)
            .env("RUST_BACKTRACE", "1")
            .output()
            .expect("run lmanim");
        let stderr = String::from_utf8_lossy(&output.stderr);
        let refused = output.status.code() == Some(2)
            && stderr.lines().count() == 1
            && stderr.contains(&name)
            && stderr.contains(words)
            && !stderr.contains("panicked");
        if !refused {
            failures.push(format!(
                "{name}: exit {:?}, stderr {stderr:?}",
                output.status.code()
            ));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
