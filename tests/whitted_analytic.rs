//! Whitted ray tracing (formula (1)) against closed-form answers: a
//! Lambertian plane under a point light, hard shadows, a mirror, a spot
//! light's cone and a directional light's shadow.

mod common;

use std::f32::consts::PI;

use common::*;
use glam::{DMat4, DQuat, DVec3, Vec3};
use lmanim::scene::{LightKind, Material};

const W: u32 = 64;
const H: u32 = 48;
const YMAG: f32 = 2.0;

fn point_light_at(position: DVec3) -> DMat4 {
    DMat4::from_translation(position)
}

fn lambert_expected(albedo: f32, intensity: f32, light: Vec3, p: Vec3) -> f32 {
    let to_light = light - p;
    let d2 = to_light.length_squared();
    let cos_theta = to_light.y / d2.sqrt();
    albedo / PI * intensity * cos_theta / d2
}

#[test]
fn lambertian_plane_matches_the_closed_form() {
    let mut scene = empty_scene();
    let albedo = 0.7;
    let m = add_material(&mut scene, lambert(Vec3::splat(albedo)));
    add_quads(&mut scene, &[floor_quad(0.0, 5.0)], 4, m);
    let light = Vec3::new(0.7, 1.5, -0.4);
    add_light(
        &mut scene,
        LightKind::Point,
        20.0,
        point_light_at(light.as_dvec3()),
    );
    add_top_camera(&mut scene, 10.0, YMAG);
    let image = render(scene, &settings(W, H));

    let mut checked = 0;
    for (px, py) in [(0, 0), (10, 40), (32, 24), (50, 7), (63, 47), (40, 30)] {
        let (x, z) = top_camera_ground(px, py, W, H, YMAG);
        let expected = lambert_expected(albedo, 20.0, light, Vec3::new(x, 0.0, z));
        let got = pixel(&image, px, py);
        for channel in [got.x, got.y, got.z] {
            let error = (channel - expected).abs() / expected;
            assert!(
                error < 1e-4,
                "pixel ({px},{py}): {channel} vs {expected}, relative {error}"
            );
        }
        assert_eq!(got.w, 1.0, "coverage");
        checked += 1;
    }
    assert_eq!(checked, 6);
}

#[test]
fn shadowed_points_get_exactly_zero_direct_light() {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    add_quads(&mut scene, &[floor_quad(0.0, 5.0)], 1, m);
    // A blocker 1 m above the floor, 0.5 m on a side, right under the light.
    add_quads(&mut scene, &[floor_quad(1.0, 0.25)], 1, m);
    add_light(
        &mut scene,
        LightKind::Point,
        10.0,
        point_light_at(DVec3::new(0.0, 2.0, 0.0)),
    );
    // Looking from below the blocker is impossible with a top camera, so the
    // camera sits between the blocker and the floor.
    add_top_camera(&mut scene, 0.5, YMAG);
    let image = render(scene, &settings(W, H));
    // The umbra on the floor: a square of half-size 0.25 · 2/1 = 0.5.
    for (px, py) in [(32, 24), (31, 23), (29, 26)] {
        let (x, z) = top_camera_ground(px, py, W, H, YMAG);
        assert!(x.abs() < 0.45 && z.abs() < 0.45);
        assert_eq!(
            pixel(&image, px, py).truncate(),
            Vec3::ZERO,
            "({px},{py}) is in the umbra"
        );
    }
    let (x, z) = top_camera_ground(5, 5, W, H, YMAG);
    assert!(x.abs() > 0.6 || z.abs() > 0.6);
    assert!(pixel(&image, 5, 5).x > 0.0, "outside the umbra is lit");
}

#[test]
fn a_perfect_mirror_shows_the_reflected_object() {
    let mut scene = empty_scene();
    let mirror = add_material(
        &mut scene,
        Material {
            base_color: glam::Vec4::ONE,
            metallic: 1.0,
            roughness: 0.0,
            ..Material::default()
        },
    );
    let red = add_material(
        &mut scene,
        Material {
            emissive: Vec3::new(3.0, 0.0, 0.0),
            ..lambert(Vec3::ZERO)
        },
    );
    add_quads(&mut scene, &[floor_quad(0.0, 5.0)], 1, mirror);
    // A red emitter facing down, above the camera, covering x in [-1, 0].
    let emitter = [
        Vec3::new(-1.0, 20.0, -1.0),
        Vec3::new(0.0, 20.0, -1.0),
        Vec3::new(0.0, 20.0, 1.0),
        Vec3::new(-1.0, 20.0, 1.0),
    ];
    add_quads(&mut scene, &[emitter], 1, red);
    add_top_camera(&mut scene, 10.0, YMAG);
    let (image, stats) = render_with_stats(scene, &settings(W, H));
    let (x, z) = top_camera_ground(24, 24, W, H, YMAG);
    assert!((-1.0..0.0).contains(&x) && z.abs() < 1.0);
    let seen = pixel(&image, 24, 24).truncate();
    assert!(
        (seen - Vec3::new(3.0, 0.0, 0.0)).abs().max_element() < 1e-5,
        "{seen}"
    );
    let (x, _) = top_camera_ground(40, 24, W, H, YMAG);
    assert!(x > 0.0);
    assert_eq!(
        pixel(&image, 40, 24).truncate(),
        Vec3::ZERO,
        "nothing reflected there"
    );
    assert!(
        stats.rays.secondary >= (W * H) as u64,
        "every mirror pixel traced a reflection"
    );
}

#[test]
fn a_scene_without_mirrors_or_glass_traces_no_secondary_rays() {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    add_quads(&mut scene, &[floor_quad(0.0, 5.0)], 1, m);
    add_light(
        &mut scene,
        LightKind::Point,
        10.0,
        point_light_at(DVec3::new(0.0, 2.0, 0.0)),
    );
    add_top_camera(&mut scene, 10.0, YMAG);
    let (_, stats) = render_with_stats(scene, &settings(W, H));
    assert_eq!(stats.rays.secondary, 0);
    assert_eq!(stats.rays.primary, (W * H) as u64);
    assert_eq!(stats.rays.shadow, (W * H) as u64);
}

#[test]
fn spot_light_cone_edge_is_where_geometry_says() {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    add_quads(&mut scene, &[floor_quad(0.0, 5.0)], 1, m);
    let (inner, outer) = (0.3f32, 0.4f32);
    let height = 2.0f32;
    // The spot shines down its node's −Z: rotate −Z onto −Y.
    let spot = DMat4::from_rotation_translation(
        DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2),
        DVec3::new(0.0, height as f64, 0.0),
    );
    add_light(
        &mut scene,
        LightKind::Spot {
            inner_cone: inner,
            outer_cone: outer,
        },
        10.0,
        spot,
    );
    add_top_camera(&mut scene, 10.0, YMAG);
    let image = render(scene, &settings(W, H));
    let (r_inner, r_outer) = (height * inner.tan(), height * outer.tan());
    let mut inside = 0;
    let mut outside = 0;
    for py in 0..H {
        for px in 0..W {
            let (x, z) = top_camera_ground(px, py, W, H, YMAG);
            let r = (x * x + z * z).sqrt();
            let value = pixel(&image, px, py).x;
            if r < r_inner - 0.01 {
                let expected =
                    lambert_expected(0.5, 10.0, Vec3::new(0.0, height, 0.0), Vec3::new(x, 0.0, z));
                assert!(
                    (value - expected).abs() / expected < 1e-4,
                    "full light inside the inner cone"
                );
                inside += 1;
            } else if r > r_outer + 0.01 {
                assert_eq!(value, 0.0, "no light outside the outer cone at r = {r}");
                outside += 1;
            }
        }
    }
    assert!(inside > 20 && outside > 200, "{inside} {outside}");
}

#[test]
fn directional_light_shadow_is_displaced_along_the_light() {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    add_quads(&mut scene, &[floor_quad(0.0, 8.0)], 1, m);
    add_quads(&mut scene, &[floor_quad(0.5, 0.5)], 1, m);
    // Light from 45° towards +X: −Z of the node rotated to (−1, −1, 0)/√2.
    let rotation = DQuat::from_rotation_arc(DVec3::NEG_Z, DVec3::new(-1.0, -1.0, 0.0).normalize());
    add_light(
        &mut scene,
        LightKind::Directional,
        2.0,
        DMat4::from_quat(rotation),
    );
    add_top_camera(&mut scene, 0.25, YMAG);
    let image = render(scene, &settings(W, H));
    let mut shadowed = 0;
    for py in 0..H {
        for px in 0..W {
            let (x, z) = top_camera_ground(px, py, W, H, YMAG);
            // The blocker [-0.5, 0.5]² at height 0.5 shadows [-1, 0]×[-0.5, 0.5].
            let in_shadow = (-0.98..-0.02).contains(&x) && z.abs() < 0.48;
            let clearly_lit = !((-1.02..0.02).contains(&x) && z.abs() < 0.52);
            let value = pixel(&image, px, py).x;
            if in_shadow {
                assert_eq!(value, 0.0, "({x}, {z}) lies in the shadow");
                shadowed += 1;
            } else if clearly_lit {
                let expected = 0.5 / PI * 2.0 * std::f32::consts::FRAC_1_SQRT_2;
                assert!(
                    (value - expected).abs() / expected < 1e-4,
                    "({x}, {z}): {value}"
                );
            }
        }
    }
    assert!(shadowed > 50);
}
