//! The background and the ambient sky (`render/environment.rs`): off by
//! default, a miss shows the background and makes the frame opaque, and
//! the sky adds its light times the diffuse albedo everywhere, in shadow
//! as in the open, for every method.

mod common;

use common::*;
use glam::Vec3;
use lmanim::output::Image;
use lmanim::scene::SceneDesc;
use lmanim::settings::{Method, Settings};

const W: u32 = 48;
const H: u32 = 32;
const YMAG: f32 = 2.0;
const ALBEDO: Vec3 = Vec3::new(0.5, 0.25, 0.75);

/// A 3 m floor seen from above (the camera sees past its edges), lit by a
/// lamp beside a box that shadows the floor towards −x.
fn shadowed_floor() -> SceneDesc {
    let mut scene = empty_scene();
    let floor = add_material(&mut scene, lambert(ALBEDO));
    add_quads(&mut scene, &[floor_quad(0.0, 1.5)], 4, floor);
    add_quads(
        &mut scene,
        &box_quads(Vec3::new(0.0, 0.5, 0.0), 0.25),
        1,
        floor,
    );
    add_lamp(&mut scene, 30.0, Vec3::new(2.0, 1.5, 0.0), 0.05);
    add_top_camera(&mut scene, 10.0, YMAG);
    scene
}

fn with_environment(background: Option<[f32; 3]>, ambient: Option<[f32; 3]>) -> Settings {
    Settings {
        background,
        ambient,
        ..settings(W, H)
    }
}

/// Pixels (x, y) whose centre sees the floor at (x, z), far enough from
/// its edge that no pixel straddles it.
fn floor_pixels() -> impl Iterator<Item = (u32, u32, f32, f32)> {
    (0..H).flat_map(|py| {
        (0..W).filter_map(move |px| {
            let (x, z) = top_camera_ground(px, py, W, H, YMAG);
            (x.abs() < 1.4 && z.abs() < 1.4).then_some((px, py, x, z))
        })
    })
}

fn miss_pixels() -> impl Iterator<Item = (u32, u32)> {
    (0..H).flat_map(|py| {
        (0..W)
            .filter(move |&px| {
                let (x, z) = top_camera_ground(px, py, W, H, YMAG);
                x.abs() > 1.6 || z.abs() > 1.6
            })
            .map(move |px| (px, py))
    })
}

fn differing_pixels(a: &Image, b: &Image) -> usize {
    a.pixels
        .iter()
        .zip(&b.pixels)
        .filter(|(p, q)| p != q)
        .count()
}

#[test]
fn a_miss_shows_the_background_and_the_frame_is_opaque() {
    let plain = render(shadowed_floor(), &settings(W, H));
    let blue = [0.1, 0.2, 0.4];
    let image = render(shadowed_floor(), &with_environment(Some(blue), None));
    let mut misses = 0;
    for (px, py) in miss_pixels() {
        assert_eq!(pixel(&plain, px, py).to_array(), [0.0; 4]);
        assert_eq!(pixel(&image, px, py).to_array(), [0.1, 0.2, 0.4, 1.0]);
        misses += 1;
    }
    assert!(misses > 100, "{misses} pixels miss the floor");
    // Where the camera sees the floor, nothing changes but alpha.
    for (px, py, _, _) in floor_pixels() {
        assert_eq!(pixel(&image, px, py), pixel(&plain, px, py));
    }
}

#[test]
fn the_ambient_sky_adds_albedo_times_sky_in_shadow_and_in_the_open() {
    let sky = [0.2, 0.4, 0.1];
    let sky_light = ALBEDO * Vec3::from_array(sky);
    for method in [Method::Whitted, Method::Lmm, Method::Lmm1, Method::Area] {
        let plain = render(
            shadowed_floor(),
            &Settings {
                method,
                ..settings(W, H)
            },
        );
        let lit = render(
            shadowed_floor(),
            &Settings {
                method,
                ..with_environment(None, Some(sky))
            },
        );
        let (mut umbra, mut open) = (0, 0);
        for (px, py, x, z) in floor_pixels() {
            let before = pixel(&plain, px, py).truncate();
            let after = pixel(&lit, px, py).truncate();
            if (-1.1..-0.6).contains(&x) && z.abs() < 0.1 {
                // In the box's umbra the lamp is hidden: only the sky.
                assert_eq!(before, Vec3::ZERO, "{method} ({px}, {py})");
                assert_eq!(after, sky_light, "{method} ({px}, {py})");
                umbra += 1;
            } else if x.abs() > 1.0 || z.abs() > 1.0 {
                let expected = before + sky_light;
                assert!(
                    (after - expected).abs().max_element() <= 1e-6 * expected.max_element(),
                    "{method} ({px}, {py}): {after} against {expected}"
                );
                open += 1;
            }
        }
        assert!(
            umbra > 0 && open > 100,
            "{method}: {umbra} in the umbra, {open} open"
        );
        // The misses stay transparent black: the sky is no background.
        for (px, py) in miss_pixels() {
            assert_eq!(pixel(&lit, px, py).to_array(), [0.0; 4]);
        }
    }
}

#[test]
fn neither_is_on_unless_asked_for() {
    let defaults = Settings::default();
    assert_eq!((defaults.background, defaults.ambient), (None, None));
    let plain = render(shadowed_floor(), &settings(W, H));
    let black = render(
        shadowed_floor(),
        &with_environment(None, Some([0.0, 0.0, 0.0])),
    );
    assert_eq!(differing_pixels(&plain, &black), 0);
    let sky = render(
        shadowed_floor(),
        &with_environment(None, Some([0.1, 0.1, 0.1])),
    );
    assert!(differing_pixels(&plain, &sky) > 100);
}

#[test]
fn impossible_colours_are_refused_by_name() {
    for (field, text) in [
        ("background", "(background: Some((0.1, -1.0, 0.0)))"),
        ("ambient", "(ambient: Some((0.1, inf, 0.0)))"),
    ] {
        let dir = tempfile::tempdir().expect("tempdir");
        let path = dir.path().join("bad.ron");
        std::fs::write(&path, text).expect("write");
        let output = common::cli::lmanim(&[
            concat!(env!("CARGO_MANIFEST_DIR"), "/animations/courtyard.gltf"),
            "--settings",
            path.to_str().expect("UTF-8"),
        ]);
        common::cli::assert_bad_input(&output, field);
    }
}
