//! AOV layers (`--aovs`): the per-light layers (with `other`) sum to the
//! beauty for every method, a light with no effect has a zero layer, the
//! beauty is the same bits with and without them, `albedo`, `normal` and
//! `depth` hold what the camera sees, the GPU backend writes the CPU's
//! layers bit for bit for every method, OpenEXR's own reader lists the
//! channels, and bad lists are refused in one line (the GPU backend is
//! not).

mod common;

use std::path::{Path, PathBuf};

use common::cli::{assert_bad_input, lmanim};
use common::*;
use glam::{DMat4, Vec3};
use lmanim::backend::Backend;
use lmanim::output::{AovLayer, RenderedFrame};
use lmanim::scene::{LightKind, SceneDesc};
use lmanim::sequence::Sequence;
use lmanim::settings::{Aov, BackendKind, Method, Settings};

fn courtyard() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf")
}

fn render_frame(sequence: Sequence, settings: &Settings) -> RenderedFrame {
    let mut backend = Backend::new(BackendKind::Cpu, settings.threads).expect("threads");
    render_frame_on(&mut backend, sequence, settings)
}

fn render_frame_on(
    backend: &mut Backend,
    mut sequence: Sequence,
    settings: &Settings,
) -> RenderedFrame {
    let placed = sequence.place(settings).expect("placed");
    sequence
        .render_frame(backend, &placed, settings, &mut Default::default())
        .expect("frame")
}

fn layer<'a>(frame: &'a RenderedFrame, first_channel: &str) -> &'a AovLayer {
    (frame.aovs.iter())
        .find(|layer| layer.channels[0] == first_channel)
        .unwrap_or_else(|| panic!("no layer {first_channel}"))
}

/// Every `light.*` layer and `other`, summed per pixel.
fn light_sum(frame: &RenderedFrame) -> Vec<Vec3> {
    let mut sum = vec![Vec3::ZERO; frame.image.pixels.len()];
    let light_layers = (frame.aovs.iter())
        .filter(|layer| layer.channels[0].starts_with("light.") || layer.channels[0] == "other.R");
    for layer in light_layers {
        for (pixel, rgb) in sum.iter_mut().zip(layer.values.chunks(3)) {
            *pixel += Vec3::from_slice(rgb);
        }
    }
    sum
}

#[test]
fn light_layers_sum_to_the_beauty_for_every_method() {
    // The courtyard: four lights, a mirror and a glass sphere (terms at
    // every depth of the recursion, weighted by their paths), an ambient
    // sky and a background (in `other`), two samples a pixel.
    for method in [Method::Whitted, Method::Lmm, Method::Lmm1, Method::Area] {
        let plain = Settings {
            method,
            spp: 2,
            background: Some([0.1, 0.2, 0.3]),
            ambient: Some([0.02, 0.03, 0.04]),
            ..settings(64, 36)
        };
        let with_aovs = Settings {
            aovs: vec![Aov::Light],
            ..plain.clone()
        };
        let load = || Sequence::load(&courtyard()).expect("courtyard");
        let frame = render_frame(load(), &with_aovs);
        let beauty = render_frame(load(), &plain);
        assert_eq!(frame.image, beauty.image, "{method}: the beauty changed");
        let names: Vec<&str> = frame.aovs.iter().map(|l| l.channels[0].as_str()).collect();
        assert_eq!(
            names,
            [
                "light.Lamp_Warm.R",
                "light.Lamp_Cool.R",
                "light.Lamp_Small.R",
                "light.Spot_Key.R",
                "other.R"
            ],
            "{method}"
        );
        assert_layers_sum_to_the_beauty(&frame, &method.to_string());
        let lit = (frame.image.pixels.iter())
            .filter(|pixel| pixel.truncate().max_element() > 0.1)
            .count();
        assert!(lit > 1000, "{method}: {lit} lit pixels");
        // Each lamp lights something.
        for layer in &frame.aovs {
            assert!(
                layer.values.iter().any(|&v| v > 0.0),
                "{method}: {:?} is black",
                layer.channels
            );
        }
    }
}

/// Asserts that every light layer's pixels and `other`'s sum to the
/// beauty's within rounding.
fn assert_layers_sum_to_the_beauty(frame: &RenderedFrame, what: &str) {
    for (pixel, sum) in frame.image.pixels.iter().zip(light_sum(frame)) {
        let beauty = pixel.truncate();
        let error = (sum - beauty).abs().max_element();
        assert!(
            error <= 1e-5 * beauty.max_element().max(1e-3),
            "{what}: layers sum to {sum}, the beauty is {beauty}"
        );
    }
}

#[test]
fn the_gpu_writes_the_cpus_layers_for_every_method() {
    // The courtyard small: four lights, a mirror and a glass sphere (light
    // layers at every depth of the recursion), sky and background (in
    // `other`), two samples a pixel, every AOV.
    let Some((mut gpu, exact)) = common::gpu::backend_to_compare() else {
        return;
    };
    let mut cpu = Backend::new(BackendKind::Cpu, Some(2)).expect("threads");
    for method in [Method::Whitted, Method::Lmm, Method::Lmm1, Method::Area] {
        let settings = Settings {
            method,
            spp: 2,
            background: Some([0.1, 0.2, 0.3]),
            ambient: Some([0.02, 0.03, 0.04]),
            aovs: Aov::ALL.to_vec(),
            ..settings(32, 18)
        };
        let load = || Sequence::load(&courtyard()).expect("courtyard");
        let on_cpu = render_frame_on(&mut cpu, load(), &settings);
        let on_gpu = render_frame_on(&mut gpu, load(), &settings);
        let channels = |frame: &RenderedFrame| -> Vec<String> {
            (frame.aovs.iter())
                .flat_map(|layer| layer.channels.clone())
                .collect()
        };
        assert_eq!(channels(&on_gpu), channels(&on_cpu), "{method}");
        assert_eq!(channels(&on_cpu).len(), 3 * 5 + 3 + 3 + 1, "{method}");
        if !exact {
            let values = on_gpu.aovs.iter().flat_map(|layer| &layer.values);
            assert!(values.filter(|v| !v.is_nan()).count() > 0, "{method}");
            continue;
        }
        assert!(on_gpu.image == on_cpu.image, "{method}: the beauty differs");
        for (gpu_layer, cpu_layer) in on_gpu.aovs.iter().zip(&on_cpu.aovs) {
            let channels = gpu_layer.channels.len();
            let bits = |layer: &AovLayer| -> Vec<u32> {
                layer.values.iter().map(|v| v.to_bits()).collect()
            };
            let (gpu_bits, cpu_bits) = (bits(gpu_layer), bits(cpu_layer));
            assert_eq!(gpu_bits.len(), cpu_bits.len(), "{method}");
            let differing = (gpu_bits.iter().zip(&cpu_bits).enumerate())
                .filter(|(_, (g, c))| g != c)
                .map(|(at, _)| (at / channels, gpu_layer.channels[at % channels].as_str()))
                .collect::<Vec<_>>();
            assert!(
                differing.is_empty(),
                "{method}: {} values differ from the CPU's, first (pixel, channel) {:?}",
                differing.len(),
                &differing[..differing.len().min(4)]
            );
        }
        let lit = layer(&on_gpu, "light.Lamp_Warm.R").values.iter();
        assert!(lit.filter(|&&v| v > 0.0).count() > 50, "{method}");
        assert_layers_sum_to_the_beauty(&on_gpu, &format!("{method} on the GPU"));
    }
}

/// The shadowed floor of a box, lit by a lamp, with a second lamp below
/// the floor (it reaches no surface the camera sees) in the group
/// "under" and a third lamp beside the first in the same group "side".
fn floor_with_a_useless_light() -> SceneDesc {
    let mut scene = empty_scene();
    let floor = add_material(&mut scene, lambert(Vec3::new(0.5, 0.25, 0.75)));
    add_quads(&mut scene, &[floor_quad(0.0, 1.5)], 4, floor);
    add_quads(
        &mut scene,
        &box_quads(Vec3::new(0.0, 0.5, 0.0), 0.25),
        1,
        floor,
    );
    add_lamp(&mut scene, 30.0, Vec3::new(2.0, 1.5, 0.0), 0.05);
    add_lamp(&mut scene, 30.0, Vec3::new(0.0, -1.0, 0.0), 0.05);
    add_lamp(&mut scene, 10.0, Vec3::new(-2.0, 1.5, 0.0), 0.05);
    let groups = [Some("side"), Some("under"), Some("side")];
    for (light, group) in scene.lights.iter_mut().zip(groups) {
        light.group = group.map(str::to_owned);
    }
    add_top_camera(&mut scene, 10.0, 2.0);
    scene
}

#[test]
fn a_light_with_no_effect_has_a_zero_layer_and_groups_share_one() {
    for method in [Method::Whitted, Method::Lmm1] {
        let settings = Settings {
            method,
            aovs: vec![Aov::Light],
            ..settings(48, 32)
        };
        let sequence = Sequence::new(floor_with_a_useless_light(), "floor".into()).expect("scene");
        let frame = render_frame(sequence, &settings);
        let names: Vec<&str> = frame.aovs.iter().map(|l| l.channels[0].as_str()).collect();
        assert_eq!(names, ["light.side.R", "light.under.R", "other.R"]);
        let under = layer(&frame, "light.under.R");
        assert!(under.values.iter().all(|&v| v == 0.0), "{method}");
        let side = layer(&frame, "light.side.R");
        assert!(side.values.iter().any(|&v| v > 0.0), "{method}");
        let other = layer(&frame, "other.R");
        assert!(other.values.iter().all(|&v| v == 0.0), "{method}");
    }
}

#[test]
fn albedo_normal_and_depth_hold_what_the_camera_sees() {
    let settings = Settings {
        aovs: vec![Aov::Depth, Aov::Albedo, Aov::Normal],
        ..settings(48, 32)
    };
    let mut scene = empty_scene();
    let floor = add_material(&mut scene, lambert(Vec3::new(0.5, 0.25, 0.75)));
    add_quads(&mut scene, &[floor_quad(0.0, 1.5)], 4, floor);
    add_light(
        &mut scene,
        LightKind::Point,
        5.0,
        DMat4::from_translation((0.0, 2.0, 0.0).into()),
    );
    // An orthographic camera 10 m up: every ray meets the floor after 10 m.
    add_top_camera(&mut scene, 10.0, 2.0);
    let frame = render_frame(
        Sequence::new(scene, "floor".into()).expect("scene"),
        &settings,
    );
    let names: Vec<&str> = (frame.aovs.iter())
        .flat_map(|layer| layer.channels.iter().map(String::as_str))
        .collect();
    assert_eq!(
        names,
        ["Z", "albedo.R", "albedo.G", "albedo.B", "N.X", "N.Y", "N.Z"]
    );
    let (depth, albedo, normal) = (&frame.aovs[0], &frame.aovs[1], &frame.aovs[2]);
    let (mut floor_pixels, mut misses) = (0, 0);
    for (index, pixel) in frame.image.pixels.iter().enumerate() {
        let z = depth.values[index];
        let a = Vec3::from_slice(&albedo.values[3 * index..]);
        let n = Vec3::from_slice(&normal.values[3 * index..]);
        if pixel.w == 1.0 {
            assert!((z - 10.0).abs() < 1e-4, "depth {z}");
            assert_eq!(a, Vec3::new(0.5, 0.25, 0.75));
            assert_eq!(n, Vec3::Y);
            floor_pixels += 1;
        } else if pixel.w == 0.0 {
            assert_eq!(z, f32::INFINITY);
            assert_eq!((a, n), (Vec3::ZERO, Vec3::ZERO));
            misses += 1;
        }
    }
    assert!(
        floor_pixels > 300 && misses > 100,
        "{floor_pixels} on the floor, {misses} missing it"
    );
}

#[test]
fn openexrs_own_reader_lists_the_layers() {
    let Some(python) = openexr_python() else {
        return;
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("f.####.exr");
    let run = lmanim(&[
        courtyard().to_str().expect("UTF-8"),
        "--width",
        "32",
        "--height",
        "18",
        "--aovs",
        "light,albedo,normal,depth",
        "--out",
        out.to_str().expect("UTF-8"),
        "--no-cache",
        "--quiet",
    ]);
    assert!(
        run.status.success(),
        "{}",
        String::from_utf8_lossy(&run.stderr)
    );
    let script = "import sys, OpenEXR\n\
                  header = OpenEXR.InputFile(sys.argv[1]).header()\n\
                  print(' '.join(sorted(header['channels'])))";
    let read = std::process::Command::new(&python)
        .args([
            "-c",
            script,
            dir.path().join("f.0000.exr").to_str().expect("UTF-8"),
        ])
        .output()
        .expect("run Python");
    assert!(
        read.status.success(),
        "{}",
        String::from_utf8_lossy(&read.stderr)
    );
    let listed = String::from_utf8_lossy(&read.stdout);
    let mut expected: Vec<String> = ["R", "G", "B", "A", "N.X", "N.Y", "N.Z", "Z"]
        .map(str::to_owned)
        .to_vec();
    for layer in [
        "albedo",
        "light.Lamp_Warm",
        "light.Lamp_Cool",
        "light.Lamp_Small",
        "light.Spot_Key",
        "other",
    ] {
        expected.extend(["R", "G", "B"].map(|c| format!("{layer}.{c}")));
    }
    expected.sort();
    assert_eq!(listed.split_whitespace().collect::<Vec<_>>(), expected);
}

#[test]
fn bad_aov_lists_are_refused_in_one_line() {
    let scene = courtyard();
    let scene = scene.to_str().expect("UTF-8");
    assert_bad_input(
        &lmanim(&[scene, "--aovs", "light,glow"]),
        "--aovs light,glow: unknown AOV 'glow'",
    );
    assert_bad_input(
        &lmanim(&[scene, "--aovs", "depth,depth"]),
        "aovs lists depth twice",
    );
    let dir = tempfile::tempdir().expect("tempdir");
    let settings = dir.path().join("bad.ron");
    std::fs::write(&settings, "(aovs: [light, shine])").expect("write");
    assert_bad_input(
        &lmanim(&[scene, "--settings", settings.to_str().expect("UTF-8")]),
        "bad.ron",
    );
}

#[test]
fn the_gpu_backend_writes_aovs_from_the_command_line() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("f.####.exr");
    let run = lmanim(&[
        courtyard().to_str().expect("UTF-8"),
        "--backend",
        "gpu",
        "--width",
        "16",
        "--height",
        "9",
        "--aovs",
        "light,depth",
        "--out",
        out.to_str().expect("UTF-8"),
        "--no-cache",
        "--quiet",
    ]);
    let stderr = String::from_utf8_lossy(&run.stderr);
    if !run.status.success()
        && std::env::var_os("CI").is_none()
        && stderr.contains("no GPU adapter")
    {
        eprintln!("skipped: {stderr}");
        return;
    }
    assert!(run.status.success(), "{stderr}");
    assert!(dir.path().join("f.0000.exr").is_file());
}
