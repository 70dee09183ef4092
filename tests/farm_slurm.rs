//! The Slurm array (`farm/slurm/`), run on a single-node Slurm on this
//! machine (`farm/slurm/local-slurm.sh`, which CI starts): a warm job,
//! then three chunks at once against one cache directory, write the
//! frames one lmanim run writes, bit for bit, and leave a cache holding
//! every worker's bits (no save lost when they save together). Off CI
//! without a running Slurm the test says so and passes.

mod common;

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use lmanim::output::read_exr;

fn slurm_is_up() -> bool {
    let up = Command::new("sinfo")
        .arg("--noheader")
        .output()
        .is_ok_and(|o| o.status.success());
    if !up && std::env::var_os("CI").is_some() {
        panic!("CI must start Slurm (farm/slurm/local-slurm.sh)");
    }
    if !up {
        eprintln!("skipped: no Slurm running (farm/slurm/local-slurm.sh starts one)");
    }
    up
}

fn repository(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn run(command: &mut Command) -> Output {
    let output = command.output().expect("the command runs");
    assert!(
        output.status.success(),
        "{}{}",
        String::from_utf8_lossy(&output.stdout),
        String::from_utf8_lossy(&output.stderr)
    );
    output
}

/// `lmanim warm` over the shot with `cache`: the bits it had to compute.
fn bits_warm_computes(dir: &Path, settings: &Path, cache: &Path) -> u64 {
    let output = run(Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args(["warm"])
        .arg(repository("animations/courtyard.gltf"))
        .args(["--frames", "0-5", "--method", "lmm1", "--settings"])
        .arg(settings)
        .arg("--cache")
        .arg(cache)
        .current_dir(dir));
    let report = String::from_utf8_lossy(&output.stderr).to_string();
    let words: Vec<&str> = report.split_whitespace().collect();
    let at = words
        .iter()
        .position(|&word| word == "mask")
        .expect("a report");
    words[at - 1].parse().unwrap_or_else(|_| panic!("{report}"))
}

#[test]
fn three_chunks_at_once_write_one_runs_frames_and_one_cache() {
    if !slurm_is_up() {
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let settings = dir.path().join("small.ron");
    std::fs::write(&settings, "(width: 64, height: 36, exr_precision: float)\n").unwrap();
    run(Command::new(repository("farm/slurm/submit.sh"))
        .arg("--wait")
        .arg(repository("animations/courtyard.gltf"))
        .args(["0-5", "2", "farm/frame.####.exr", "cache"])
        .env("SETTINGS", &settings)
        .env("LMANIM", env!("CARGO_BIN_EXE_lmanim"))
        .current_dir(dir.path()));

    common::cli::courtyard_in_one_run("0-5", &settings, &dir.path().join("one"));
    for frame in 0..6 {
        let name = format!("frame.{frame:04}.exr");
        let farm = read_exr(&dir.path().join("farm").join(&name)).expect("the farm wrote it");
        let one = read_exr(&dir.path().join("one").join(&name)).unwrap();
        assert!(
            farm == one,
            "{name}: the farm's frame differs from one run's"
        );
    }

    // The chunks alone, at once, into an empty cache: it must end holding
    // every worker's static bits, so that a warm over the whole shot has
    // as little left to compute as after one full warm.
    run(Command::new("sbatch")
        .args(["--wait", "--array=0-2"])
        .arg(repository("farm/slurm/lmanim-array.sbatch"))
        .env("LMANIM", env!("CARGO_BIN_EXE_lmanim"))
        .env("SCENE", repository("animations/courtyard.gltf"))
        .env("FIRST", "0")
        .env("LAST", "5")
        .env("CHUNK", "2")
        .env("OUT", dir.path().join("unwarmed/frame.####.exr"))
        .env("CACHE", dir.path().join("unwarmed-cache"))
        .env("METHOD", "lmm1")
        .env("SETTINGS", &settings)
        .current_dir(dir.path()));
    let reference = dir.path().join("reference");
    bits_warm_computes(dir.path(), &settings, &reference);
    let after_one = bits_warm_computes(dir.path(), &settings, &reference);
    let after_farm = bits_warm_computes(dir.path(), &settings, &dir.path().join("unwarmed-cache"));
    assert_eq!(after_farm, after_one, "the workers' saves lost bits");
}
