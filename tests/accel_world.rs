//! The world's closest hits and occlusion against brute force over every
//! triangle, on random soups with shared vertices and edges, rays aimed
//! exactly at vertices and edge midpoints and along edges, static and dynamic
//! objects mixed, after moves and deformations; and thread-count
//! independence.

use glam::{Affine3A, Quat, Vec3};
use lmanim::accel::{triangle::intersect_triangle, Hit, Ray, World, WorldObject};
use proptest::prelude::*;

/// A small deterministic generator, so one proptest seed is one scene.
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f32 {
        self.0 ^= self.0 << 13;
        self.0 ^= self.0 >> 7;
        self.0 ^= self.0 << 17;
        (self.0 >> 40) as f32 / (1u64 << 24) as f32
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next()
    }
    fn vec(&mut self, lo: f32, hi: f32) -> Vec3 {
        Vec3::new(self.range(lo, hi), self.range(lo, hi), self.range(lo, hi))
    }
}

struct Mesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

/// A bumpy grid (every inner vertex and edge shared) plus a loose soup,
/// with a few zero-area triangles.
fn mesh(rng: &mut Rng, n: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut triangles = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            let h = rng.range(-0.3, 0.3);
            positions.push(Vec3::new(
                i as f32 - n as f32 / 2.0,
                h,
                j as f32 - n as f32 / 2.0,
            ));
        }
    }
    for j in 0..n {
        for i in 0..n {
            let v = j * (n + 1) + i;
            triangles.push([v, v + 1, v + n + 1]);
            triangles.push([v + 1, v + n + 2, v + n + 1]);
        }
    }
    for _ in 0..n * 2 {
        let base = positions.len() as u32;
        let c = rng.vec(-3.0, 3.0);
        positions.extend([
            c + rng.vec(-1.0, 1.0),
            c + rng.vec(-1.0, 1.0),
            c + rng.vec(-1.0, 1.0),
        ]);
        triangles.push([base, base + 1, base + 2]);
    }
    // Degenerate: repeated index, and collinear vertices.
    let base = positions.len() as u32;
    positions.extend([Vec3::ZERO, Vec3::X, Vec3::X * 2.0]);
    triangles.push([base, base + 1, base + 2]);
    triangles.push([0, 0, 1]);
    Mesh {
        positions,
        triangles,
    }
}

/// Every triangle of every object, each tested in the space the world tests
/// it in (render space for static objects, object space for dynamic ones),
/// closest by `(t, object, triangle)`.
fn brute_force(objects: &[WorldObject], ray: &Ray) -> Option<(f32, u32, u32, glam::Vec2)> {
    let mut best: Option<(f32, u32, u32, glam::Vec2)> = None;
    for (o, object) in objects.iter().enumerate() {
        let (local, placed): (Ray, Box<dyn Fn(Vec3) -> Vec3>) = if object.dynamic {
            let inv = object.to_render.inverse();
            let r = Ray::new(
                inv.transform_point3(ray.origin),
                inv.transform_vector3(ray.direction),
                ray.t_max,
            );
            (r, Box::new(|p| p))
        } else {
            (
                *ray,
                Box::new(move |p| object.to_render.transform_point3(p)),
            )
        };
        for (i, tri) in object.triangles.iter().enumerate() {
            let [a, b, c] = tri.map(|v| placed(object.positions[v as usize]));
            if (b - a).as_dvec3().cross((c - a).as_dvec3()) == glam::DVec3::ZERO {
                continue;
            }
            if let Some(h) = intersect_triangle(&local, a, b, c) {
                let key = (h.t, o as u32, i as u32, h.barycentric);
                if best.is_none_or(|b| (key.0, key.1, key.2) < (b.0, b.1, b.2)) {
                    best = Some(key);
                }
            }
        }
    }
    best
}

fn check(world: &World, objects: &[WorldObject], ray: &Ray) {
    let expected = brute_force(objects, ray);
    let got = world.closest_hit(ray);
    assert_eq!(
        got.map(|h: Hit| (h.t, h.object, h.triangle, h.barycentric)),
        expected,
        "ray {ray:?}"
    );
    if let Some(h) = got {
        assert!((h.geometric_normal.length() - 1.0).abs() < 1e-5);
    }
    assert_eq!(world.occluded(ray), expected.is_some(), "ray {ray:?}");
}

/// Rays at every vertex, at every edge midpoint, along edges, and random.
fn rays(rng: &mut Rng, objects: &[WorldObject]) -> Vec<Ray> {
    let mut rays = Vec::new();
    for object in objects {
        let placed = |v: u32| {
            object
                .to_render
                .transform_point3(object.positions[v as usize])
        };
        for tri in object.triangles.iter().take(40) {
            let [a, b, c] = tri.map(placed);
            let origin = rng.vec(-6.0, 6.0) + Vec3::Y * 4.0;
            for target in [a, b, c, (a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5] {
                rays.push(Ray::new(origin, target - origin, f32::INFINITY));
                // A segment ending exactly there.
                rays.push(Ray::segment(origin, target));
            }
            rays.push(Ray::new(a, b - a, f32::INFINITY));
            rays.push(Ray::new(a - (b - a), b - a, 3.0));
        }
    }
    for _ in 0..200 {
        let origin = rng.vec(-8.0, 8.0);
        rays.push(Ray::new(origin, rng.vec(-1.0, 1.0), rng.range(0.5, 30.0)));
    }
    rays
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    #[test]
    fn static_world_equals_brute_force(seed in 1u64..u64::MAX) {
        let mut rng = Rng(seed);
        let m = mesh(&mut rng, 6);
        let objects = [WorldObject {
            positions: &m.positions,
            triangles: &m.triangles,
            to_render: Affine3A::from_translation(rng.vec(-1.0, 1.0)),
            dynamic: false,
        }];
        let world = World::build(&objects);
        let mut remembered = None;
        for ray in rays(&mut rng, &objects) {
            check(&world, &objects, &ray);
            // The shadow-cache query answers exactly what `occluded` does,
            // whichever triangle it is handed first (often one that misses).
            let occluder = world.static_occluder(&ray, remembered);
            prop_assert_eq!(occluder.is_some(), world.occluded_static(&ray), "ray {:?}", ray);
            remembered = occluder.or(remembered);
        }
    }

    #[test]
    fn static_and_dynamic_mix_equals_brute_force(seed in 1u64..u64::MAX) {
        let mut rng = Rng(seed);
        let meshes: Vec<Mesh> = (0..4).map(|_| mesh(&mut rng, 3)).collect();
        let mut objects: Vec<WorldObject> = meshes
            .iter()
            .enumerate()
            .map(|(i, m)| WorldObject {
                positions: &m.positions,
                triangles: &m.triangles,
                to_render: Affine3A::from_translation(rng.vec(-2.0, 2.0)),
                dynamic: i % 2 == 1,
            })
            .collect();
        let mut world = World::build(&objects);
        let mut blocker = None;
        for ray in rays(&mut rng, &objects) {
            check(&world, &objects, &ray);
            // With dynamic objects too, the query that starts from a
            // remembered static triangle answers what `occluded` does.
            prop_assert_eq!(world.occluded_near(&ray, &mut blocker), world.occluded(&ray));
        }
        // Move the dynamic ones (with scale and a mirror), then compare again.
        for (i, object) in objects.iter_mut().enumerate().filter(|(_, o)| o.dynamic) {
            let to_render = Affine3A::from_scale_rotation_translation(
                Vec3::new(rng.range(0.5, 2.0), -rng.range(0.5, 2.0), rng.range(0.5, 2.0)),
                Quat::from_rotation_y(rng.range(0.0, 6.0)),
                rng.vec(-3.0, 3.0),
            );
            world.set_transform(i, to_render).expect("dynamic");
            object.to_render = to_render;
        }
        for ray in rays(&mut rng, &objects) {
            check(&world, &objects, &ray);
        }
        let static_only: Vec<WorldObject> = objects.iter().filter(|o| !o.dynamic).copied().collect();
        let dynamic_only: Vec<WorldObject> = objects.iter().filter(|o| o.dynamic).copied().collect();
        for ray in rays(&mut rng, &objects) {
            assert_eq!(world.occluded_static(&ray), brute_force(&static_only, &ray).is_some());
            assert_eq!(world.occluded_dynamic(&ray), brute_force(&dynamic_only, &ray).is_some());
        }
    }
}

#[test]
fn deformed_dynamic_object_equals_brute_force() {
    let mut rng = Rng(7);
    let m = mesh(&mut rng, 5);
    let mut objects = [WorldObject {
        positions: &m.positions,
        triangles: &m.triangles,
        to_render: Affine3A::from_rotation_x(0.3),
        dynamic: true,
    }];
    let mut world = World::build(&objects);
    let (mut small, mut large) = (m.positions.clone(), m.positions.clone());
    // A gentle wave keeps every triangle's area (refit); collapsing the grid
    // flat onto a line removes area (rebuild).
    for p in &mut small {
        p.y += 0.2 * (p.x * 1.3).sin();
    }
    for p in &mut large {
        p.z = 0.0;
    }
    for positions in [&small, &large, &m.positions] {
        world.set_positions(0, positions).expect("dynamic");
        objects[0].positions = positions;
        for ray in rays(&mut rng, &objects) {
            check(&world, &objects, &ray);
        }
    }
    assert!(world.set_positions(0, &small[1..]).is_err());
    assert!(world.set_transform(1, Affine3A::IDENTITY).is_err());
}

#[test]
fn static_objects_refuse_to_move_and_bounds_cover_everything() {
    let mut rng = Rng(11);
    let (a, b) = (mesh(&mut rng, 2), mesh(&mut rng, 2));
    let objects = [
        WorldObject {
            positions: &a.positions,
            triangles: &a.triangles,
            to_render: Affine3A::IDENTITY,
            dynamic: false,
        },
        WorldObject {
            positions: &b.positions,
            triangles: &b.triangles,
            to_render: Affine3A::from_translation(Vec3::X * 100.0),
            dynamic: true,
        },
    ];
    let mut world = World::build(&objects);
    assert!(world.set_transform(0, Affine3A::IDENTITY).is_err());
    let bounds = world.bounds();
    assert!(bounds.max.x > 100.0 && bounds.min.x < 0.0);
    let moved = Affine3A::from_translation(Vec3::Y * 50.0);
    world.set_transform(1, moved).expect("dynamic");
    let ob = world.object_bounds(1).expect("object 1");
    assert!(ob.min.y > 40.0);
    assert!(world.object_bounds(2).is_none());
    // Two degenerate triangles per mesh are not counted.
    assert_eq!(
        world.triangle_count(),
        a.triangles.len() + b.triangles.len() - 4
    );
}

#[test]
fn hits_do_not_depend_on_thread_count() {
    let mut rng = Rng(3);
    let m = mesh(&mut rng, 90);
    let objects = [WorldObject {
        positions: &m.positions,
        triangles: &m.triangles,
        to_render: Affine3A::IDENTITY,
        dynamic: false,
    }];
    let rays = rays(&mut rng, &objects);
    let render = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .expect("pool");
        pool.install(|| {
            use rayon::prelude::*;
            let world = World::build(&objects);
            rays.par_iter()
                .map(|r| world.closest_hit(r))
                .collect::<Vec<_>>()
        })
    };
    assert_eq!(render(1), render(2));
}

#[test]
fn world_is_send_and_sync() {
    fn check<T: Send + Sync>() {}
    check::<World>();
}
