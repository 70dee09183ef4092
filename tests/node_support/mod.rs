//! Node packages that tests run as independent references (three.js, the
//! Khronos glTF validator): each lives in a folder under `tests/` with a
//! pinned `package.json` and lock file, installed with `npm ci` on first use.
//! Node and npm are required; without them a test fails and says why.
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};
use std::process::Command;

use serde_json::Value;

/// The folder `tests/<name>`, with Node and npm on PATH and the locked
/// packages installed (`package` is the one whose presence means done).
/// `purpose` names what needs them, for the failure message.
pub fn node_package_dir(name: &str, package: &str, purpose: &str) -> PathBuf {
    for tool in ["node", "npm"] {
        let found = Command::new(tool)
            .arg("--version")
            .output()
            .is_ok_and(|output| output.status.success());
        assert!(
            found,
            "`{tool}` is required by {purpose} and was not found on PATH; \
             install Node.js (v18 or later) with npm"
        );
    }
    let dir = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests")
        .join(name);
    if dir
        .join("node_modules")
        .join(package)
        .join("package.json")
        .is_file()
    {
        return dir;
    }
    let output = Command::new("npm")
        .args(["ci", "--no-audit", "--no-fund"])
        .current_dir(&dir)
        .output()
        .expect("run npm ci");
    assert!(
        output.status.success(),
        "`npm ci` in {} failed (is the npm registry reachable?):\n{}",
        dir.display(),
        String::from_utf8_lossy(&output.stderr)
    );
    dir
}

/// The Khronos glTF validator's JSON report on `file`; its messages and
/// counts are printed (shown with `--nocapture`).
pub fn khronos_report(file: &Path) -> Value {
    let package_dir = node_package_dir(
        "gltf_validator",
        "gltf-validator",
        "the Khronos glTF validator",
    );
    let output = Command::new("node")
        .arg(package_dir.join("validate.mjs"))
        .arg(file)
        .current_dir(package_dir)
        .output()
        .expect("start node");
    assert!(
        output.status.success(),
        "the glTF validator failed:\n{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let report: Value = serde_json::from_slice(&output.stdout).expect("validator JSON");
    let issues = &report["issues"];
    for message in issues["messages"].as_array().into_iter().flatten() {
        println!(
            "{} (severity {}) at {}: {}",
            message["code"], message["severity"], message["pointer"], message["message"]
        );
    }
    println!(
        "validator {}: {} errors, {} warnings, {} infos, {} hints",
        report["validatorVersion"],
        issues["numErrors"],
        issues["numWarnings"],
        issues["numInfos"],
        issues["numHints"]
    );
    report
}
