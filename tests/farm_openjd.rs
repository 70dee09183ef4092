//! The Open Job Description template (`farm/openjd/lmanim.yaml`), checked
//! and run by OpenJD's own CLI (`openjd`, from the PyPI package
//! `openjd-cli`): its warm step and three render chunks write the frames
//! one lmanim run writes, bit for bit. CI installs the CLI and names it in
//! `LMANIM_OPENJD`; elsewhere the test looks for `openjd` on the PATH and
//! says so when there is none.

mod common;

use std::path::{Path, PathBuf};
use std::process::Command;

use lmanim::output::read_exr;

/// The `openjd` command, or None (with the reason) off CI.
fn openjd() -> Option<PathBuf> {
    let named = std::env::var_os("LMANIM_OPENJD").map(PathBuf::from);
    let command = named.unwrap_or_else(|| PathBuf::from("openjd"));
    match Command::new(&command).arg("--version").output() {
        Ok(output) if output.status.success() => Some(command),
        _ if std::env::var_os("CI").is_none() => {
            eprintln!("skipped: no openjd (pip install openjd-cli, or set LMANIM_OPENJD)");
            None
        }
        _ => panic!("CI must install openjd-cli and set LMANIM_OPENJD"),
    }
}

fn template() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("farm/openjd/lmanim.yaml")
}

fn courtyard() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf")
}

fn frames_in(dir: &Path) -> Vec<(String, lmanim::output::Image)> {
    let mut names: Vec<String> = (std::fs::read_dir(dir).unwrap())
        .map(|entry| entry.unwrap().file_name().into_string().unwrap())
        .filter(|name| name.ends_with(".exr"))
        .collect();
    names.sort();
    names
        .into_iter()
        .map(|name| {
            let image = read_exr(&dir.join(&name)).unwrap();
            (name, image)
        })
        .collect()
}

/// The shot's last frames: the glass ball comes to rest at frame 96, so
/// the chunks 96-97 and 98-99 show it still, and must still render it as
/// the run that saw it move does (issue 32).
const FRAMES: &str = "94-99";

#[test]
fn the_template_checks_and_its_chunks_write_one_runs_frames() {
    let Some(openjd) = openjd() else { return };
    let check = Command::new(&openjd)
        .arg("check")
        .arg(template())
        .output()
        .unwrap();
    assert!(
        check.status.success(),
        "{}",
        String::from_utf8_lossy(&check.stdout)
    );

    let dir = tempfile::tempdir().unwrap();
    let settings = dir.path().join("small.ron");
    std::fs::write(&settings, "(width: 64, height: 36, exr_precision: float)\n").unwrap();
    let lmanim = env!("CARGO_BIN_EXE_lmanim");
    let param = |name: &str, value: &Path| format!("{name}={}", value.display());
    let run = Command::new(&openjd)
        .arg("run")
        .arg(template())
        .args(["--step", "Render", "--run-dependencies"])
        .args(["-p", &param("SceneFile", &courtyard())])
        .args(["-p", &format!("Frames={FRAMES}"), "-p", "ChunkSize=2"])
        .args([
            "-p",
            &param("OutputPattern", &dir.path().join("farm/frame.####.exr")),
        ])
        .args(["-p", &param("CacheDir", &dir.path().join("cache"))])
        .args(["-p", &param("Settings", &settings)])
        .args(["-p", &param("Lmanim", Path::new(lmanim))])
        .current_dir(dir.path())
        .output()
        .unwrap();
    let log = String::from_utf8_lossy(&run.stdout);
    assert!(run.status.success(), "{log}");
    // The warm step and three chunks of two frames.
    assert!(log.contains("Chunks run: 4"), "{log}");

    common::cli::courtyard_in_one_run(FRAMES, &settings, &dir.path().join("one"));
    let (farm, one) = (
        frames_in(&dir.path().join("farm")),
        frames_in(&dir.path().join("one")),
    );
    assert_eq!(farm.len(), 6);
    let names = |frames: &[(String, lmanim::output::Image)]| {
        frames
            .iter()
            .map(|(name, _)| name.clone())
            .collect::<Vec<_>>()
    };
    assert_eq!(names(&farm), names(&one));
    for ((name, farm), (_, one)) in farm.iter().zip(&one) {
        assert!(
            farm == one,
            "{name}: the farm's frame differs from one run's"
        );
    }
}
