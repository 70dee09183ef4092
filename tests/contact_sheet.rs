//! A contact sheet over more frames than the run renders (`--sheet-frames`):
//! the frames already on disk are read back into it, so the sheet of a
//! shot rendered in parts equals the sheet of one whole run, and a frame
//! not on disk yet is left out with a warning.

mod common;

use std::path::Path;

use common::cli::{assert_bad_input, lmanim};

fn courtyard() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf");
    path.to_str().expect("UTF-8").to_owned()
}

/// Renders `frames` of the courtyard at 96×54 (whitted, float EXRs, so a
/// frame read back is the frame rendered) into `dir`, with a sheet.
fn render(dir: &Path, frames: &str, extra: &[&str]) -> std::process::Output {
    let out = dir.join("frame.####.exr");
    let sheet = dir.join("sheet.png");
    let mut args = vec![
        courtyard(),
        "--frames".into(),
        frames.into(),
        "--width".into(),
        "96".into(),
        "--height".into(),
        "54".into(),
        "--method".into(),
        "whitted".into(),
        "--exr-float".into(),
        "--out".into(),
        out.to_str().expect("UTF-8").into(),
        "--contact-sheet".into(),
        sheet.to_str().expect("UTF-8").into(),
        "--sheet-columns".into(),
        "3".into(),
    ];
    args.extend(extra.iter().map(|&arg| arg.to_owned()));
    let args: Vec<&str> = args.iter().map(String::as_str).collect();
    lmanim(&args)
}

fn sheet(dir: &Path) -> image::RgbaImage {
    image::open(dir.join("sheet.png"))
        .expect("sheet")
        .to_rgba8()
}

#[test]
fn frames_on_disk_are_read_back_into_the_sheet() {
    let whole = tempfile::tempdir().expect("tempdir");
    let run = render(whole.path(), "0..6", &[]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );

    // The same shot in two parts: frames 0..3, then 3..6 with the sheet
    // over all six, the first three read back from disk.
    let parts = tempfile::tempdir().expect("tempdir");
    let first = render(parts.path(), "0..3", &[]);
    assert!(first.status.success());
    let second = render(parts.path(), "3..6", &["--sheet-frames", "0..6"]);
    assert!(
        second.status.success(),
        "{}",
        String::from_utf8_lossy(&second.stderr)
    );
    let (whole, parts) = (sheet(whole.path()), sheet(parts.path()));
    assert_eq!(
        parts.dimensions(),
        (288, 108),
        "two rows of three cells of 96×54: frames narrower than 256 pixels are not shrunk"
    );
    assert_eq!(whole.as_raw(), parts.as_raw());
}

#[test]
fn a_frame_not_on_disk_is_left_out_with_a_warning() {
    let dir = tempfile::tempdir().expect("tempdir");
    let run = render(dir.path(), "1", &["--sheet-frames", "0..3"]);
    assert!(run.status.success());
    let stderr = String::from_utf8_lossy(&run.stderr);
    let warnings: Vec<&str> = stderr.lines().filter(|l| l.contains("warn")).collect();
    assert_eq!(warnings.len(), 2, "{stderr}");
    assert!(warnings[0].contains("frame.0000.exr") && warnings[1].contains("frame.0002.exr"));
    // One cell: frame 1.
    assert_eq!(sheet(dir.path()).dimensions(), (96, 54));
}

#[test]
fn a_sheet_too_large_is_refused_before_the_first_frame() {
    let dir = tempfile::tempdir().expect("tempdir");
    // 2400 thumbnails of 96×54 in 3 columns: 43200 pixels high.
    let run = render(dir.path(), "0", &["--sheet-frames", "0..2400"]);
    assert_bad_input(
        &run,
        "sheet.png: the contact sheet of 2400 thumbnails of 96x54",
    );
    assert!(String::from_utf8_lossy(&run.stderr).contains("--sheet-every"));
    assert!(
        !dir.path().join("frame.0000.exr").exists(),
        "nothing rendered"
    );
    // Every 10th frame fits.
    let every_tenth = [
        "--sheet-frames",
        "0..2400",
        "--sheet-every",
        "10",
        "--quiet",
    ];
    let fits = render(dir.path(), "0", &every_tenth);
    assert!(
        fits.status.success(),
        "{}",
        String::from_utf8_lossy(&fits.stderr)
    );
}

#[test]
fn a_bad_sheet_range_is_refused() {
    let dir = tempfile::tempdir().expect("tempdir");
    let run = render(dir.path(), "0", &["--sheet-frames", "5..2"]);
    assert_bad_input(&run, "sheet_frames");
}
