//! `lmanim study` end to end: a tiny study of the box scene writes its four
//! outputs with the runs the sweep promises, and bad input stops it with
//! one line and exit code 2; and the study's penumbra is where geometry
//! puts it.

use std::path::{Path, PathBuf};

mod common;

use common::cli::{assert_bad_input, lmanim};
use common::*;
use exr::prelude::{
    AnyChannel, AnyChannels, Encoding, FlatSamples, ImageAttributes, Layer, LayerAttributes,
    SmallVec, WritableImage,
};
use glam::{Vec3, Vec4};
use lmanim::backend::{Backend, CpuBackend};
use lmanim::output::{read_exr, read_exr_picture, write_exr, ExrPrecision, Image};
use lmanim::sequence::Sequence;
use lmanim::settings::{BackendKind, Method, Settings};
use lmanim::stats::FrameStats;
use lmanim::study::measure::{Mask, Reference};
use lmanim_authoring::study::StudyScene;

fn box_scene(dir: &Path) -> String {
    let path = dir.join("box.glb");
    StudyScene::Box.build().unwrap().write_glb(&path).unwrap();
    path.display().to_string()
}

fn text(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

/// An EXR of `width`×`height` pixels all `value`, written in `dir` as
/// `name`; its path.
fn filled_exr(dir: &Path, name: &str, (width, height): (u32, u32), value: Vec4) -> PathBuf {
    let path = dir.join(name);
    let image = Image::filled(width, height, value);
    write_exr(&path, &image, ExrPrecision::Half).unwrap();
    path
}

const TINY: [&str; 6] = ["--width", "48", "--height", "27", "--reference-spp", "16"];

#[test]
fn a_tiny_study_writes_all_four_outputs() {
    let dir = tempfile::tempdir().unwrap();
    let scene = box_scene(dir.path());
    let out: PathBuf = dir.path().join("study");
    let mut args = vec!["study", scene.as_str()];
    args.extend(TINY);
    args.extend([
        "--methods",
        "whitted,lmm1,area",
        "--out",
        out.to_str().unwrap(),
    ]);
    let output = lmanim(&args);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(
        stderr.contains("[21/21] area 64 spp"),
        "progress on stderr: {stderr}"
    );

    let json: serde_json::Value = serde_json::from_str(&text(&out.join("study.json"))).unwrap();
    let runs = json["runs"].as_array().unwrap();
    // whitted, lmm1 at the default lattice and 15 swept ones, area at 4 spp.
    assert_eq!(runs.len(), 1 + 16 + 4);
    assert_eq!(json["reference"]["spp"], 16);
    assert!(json["reference"]["penumbra_pixels"].as_u64().unwrap() > 0);
    for run in runs {
        assert!(run["seconds"].as_f64().unwrap() > 0.0, "{run}");
        let rmse = run["rmse"].as_f64().unwrap();
        assert!((0.0..1.0).contains(&rmse), "{run}");
    }
    assert!(runs[0]["h"].is_null() && runs[0]["ki"].is_null());
    assert_eq!(runs[1]["default_lattice"], true);
    assert!(
        runs[1]["h"].as_f64().unwrap() > 0.0,
        "the default h is reported"
    );
    // Area at the reference's own samples renders the reference's pixels.
    let same = runs
        .iter()
        .find(|run| run["method"] == "area" && run["spp"] == 16)
        .unwrap();
    assert_eq!(same["rmse"], 0.0);
    assert_eq!(same["within_1pct"], 1.0);
    // Whitted's hard edge is wrong in the penumbra.
    assert!(runs[0]["penumbra_rmse"].as_f64().unwrap() > 0.05);
    assert!(runs.iter().any(|run| run["pareto"] == true));
    // The default's verdict against area, in both errors, said on stderr.
    let verdict = &json["default_verdict"];
    assert_eq!(verdict["method"], "lmm1");
    assert!(verdict["lit"]["on_front"].is_boolean(), "{verdict}");
    assert!(verdict["penumbra"]["dominated_by"].is_array(), "{verdict}");
    assert!(verdict["over_whitted_penumbra"].as_f64().unwrap() > 0.0);
    assert!(
        stderr.contains("lmm1 at the default lattice") && stderr.contains("Whitted's"),
        "{stderr}"
    );

    let csv = text(&out.join("study.csv"));
    assert_eq!(csv.lines().count(), 1 + runs.len());
    for picture in ["study.png", "crops.png"] {
        let bytes = std::fs::read(out.join(picture)).unwrap();
        assert!(bytes.starts_with(b"\x89PNG\r\n\x1a\n"), "{picture}");
        assert!(bytes.len() > 2000, "{picture} has something drawn");
    }
    assert!(out.join("reference.exr").is_file());
}

/// A Whitted-only study of `scene` into `dir`/first, which holds its
/// rendered reference (`reference.exr`) and its tables: the reference
/// the later studies are measured against.
fn whitted_study(scene: &str, dir: &Path) -> PathBuf {
    let first = dir.join("first");
    let mut args = vec!["study", scene, "--quiet"];
    args.extend(TINY);
    args.extend(["--methods", "whitted", "--out", first.to_str().unwrap()]);
    assert!(lmanim(&args).status.success());
    first
}

#[test]
fn a_given_reference_is_measured_against_with_its_mask() {
    let dir = tempfile::tempdir().unwrap();
    let scene = box_scene(dir.path());
    let first = whitted_study(&scene, dir.path());

    // The same reference from a file, with its left half masked out.
    let reference = first.join("reference.exr");
    let mask = dir.path().join("mask.exr");
    let mut left = Image::filled(48, 27, Vec4::ZERO);
    for (i, pixel) in left.pixels.iter_mut().enumerate() {
        if i % 48 < 24 {
            *pixel = Vec4::ONE;
        }
    }
    write_exr(&mask, &left, ExrPrecision::Half).unwrap();
    let second = dir.path().join("second");
    let output = lmanim(&[
        "study",
        &scene,
        "--quiet",
        "--width",
        "48",
        "--height",
        "27",
        "--methods",
        "whitted",
        "--reference",
        reference.to_str().unwrap(),
        "--reference-mask",
        mask.to_str().unwrap(),
        "--out",
        second.to_str().unwrap(),
    ]);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json = |dir: &Path| -> serde_json::Value {
        serde_json::from_str(&text(&dir.join("study.json"))).unwrap()
    };
    let (first, second) = (json(&first), json(&second));
    assert!(second["reference"]["source"]
        .as_str()
        .unwrap()
        .ends_with("reference.exr"));
    assert!(second["reference"]["estimated_noise"].is_null());
    let count = |json: &serde_json::Value, key: &str| json["reference"][key].as_u64().unwrap();
    assert_eq!(count(&first, "masked_pixels"), 0);
    let masked = count(&second, "masked_pixels");
    assert!(masked > 0);
    assert_eq!(
        count(&first, "lit_pixels") + count(&first, "edge_pixels"),
        count(&second, "lit_pixels") + count(&second, "edge_pixels") + masked,
        "the mask takes pixels out of those measured, and only those"
    );
}

#[test]
fn candidates_are_measured_beside_the_methods_with_their_flicker() {
    let dir = tempfile::tempdir().unwrap();
    let scene = box_scene(dir.path());
    let first = whitted_study(&scene, dir.path());
    let reference = first.join("reference.exr");
    let reference = reference.to_str().unwrap();
    let dark = filled_exr(dir.path(), "dark.exr", (48, 27), Vec4::ZERO);
    let dark = dark.to_str().unwrap();
    let out = dir.path().join("second");
    let copy = format!("copy 1 frame=0.5:{reference}");
    let still = format!("still, 2 frames=0.25:{reference},{reference}");
    let blinking = format!("blinking=0.125:{reference},{dark}");
    let mut args = vec!["study", scene.as_str(), "--quiet", "--width", "48"];
    args.extend(["--height", "27", "--methods", "whitted", "--reference"]);
    args.extend([reference, "--candidate", &copy, "--candidate", &still]);
    args.extend(["--candidate", &blinking, "--out", out.to_str().unwrap()]);
    let output = lmanim(&args);
    assert!(
        output.status.success(),
        "{}",
        String::from_utf8_lossy(&output.stderr)
    );
    let json: serde_json::Value = serde_json::from_str(&text(&out.join("study.json"))).unwrap();
    let runs = json["runs"].as_array().unwrap();
    assert_eq!(runs.len(), 4);
    assert_eq!(runs[0]["method"], "whitted");
    assert!(runs[0]["flicker"].is_null());
    let [copy, still, blinking] = [&runs[1], &runs[2], &runs[3]];
    assert_eq!(copy["candidate"], "copy 1 frame");
    assert!(copy.get("method").is_none());
    assert_eq!(
        (copy["seconds"].as_f64(), copy["rmse"].as_f64()),
        (Some(0.5), Some(0.0))
    );
    assert_eq!(copy["penumbra_rmse"], 0.0);
    assert!(copy["flicker"].is_null());
    // The reference twice: its errors, and nothing flickers.
    assert_eq!(
        (still["frames"].as_u64(), still["rmse"].as_f64()),
        (Some(2), Some(0.0))
    );
    assert_eq!(still["flicker"]["lit"], 0.0);
    // The reference, then black: a lit pixel's error is 0, then −x (its
    // reference's share of the light available), so the pooled RMSE and
    // the flicker (the standard deviation of {0, −x}) are both the RMS
    // of x/√2.
    let value = |run: &serde_json::Value, key: &str| run[key].as_f64().unwrap();
    let flicker = &blinking["flicker"];
    assert!(value(blinking, "rmse") > 0.3, "{blinking}");
    assert!((value(blinking, "rmse") - value(flicker, "lit")).abs() < 1e-9);
    assert!((value(blinking, "penumbra_rmse") - value(flicker, "penumbra")).abs() < 1e-9);
    let csv = text(&out.join("study.csv"));
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].ends_with(",candidate,frames,flicker_lit,flicker_penumbra"));
    assert!(lines[3].starts_with(",,,1,0.250000,"), "{}", lines[3]);
    assert!(
        lines[3].contains(",\"still, 2 frames\",2,0.000000,"),
        "{}",
        lines[3]
    );
    assert!(out.join("study.png").is_file() && out.join("crops.png").is_file());

    // A candidate's bad frame stops the study before anything renders.
    let study = |candidate: &str| {
        let mut args = vec!["study", scene.as_str(), "--quiet", "--width", "48"];
        args.extend(["--height", "27", "--methods", "whitted", "--candidate"]);
        args.extend([candidate, "--out", out.to_str().unwrap()]);
        lmanim(&args)
    };
    let missing = dir.path().join("missing.exr");
    let output = study(&format!("gone=1:{reference},{}", missing.display()));
    assert_bad_input(&output, "candidate \"gone\"");
    assert!(String::from_utf8_lossy(&output.stderr).contains("missing.exr"));
    let small = filled_exr(dir.path(), "small.exr", (4, 4), Vec4::ONE);
    let output = study(&format!("small=1:{}", small.display()));
    assert_bad_input(&output, "small.exr");
    assert!(String::from_utf8_lossy(&output.stderr).contains("4x4"));
    let output = study("no seconds:a.exr");
    assert_eq!(output.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&output.stderr).contains("NAME=SECONDS"));
}

/// A part of an EXR: its name, if any, and its channels' names and values.
type Part<'a> = (Option<&'a str>, Vec<(&'a str, Vec<f32>)>);

/// Writes `parts` (a part's name, if any, and its channels) as one EXR of
/// `size`, laid out as a tool other than lmanim may: one-channel files,
/// RGB without alpha, the beauty in a named part after another part,
/// layers as channel prefixes.
fn write_parts(path: &Path, size: (usize, usize), parts: Vec<Part>) {
    let layers: Vec<_> = parts
        .into_iter()
        .map(|(name, channels)| {
            let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = (channels.into_iter())
                .map(|(channel, values)| AnyChannel::new(channel, FlatSamples::F32(values)))
                .collect();
            let attributes = name.map_or_else(LayerAttributes::default, LayerAttributes::named);
            Layer::new(
                size,
                attributes,
                Encoding::SMALL_LOSSLESS,
                AnyChannels::sort(list),
            )
        })
        .collect();
    exr::image::Image::from_layers(ImageAttributes::with_size(size), layers)
        .write()
        .to_file(path)
        .unwrap();
}

/// The study's reference, masked by `mask` and read from `layer` of
/// `reference`: its pixel census (lit, edge, masked, penumbra).
fn census(scene: &str, out: &Path, reference: &Path, layer: Option<&str>, mask: &Path) -> [u64; 4] {
    let mut args = vec!["study", scene, "--quiet", "--width", "48", "--height", "27"];
    args.extend(["--methods", "whitted", "--out", out.to_str().unwrap()]);
    args.extend(["--reference", reference.to_str().unwrap()]);
    args.extend(["--reference-mask", mask.to_str().unwrap()]);
    if let Some(layer) = layer {
        args.extend(["--reference-layer", layer]);
    }
    let output = lmanim(&args);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{}: {stderr}", mask.display());
    let json: serde_json::Value = serde_json::from_str(&text(&out.join("study.json"))).unwrap();
    [
        "lit_pixels",
        "edge_pixels",
        "masked_pixels",
        "penumbra_pixels",
    ]
    .map(|key| json["reference"][key].as_u64().unwrap())
}

/// Another tool's files: OpenEXR's own writer (Python) rewrites the
/// reference as RGBA and writes the left-half mask as `Y` alone and as
/// RGB without alpha (green 0.5 on the left). Returns their paths, or
/// None where no such Python is named.
fn openexr_files(dir: &Path, reference: &Path) -> Option<[PathBuf; 3]> {
    let python = openexr_python()?;
    let files = ["ref_py.exr", "y_py.exr", "rgb_py.exr"].map(|name| dir.join(name));
    let script = "import sys, numpy as np, OpenEXR\n\
                  source, rgba_out, y_out, rgb_out = sys.argv[1:5]\n\
                  with OpenEXR.File(source) as f:\n    rgba = f.channels()['RGBA'].pixels.astype(np.float32)\n\
                  h, w = rgba.shape[:2]\n\
                  header = {'compression': OpenEXR.ZIP_COMPRESSION, 'type': OpenEXR.scanlineimage}\n\
                  OpenEXR.File(header, {'RGBA': rgba}).write(rgba_out)\n\
                  left = np.zeros((h, w), dtype=np.float32)\n\
                  left[:, : w // 2] = 1.0\n\
                  OpenEXR.File(header, {'Y': left}).write(y_out)\n\
                  rgb = np.zeros((h, w, 3), dtype=np.float32)\n\
                  rgb[:, : w // 2, 1] = 0.5\n\
                  OpenEXR.File(header, {'RGB': rgb}).write(rgb_out)\n";
    let mut args = vec![
        "-c".to_owned(),
        script.to_owned(),
        reference.display().to_string(),
    ];
    args.extend(files.iter().map(|path| path.display().to_string()));
    let run = std::process::Command::new(&python)
        .args(&args)
        .output()
        .expect("run Python");
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    Some(files)
}

#[test]
fn references_and_masks_of_any_layout_leave_out_exactly_the_masks_pixels() {
    let dir = tempfile::tempdir().unwrap();
    let scene = box_scene(dir.path());
    let first = whitted_study(&scene, dir.path());
    let reference_path = first.join("reference.exr");
    let reference = read_exr(&reference_path).unwrap();
    let size = (48, 27);

    // The left half of the frame, as the mask's pixels.
    let left: Vec<bool> = (0..48 * 27).map(|i| i % 48 < 24).collect();
    let level = |on: f32| -> Vec<f32> { left.iter().map(|&l| if l { on } else { 0.0 }).collect() };
    let zeros = vec![0.0; 48 * 27];
    let rgba_mask = dir.path().join("rgba_mask.exr");
    let as_rgba = level(1.0).into_iter().map(Vec4::splat).collect();
    write_exr(
        &rgba_mask,
        &Image {
            width: 48,
            height: 27,
            pixels: as_rgba,
        },
        ExrPrecision::Half,
    )
    .unwrap();
    let y_mask = dir.path().join("y_mask.exr");
    write_parts(&y_mask, size, vec![(None, vec![("Y", level(1.0))])]);
    let rgb_mask = dir.path().join("rgb_mask.exr");
    let rgb = vec![
        ("R", zeros.clone()),
        ("G", level(0.5)),
        ("B", zeros.clone()),
    ];
    write_parts(&rgb_mask, size, vec![(None, rgb)]);

    // The reference in other layouts: the beauty as a named part after a
    // depth part, and as a layer of prefixed channels.
    let channel = |k: usize| reference.pixels.iter().map(|p| p[k]).collect::<Vec<f32>>();
    let multi_part = dir.path().join("multi_part.exr");
    let beauty = ["R", "G", "B", "A"]
        .into_iter()
        .enumerate()
        .map(|(k, c)| (c, channel(k)))
        .collect();
    write_parts(
        &multi_part,
        size,
        vec![
            (Some("depth"), vec![("Z", zeros.clone())]),
            (Some("rgba"), beauty),
        ],
    );
    let layered = dir.path().join("layered.exr");
    let names = ["R", "G", "B", "A"].map(|c| format!("ViewLayer.Combined.{c}"));
    let mut layer_channels: Vec<(&str, Vec<f32>)> = (names.iter().enumerate())
        .map(|(k, name)| (name.as_str(), channel(k)))
        .collect();
    layer_channels.push(("ViewLayer.Depth.Z", zeros.clone()));
    write_parts(&layered, size, vec![(None, layer_channels)]);

    let mut masks = vec![rgba_mask.clone(), y_mask.clone(), rgb_mask.clone()];
    let mut references = vec![
        (multi_part.clone(), None, y_mask.clone()),
        (
            layered.clone(),
            Some("ViewLayer.Combined"),
            rgb_mask.clone(),
        ),
    ];
    if let Some([py_reference, py_y, py_rgb]) = openexr_files(dir.path(), &reference_path) {
        masks.extend([py_y.clone(), py_rgb.clone()]);
        references.extend([
            (py_reference.clone(), None, py_y),
            (py_reference, None, py_rgb),
        ]);
    }
    // Every mask leaves out exactly its left half: alpha in RGBA, Y in a
    // one-channel file, the largest channel in RGB without alpha.
    for mask in &masks {
        let picture = read_exr_picture(mask, None).unwrap();
        assert_eq!(Mask::of(&picture).left_out, left, "{}", mask.display());
    }
    // Every reference reads as the one lmanim wrote.
    for (path, layer, _) in &references {
        let picture = read_exr_picture(path, *layer).unwrap();
        assert_eq!(picture.image, reference, "{}", path.display());
    }

    // The study accepts each, and measures the same pixels as with the
    // RGBA mask lmanim writes: the mask's pixels taken out of those
    // measured, and only those.
    let unmasked: serde_json::Value =
        serde_json::from_str(&text(&first.join("study.json"))).unwrap();
    let count = |key: &str| unmasked["reference"][key].as_u64().unwrap();
    let expected = census(
        &scene,
        &dir.path().join("rgba"),
        &reference_path,
        None,
        &rgba_mask,
    );
    let [lit, edge, masked, _] = expected;
    assert!(masked > 0 && lit > 0);
    assert_eq!(
        count("lit_pixels") + count("edge_pixels"),
        lit + edge + masked
    );
    for (index, (path, layer, mask)) in references.iter().enumerate() {
        let out = dir.path().join(format!("study{index}"));
        assert_eq!(
            census(&scene, &out, path, *layer, mask),
            expected,
            "{} with {}",
            path.display(),
            mask.display()
        );
    }
}

#[test]
fn bad_input_stops_the_study_with_one_line() {
    let dir = tempfile::tempdir().unwrap();
    let scene = box_scene(dir.path());
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    let study = |extra: &[&str]| {
        let mut args = vec![
            "study",
            scene.as_str(),
            "--width",
            "48",
            "--height",
            "27",
            "--quiet",
        ];
        args.extend(extra);
        args.extend(["--out", out]);
        lmanim(&args)
    };
    let missing = dir.path().join("missing.exr");
    assert_bad_input(
        &study(&["--reference", missing.to_str().unwrap()]),
        "missing.exr",
    );
    let junk = dir.path().join("junk.exr");
    std::fs::write(&junk, b"not an exr").unwrap();
    assert_bad_input(&study(&["--reference", junk.to_str().unwrap()]), "junk.exr");
    let small = filled_exr(dir.path(), "small.exr", (4, 4), Vec4::ONE);
    let output = study(&["--reference", small.to_str().unwrap()]);
    assert_bad_input(&output, "small.exr");
    assert!(String::from_utf8_lossy(&output.stderr).contains("4x4"));
    assert_bad_input(&study(&["--reference-spp", "0"]), "--reference-spp");
    // Nothing to measure: a reference in umbra everywhere has no
    // penumbra; a mask over everything leaves no lit pixel.
    let dark = filled_exr(dir.path(), "dark.exr", (48, 27), Vec4::ZERO);
    let dark_arg = dark.to_str().unwrap();
    let output = study(&["--reference", dark_arg]);
    assert_bad_input(
        &output,
        "dark.exr: the reference leaves no penumbra pixel to measure",
    );
    let everything = filled_exr(dir.path(), "everything.exr", (48, 27), Vec4::ONE);
    let output = study(&[
        "--reference",
        dark_arg,
        "--reference-mask",
        everything.to_str().unwrap(),
    ]);
    assert_bad_input(&output, "the reference leaves no lit pixel to measure");
    assert!(String::from_utf8_lossy(&output.stderr).contains("0 lit"));
    // A file of no layout lmanim reads names the channels it holds.
    let odd = dir.path().join("odd.exr");
    write_parts(
        &odd,
        (48, 27),
        vec![(None, vec![("Z", vec![1.0; 48 * 27])])],
    );
    let output = study(&["--reference", odd.to_str().unwrap()]);
    assert_bad_input(&output, "odd.exr: cannot read EXR: no beauty");
    assert!(String::from_utf8_lossy(&output.stderr).contains("found channels Z"));
    let output = study(&["--reference", dark_arg, "--reference-layer", "spec"]);
    assert_bad_input(&output, "no layer 'spec'; found channels A, B, G, R");
    assert_bad_input(
        &lmanim(&["study", &scene, "--width", "0", "--out", out]),
        "width",
    );
    assert_bad_input(
        &lmanim(&["study", "/no/such/scene.gltf", "--out", out]),
        "/no/such/scene.gltf",
    );
    assert!(!Path::new(out).join("study.json").exists());
}

/// A square plate (half-size 0.25 m) 1 m above the floor, under a lamp of
/// radius 0.2 m 1 m above the plate. Along the floor's central strip,
/// similar triangles put the umbra within |x| = 0.3 m and full light
/// beyond 0.7 m (a floor point at x sees the lamp's x' where
/// (x + x') / 2 ≥ 0.25): the measure's penumbra pixels must lie between,
/// and fill it two pixels in from each end, where at least 7% and at most
/// 93% of the lamp shows.
#[test]
fn penumbra_pixels_lie_where_similar_triangles_put_the_penumbra() {
    let mut scene = empty_scene();
    let grey = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    add_quads(
        &mut scene,
        &[floor_quad(0.0, 3.0), floor_quad(1.0, 0.25)],
        1,
        grey,
    );
    add_lamp(&mut scene, 20.0, Vec3::new(0.0, 2.0, 0.0), 0.2);
    add_top_camera(&mut scene, 0.5, 1.0);
    let (width, height) = (80, 80);
    let frame = settings(width, height);
    let mut sequence = Sequence::new(scene, "plate".into()).unwrap();
    let placed = sequence.place(&frame).unwrap();
    let mut backend = Backend::new(BackendKind::Cpu, None).unwrap();
    let area = Settings {
        method: Method::Area,
        spp: 1024,
        ..frame.clone()
    };
    let lamp = sequence
        .render(&mut backend, &placed, &area, &mut FrameStats::default())
        .unwrap();
    let cpu = CpuBackend::new(None).unwrap();
    let unshadowed = sequence.render_unshadowed(&cpu, &placed, &frame, &mut FrameStats::default());
    let measure = Reference::new(lamp, &unshadowed, &unshadowed, None).unwrap();

    let step = 2.0 / width as f32;
    let mut inside = 0;
    for py in 0..height {
        for px in 0..width {
            let (x, z) = top_camera_ground(px, py, width, height, 1.0);
            if z.abs() > 0.2 {
                continue;
            }
            let penumbra = measure.is_penumbra_pixel((py * width + px) as usize);
            let r = x.abs();
            if (0.3 + 2.0 * step..0.7 - 2.0 * step).contains(&r) {
                assert!(penumbra, "x = {x}, z = {z} is in the penumbra");
                inside += 1;
            }
            if r < 0.3 - step || r > 0.7 + step {
                assert!(!penumbra, "x = {x}, z = {z} is umbra or fully lit");
            }
        }
    }
    assert!(inside > 100, "{inside} pixels checked inside the penumbra");
}
