//! Numerically hard cases of the Whitted reference: huge coordinates,
//! grazing light, degenerate triangles, a light on a surface, and the
//! image's independence from the thread count.

mod common;

use common::*;
use glam::{DMat4, DVec3, Vec3};
use lmanim::scene::{LightKind, SceneDesc};

const W: u32 = 48;
const H: u32 = 32;

/// A floor, a box-like blocker of two quads, a point light and a camera.
fn courtyard(offset: DVec3) -> SceneDesc {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::new(0.8, 0.6, 0.4)));
    add_quads(
        &mut scene,
        &[floor_quad(0.0, 6.0), floor_quad(0.8, 0.5)],
        3,
        m,
    );
    add_light(
        &mut scene,
        LightKind::Point,
        30.0,
        DMat4::from_translation(DVec3::new(0.6, 2.5, 0.3)),
    );
    add_camera(
        &mut scene,
        lmanim::scene::Projection::Perspective {
            yfov: 0.9,
            aspect_ratio: None,
            znear: 0.05,
            zfar: None,
        },
        look_at(DVec3::new(3.0, 4.0, 5.0), DVec3::ZERO),
    );
    // Move everything: a root above all nodes carries the offset.
    let children = scene.roots.clone();
    scene.nodes.push(lmanim::scene::Node {
        local: DMat4::from_translation(offset),
        children,
        ..Default::default()
    });
    scene.roots = vec![scene.nodes.len() - 1];
    scene
}

#[test]
fn translating_the_scene_by_100_km_renders_the_same_image() {
    let near = render(courtyard(DVec3::ZERO), &settings(W, H));
    let far = render(courtyard(DVec3::new(1e5, 0.0, -1e5)), &settings(W, H));
    let mut lit = 0;
    for (a, b) in near.pixels.iter().zip(&far.pixels) {
        let scale = a.x.abs().max(1e-3);
        assert!((a.x - b.x).abs() / scale < 1e-3, "{a} vs {b}");
        assert_eq!(a.w, b.w);
        lit += (a.x > 0.0) as u32;
    }
    assert!(lit > (W * H / 2), "the comparison covers a lit image");
}

#[test]
fn grazing_light_gives_no_nan_and_no_acne() {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    // A finely tessellated floor: many shared edges for shadow rays to graze.
    add_quads(&mut scene, &[floor_quad(0.0, 4.0)], 64, m);
    // 0.5° above the horizon, 50 m away.
    let elevation = 0.5f64.to_radians();
    let light = DVec3::new(50.0 * elevation.cos(), 50.0 * elevation.sin(), 0.0);
    add_light(
        &mut scene,
        LightKind::Point,
        1e4,
        DMat4::from_translation(light),
    );
    add_top_camera(&mut scene, 5.0, 2.0);
    let image = render(scene, &settings(W, H));
    for (i, p) in image.pixels.iter().enumerate() {
        assert!(p.is_finite(), "pixel {i} is {p}");
        // Nothing occludes the floor: every pixel must be lit (acne would
        // show as pixels wrongly shadowed by their own floor).
        assert!(p.x > 0.0, "pixel {i} is dark: self-shadowing acne");
    }
    // And the values follow the closed form's smooth falloff.
    let (x, z) = top_camera_ground(10, 10, W, H, 2.0);
    let to_light = light.as_vec3() - Vec3::new(x, 0.0, z);
    let expected = 0.5 / std::f32::consts::PI * 1e4 * to_light.y / to_light.length().powi(3);
    let got = pixel(&image, 10, 10).x;
    assert!(
        (got - expected).abs() / expected < 1e-3,
        "{got} vs {expected}"
    );
}

#[test]
fn zero_area_triangles_are_ignored() {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    add_quads(&mut scene, &[floor_quad(0.0, 4.0)], 1, m);
    // A degenerate blocker: all three corners on one line, right under the light.
    let mut mesh = lmanim::scene::Mesh {
        positions: vec![
            Vec3::new(-1.0, 1.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ],
        triangles: vec![[0, 1, 2], [1, 1, 1]],
        triangle_materials: vec![m, m],
        ..Default::default()
    };
    mesh.normals = vec![Vec3::Y; 3];
    scene.meshes.push(mesh);
    let node = add_node(&mut scene, DMat4::IDENTITY);
    scene.nodes[node].mesh = Some(scene.meshes.len() - 1);
    add_light(
        &mut scene,
        LightKind::Point,
        10.0,
        DMat4::from_translation(DVec3::new(0.0, 2.0, 0.0)),
    );
    add_top_camera(&mut scene, 0.5, 2.0);
    let image = render(scene, &settings(W, H));
    for p in &image.pixels {
        assert!(p.x > 0.0, "a degenerate triangle cast a shadow");
    }
}

#[test]
fn a_light_exactly_on_a_surface_lights_the_rest_and_stays_finite() {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    add_quads(&mut scene, &[floor_quad(0.0, 4.0)], 8, m);
    // A wall at x = 1 facing −X, and the light lying on the floor at a vertex.
    let wall = [
        Vec3::new(1.0, 0.0, 2.0),
        Vec3::new(1.0, 0.0, -2.0),
        Vec3::new(1.0, 2.0, -2.0),
        Vec3::new(1.0, 2.0, 2.0),
    ];
    add_quads(&mut scene, &[wall], 2, m);
    add_light(&mut scene, LightKind::Point, 10.0, DMat4::IDENTITY);
    let camera = look_at(DVec3::new(-3.0, 1.5, 0.0), DVec3::new(1.0, 0.7, 0.0));
    add_camera(
        &mut scene,
        lmanim::scene::Projection::Perspective {
            yfov: 0.8,
            aspect_ratio: None,
            znear: 0.05,
            zfar: None,
        },
        camera,
    );
    let image = render(scene, &settings(W, H));
    assert!(image.pixels.iter().all(|p| p.is_finite()));
    // The wall (centre of the image) is lit; the floor the light lies on
    // is seen edge-on by the light and gets nothing.
    assert!(pixel(&image, W / 2, H / 2).x > 0.0, "the wall is lit");
    assert_eq!(
        pixel(&image, W / 2, H - 1).x,
        0.0,
        "the floor under the light gets no light"
    );
}

#[test]
fn the_image_does_not_depend_on_the_thread_count() {
    let mut one = settings(W, H);
    one.threads = Some(1);
    one.spp = 4;
    let mut two = one.clone();
    two.threads = Some(2);
    let a = render(courtyard(DVec3::ZERO), &one);
    let b = render(courtyard(DVec3::ZERO), &two);
    assert_eq!(a, b);
}
