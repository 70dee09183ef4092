//! Robustness of the ray tracing core: closed meshes never leak rays aimed at
//! their vertices and edges (watertight test and conservative traversal),
//! zero-area triangles are never hit, offset origins never re-hit their own
//! triangle (far from the origin, at grazing angles), and segments that end on
//! a surface.

use std::collections::HashMap;

use glam::{Affine3A, Quat, Vec3};

mod common;
use common::cube;
use lmanim::accel::{offset_ray_origin, Ray, World, WorldObject};

/// An icosphere of radius `r` with shared vertices, `levels` subdivisions.
fn icosphere(levels: u32, r: f32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut p: Vec<Vec3> = [
        (-1.0, t, 0.0),
        (1.0, t, 0.0),
        (-1.0, -t, 0.0),
        (1.0, -t, 0.0),
        (0.0, -1.0, t),
        (0.0, 1.0, t),
        (0.0, -1.0, -t),
        (0.0, 1.0, -t),
        (t, 0.0, -1.0),
        (t, 0.0, 1.0),
        (-t, 0.0, -1.0),
        (-t, 0.0, 1.0),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z).normalize() * r)
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..levels {
        let mut mid = HashMap::new();
        let mut midpoint = |a: u32, b: u32, p: &mut Vec<Vec3>| {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                p.push(((p[a as usize] + p[b as usize]) * 0.5).normalize() * r);
                p.len() as u32 - 1
            })
        };
        tris = tris
            .iter()
            .flat_map(|&[a, b, c]| {
                let (ab, bc, ca) = (
                    midpoint(a, b, &mut p),
                    midpoint(b, c, &mut p),
                    midpoint(c, a, &mut p),
                );
                [[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]
            })
            .collect();
    }
    (p, tris)
}

/// From each inside point, a ray at every vertex and every edge midpoint of
/// the placed mesh must hit it, and a segment there from outside too.
fn assert_closed(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    to_render: Affine3A,
    dynamic: bool,
    inside: &[Vec3],
) {
    let objects = [WorldObject {
        positions,
        triangles,
        to_render,
        dynamic,
    }];
    let world = World::build(&objects);
    let placed = |v: u32| to_render.transform_point3(positions[v as usize]);
    let mut targets: Vec<Vec3> = (0..positions.len() as u32).map(placed).collect();
    for t in triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            targets.push((placed(a) + placed(b)) * 0.5);
        }
    }
    let mut shot = 0;
    for &o in inside {
        let o = to_render.transform_point3(o);
        for &target in &targets {
            let ray = Ray::new(o, target - o, f32::INFINITY);
            assert!(
                world.closest_hit(&ray).is_some(),
                "escaped: {ray:?} (dynamic {dynamic})"
            );
            assert!(world.occluded(&ray), "escaped: {ray:?} (dynamic {dynamic})");
            shot += 1;
        }
    }
    assert!(shot > 1000);
}

#[test]
fn closed_meshes_never_let_a_ray_escape() {
    let inside = [
        Vec3::ZERO,
        Vec3::new(0.1, -0.2, 0.3),
        Vec3::new(0.5, 0.5, 0.5),
        Vec3::new(-0.3, 0.7, 0.01),
    ];
    let placements = [
        Affine3A::IDENTITY,
        Affine3A::from_scale_rotation_translation(
            Vec3::splat(3.0),
            Quat::from_rotation_y(0.7),
            Vec3::new(1e3, 2.0, -5e2),
        ),
        Affine3A::from_translation(Vec3::splat(1e5)),
    ];
    for (positions, triangles) in [icosphere(3, 1.0), cube(4)] {
        for to_render in placements {
            for dynamic in [false, true] {
                assert_closed(&positions, &triangles, to_render, dynamic, &inside);
            }
        }
    }
}

#[test]
fn zero_area_triangles_are_never_hit() {
    let positions = [Vec3::ZERO, Vec3::X, Vec3::X * 2.0, Vec3::new(1.0, 1.0, 0.0)];
    // Collinear, repeated vertex, all three the same.
    let triangles = [[0, 1, 2], [0, 0, 3], [3, 3, 3]];
    for dynamic in [false, true] {
        let objects = [WorldObject {
            positions: &positions,
            triangles: &triangles,
            to_render: Affine3A::IDENTITY,
            dynamic,
        }];
        let world = World::build(&objects);
        assert_eq!(world.triangle_count(), 0);
        for target in [
            Vec3::X,
            Vec3::new(0.5, 0.0, 0.0),
            Vec3::new(0.5, 0.5, 0.0),
            Vec3::new(1.0, 1.0, 0.0),
        ] {
            for origin in [
                Vec3::new(0.3, 0.2, 1.0),
                Vec3::new(-1.0, 0.0, 0.0),
                Vec3::new(0.0, -1.0, 0.0),
            ] {
                let ray = Ray::new(origin, target - origin, f32::INFINITY);
                assert!(world.closest_hit(&ray).is_none());
                assert!(!world.occluded(&ray));
            }
        }
    }
}

/// Rays re-launched from hit points (offset along the geometric normal) into
/// either side, at angles down to grazing, never hit the triangle they left.
#[test]
fn offset_origins_never_rehit_their_triangle() {
    let mut seed = 0x9e3779b97f4a7c15u64;
    let mut rnd = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed >> 40) as f32 / (1u64 << 24) as f32
    };
    for scale in [1.0f32, 1e3, 1e5] {
        for _ in 0..200 {
            let centre = Vec3::new(rnd(), rnd(), rnd()) * scale;
            let size = 0.5 + 10.0 * rnd();
            let mut corner = || centre + (Vec3::new(rnd(), rnd(), rnd()) - 0.5) * size;
            let positions = [corner(), corner(), corner()];
            let triangles = [[0, 1, 2]];
            let objects = [WorldObject {
                positions: &positions,
                triangles: &triangles,
                to_render: Affine3A::IDENTITY,
                dynamic: false,
            }];
            let world = World::build(&objects);
            let [a, b, c] = positions;
            let (u, v) = (rnd() * 0.5, rnd() * 0.5);
            let target = a + u * (b - a) + v * (c - a);
            let from = target + Vec3::new(rnd() - 0.5, rnd() - 0.5, rnd() - 0.5) * size * 4.0;
            let Some(hit) = world.closest_hit(&Ray::new(from, target - from, f32::INFINITY)) else {
                continue;
            };
            let [bu, bv] = hit.barycentric.to_array();
            let p = (1.0 - bu - bv) * a + bu * b + bv * c;
            let n = hit.geometric_normal;
            let tangent = n.any_orthonormal_vector();
            for side in [1.0f32, -1.0] {
                let n = n * side;
                let origin = offset_ray_origin(p, n);
                for lift in [1.0f32, 0.1, 1e-2, 1e-3] {
                    for spin in 0..8 {
                        let along = Quat::from_axis_angle(n, spin as f32 * 0.785) * tangent;
                        let dir = along + n * lift;
                        let ray = Ray::new(origin, dir, f32::INFINITY);
                        assert!(
                            world.closest_hit(&ray).is_none(),
                            "re-hit at scale {scale}: {ray:?}"
                        );
                        assert!(!world.occluded(&ray));
                        // A shadow segment to a far point on that side.
                        assert!(!world.occluded(&Ray::segment(origin, origin + dir * 100.0)));
                    }
                }
            }
        }
    }
}

#[test]
fn segments_ending_on_a_surface() {
    let positions = [
        Vec3::new(-10.0, 0.0, -10.0),
        Vec3::new(10.0, 0.0, -10.0),
        Vec3::new(10.0, 0.0, 10.0),
        Vec3::new(-10.0, 0.0, 10.0),
    ];
    let triangles = [[0, 2, 1], [0, 3, 2]];
    let objects = [WorldObject {
        positions: &positions,
        triangles: &triangles,
        to_render: Affine3A::IDENTITY,
        dynamic: false,
    }];
    let world = World::build(&objects);
    // Straight down onto the floor, ending exactly on it (and on the shared
    // diagonal): the end is excluded.
    for end in [
        Vec3::new(0.25, 0.0, 0.5),
        Vec3::new(1.0, 0.0, 1.0),
        Vec3::ZERO,
    ] {
        assert!(!world.occluded(&Ray::segment(end + Vec3::Y * 3.0, end)));
        assert!(world.occluded(&Ray::segment(end + Vec3::Y * 3.0, end - Vec3::Y)));
    }
    // At a slant, an end on the surface is only as exact as its rounding:
    // offset it towards the start, as for origins, and it is never occluded.
    for i in 0..200 {
        let end = Vec3::new(i as f32 * 0.09 - 9.0, 0.0, (i * 7 % 19) as f32 * 0.9 - 8.0);
        let start = Vec3::new(3.0 - i as f32 * 0.03, 0.5 + i as f32 * 0.1, 2.0);
        let end = offset_ray_origin(end, Vec3::Y);
        assert!(!world.occluded(&Ray::segment(start, end)), "{start} {end}");
        assert!(world.occluded(&Ray::segment(start, end - Vec3::Y * 0.01)));
    }
}
