//! Rays per second of the ray tracing core: closest-hit primary rays from a
//! 1920×1080 pinhole camera and shadow segments from the primary hits to 8
//! point lights, on a procedural city block of more than 1M triangles and on
//! a ~1k triangle scene, on one thread and on two (rayon). Also the static
//! BVH's build time, and the wide layout against BVH2 on the city. Figures go
//! to BENCHMARKS.md ("Ray tracing core").

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{Affine3A, Vec3};
use lmanim::accel::mesh_bvh::{BuildTriangle, Layout, MeshBvh, TriangleRef};
use lmanim::accel::{offset_ray_origin, Ray, World, WorldObject};
use obvhs::BvhBuildParams;
use rayon::prelude::*;

const WIDTH: u32 = 1920;
const HEIGHT: u32 = 1080;
/// Shadow rays start from every `SHADOW_STRIDE`-th primary hit in x and y,
/// to keep one iteration near a second.
const SHADOW_STRIDE: u32 = 2;

struct Mesh {
    positions: Vec<Vec3>,
    triangles: Vec<[u32; 3]>,
}

impl Mesh {
    fn new() -> Mesh {
        Mesh {
            positions: Vec::new(),
            triangles: Vec::new(),
        }
    }

    /// A planar grid from `origin` spanning `u` and `v`, `nu × nv` quads.
    fn grid(&mut self, origin: Vec3, u: Vec3, v: Vec3, nu: u32, nv: u32) {
        let base = self.positions.len() as u32;
        for j in 0..=nv {
            for i in 0..=nu {
                self.positions
                    .push(origin + u * (i as f32 / nu as f32) + v * (j as f32 / nv as f32));
            }
        }
        for j in 0..nv {
            for i in 0..nu {
                let a = base + j * (nu + 1) + i;
                let (b, c, d) = (a + 1, a + nu + 2, a + nu + 1);
                self.triangles.extend([[a, b, c], [a, c, d]]);
            }
        }
    }

    /// A building: four subdivided facades and a roof.
    fn building(&mut self, min: Vec3, size: Vec3, div: u32) {
        let (x, y, z) = (Vec3::X * size.x, Vec3::Y * size.y, Vec3::Z * size.z);
        let floors = (size.y / 3.0).ceil() as u32 * div;
        let across = |w: f32| (w / 3.0).ceil() as u32 * div;
        self.grid(min, x, y, across(size.x), floors);
        self.grid(min + z, x, y, across(size.x), floors);
        self.grid(min, z, y, across(size.z), floors);
        self.grid(min + x, z, y, across(size.z), floors);
        self.grid(min + y, x, z, 2, 2);
    }

    /// A UV sphere.
    fn sphere(&mut self, centre: Vec3, r: f32, rings: u32, segments: u32) {
        let base = self.positions.len() as u32;
        for j in 0..=rings {
            let theta = std::f32::consts::PI * j as f32 / rings as f32;
            for i in 0..segments {
                let phi = std::f32::consts::TAU * i as f32 / segments as f32;
                let dir = Vec3::new(
                    theta.sin() * phi.cos(),
                    theta.cos(),
                    theta.sin() * phi.sin(),
                );
                self.positions.push(centre + r * dir);
            }
        }
        for j in 0..rings {
            for i in 0..segments {
                let a = base + j * segments + i;
                let b = base + j * segments + (i + 1) % segments;
                let (c, d) = (b + segments, a + segments);
                // Pole rows would be zero-area triangles; they are dropped at
                // build like any other.
                self.triangles.extend([[a, b, c], [a, c, d]]);
            }
        }
    }
}

/// Deterministic pseudo-random numbers in `[0, 1)`.
fn hash(i: u32) -> f32 {
    let mut x = i.wrapping_mul(0x9e37_79b9) ^ 0x85eb_ca6b;
    x ^= x >> 15;
    x = x.wrapping_mul(0x2c1b_3c6d);
    x ^= x >> 12;
    (x >> 8) as f32 / (1 << 24) as f32
}

/// A `blocks × blocks` grid of city blocks of four buildings each, with
/// spheres in the streets, on a ground plane.
fn city(blocks: u32, div: u32, sphere_res: u32) -> Mesh {
    let mut m = Mesh::new();
    let pitch = 40.0;
    let extent = blocks as f32 * pitch;
    m.grid(
        Vec3::new(-10.0, 0.0, -10.0),
        Vec3::X * (extent + 10.0),
        Vec3::Z * (extent + 10.0),
        8,
        8,
    );
    let mut k = 0;
    for bz in 0..blocks {
        for bx in 0..blocks {
            for (dx, dz) in [(0.0, 0.0), (16.0, 0.0), (0.0, 16.0), (16.0, 16.0)] {
                k += 1;
                let height = 6.0 + 50.0 * hash(k).powi(2);
                let min = Vec3::new(bx as f32 * pitch + dx, 0.0, bz as f32 * pitch + dz);
                m.building(
                    min,
                    Vec3::new(12.0 + 2.0 * hash(k + 1000), height, 12.0),
                    div,
                );
            }
            if (bx + bz) % 2 == 0 {
                let c = Vec3::new(bx as f32 * pitch + 35.0, 2.5, bz as f32 * pitch + 35.0);
                m.sphere(c, 2.5, sphere_res, sphere_res * 2);
            }
        }
    }
    m
}

struct Scene {
    name: &'static str,
    mesh: Mesh,
    eye: Vec3,
    look_at: Vec3,
    lights: Vec<Vec3>,
}

fn scenes() -> Vec<Scene> {
    let big = city(12, 3, 32);
    let small = city(1, 1, 6);
    let lights = |extent: f32| {
        (0..8)
            .map(|i| {
                Vec3::new(
                    extent * hash(i * 3 + 7),
                    20.0 + 40.0 * hash(i * 3 + 8),
                    extent * hash(i * 3 + 9),
                )
            })
            .collect()
    };
    vec![
        Scene {
            name: "city",
            mesh: big,
            eye: Vec3::new(-30.0, 25.0, -30.0),
            look_at: Vec3::new(240.0, 0.0, 240.0),
            lights: lights(480.0),
        },
        Scene {
            name: "small",
            mesh: small,
            eye: Vec3::new(-25.0, 20.0, -25.0),
            look_at: Vec3::new(20.0, 5.0, 20.0),
            lights: lights(40.0),
        },
    ]
}

/// The primary ray through pixel `(x, y)`: 60° vertical field of view.
fn camera_ray(eye: Vec3, look_at: Vec3, x: u32, y: u32) -> Ray {
    let forward = (look_at - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let half = (30f32).to_radians().tan();
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let sx = (2.0 * (x as f32 + 0.5) / WIDTH as f32 - 1.0) * half * aspect;
    let sy = (1.0 - 2.0 * (y as f32 + 0.5) / HEIGHT as f32) * half;
    Ray::new(eye, forward + sx * right + sy * up, f32::INFINITY)
}

fn primary_rays(scene: &Scene) -> Vec<Ray> {
    (0..HEIGHT)
        .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
        .map(|(x, y)| camera_ray(scene.eye, scene.look_at, x, y))
        .collect()
}

/// Shadow segments from the (offset) primary hits to every light on the
/// hit's side.
fn shadow_rays(scene: &Scene, world: &World) -> Vec<Ray> {
    let points: Vec<(Vec3, Vec3)> = (0..HEIGHT)
        .step_by(SHADOW_STRIDE as usize)
        .flat_map(|y| {
            (0..WIDTH)
                .step_by(SHADOW_STRIDE as usize)
                .map(move |x| (x, y))
        })
        .filter_map(|(x, y)| {
            let ray = camera_ray(scene.eye, scene.look_at, x, y);
            let hit = world.closest_hit(&ray)?;
            let n = hit.geometric_normal;
            let n = if n.dot(ray.direction) < 0.0 { n } else { -n };
            Some((offset_ray_origin(ray.at(hit.t), n), n))
        })
        .collect();
    points
        .iter()
        .flat_map(|&(p, _)| scene.lights.iter().map(move |&l| Ray::segment(p, l)))
        .collect()
}

fn pools() -> Vec<(usize, rayon::ThreadPool)> {
    [1, 2]
        .into_iter()
        .map(|n| {
            (
                n,
                rayon::ThreadPoolBuilder::new()
                    .num_threads(n)
                    .build()
                    .expect("thread pool"),
            )
        })
        .collect()
}

fn bench_world(c: &mut Criterion) {
    for scene in scenes() {
        let objects = [WorldObject {
            positions: &scene.mesh.positions,
            triangles: &scene.mesh.triangles,
            to_render: Affine3A::IDENTITY,
            dynamic: false,
        }];
        let start = Instant::now();
        let world = World::build(&objects);
        println!(
            "{}: {} triangles, World::build {:.2} s",
            scene.name,
            world.triangle_count(),
            start.elapsed().as_secs_f64()
        );
        let primary = primary_rays(&scene);
        let shadow = shadow_rays(&scene, &world);
        let mut group = c.benchmark_group(format!("rays/{}", scene.name));
        for (threads, pool) in pools() {
            group.throughput(Throughput::Elements(primary.len() as u64));
            group.bench_function(format!("primary_closest/{threads}t"), |b| {
                b.iter(|| {
                    pool.install(|| {
                        primary
                            .par_chunks(4096)
                            .map(|c| c.iter().filter(|r| world.closest_hit(r).is_some()).count())
                            .sum::<usize>()
                    })
                })
            });
            group.throughput(Throughput::Elements(shadow.len() as u64));
            group.bench_function(format!("shadow_occluded/{threads}t"), |b| {
                b.iter(|| {
                    pool.install(|| {
                        shadow
                            .par_chunks(4096)
                            .map(|c| c.iter().filter(|r| world.occluded(r)).count())
                            .sum::<usize>()
                    })
                })
            });
        }
        group.finish();
    }
}

/// The wide layout (CWBVH topology, exact boxes) against BVH2, and build
/// presets, over the city's triangles, two threads.
fn bench_layouts(c: &mut Criterion) {
    let scene = scenes().remove(0);
    let triangles: Vec<BuildTriangle> = (scene.mesh.triangles.iter().enumerate())
        .map(|(i, t)| BuildTriangle {
            vertices: t.map(|v| scene.mesh.positions[v as usize]),
            source: TriangleRef {
                object: 0,
                triangle: i as u32,
            },
        })
        .collect();
    let objects = [WorldObject {
        positions: &scene.mesh.positions,
        triangles: &scene.mesh.triangles,
        to_render: Affine3A::IDENTITY,
        dynamic: false,
    }];
    let world = World::build(&objects);
    let primary = primary_rays(&scene);
    let shadow = shadow_rays(&scene, &world);
    drop(world);
    let (_, pool) = pools().remove(1);
    let mut group = c.benchmark_group("layouts/city");
    let presets = [
        ("fast", BvhBuildParams::fast_build()),
        ("medium", BvhBuildParams::medium_build()),
    ];
    for (layout_name, layout) in [("wide", Layout::Wide), ("bvh2", Layout::Binary)] {
        for (preset_name, params) in presets {
            let start = Instant::now();
            let bvh = MeshBvh::build(&triangles, layout, params);
            println!(
                "{layout_name}/{preset_name}: build {:.2} s",
                start.elapsed().as_secs_f64()
            );
            group.throughput(Throughput::Elements(primary.len() as u64));
            group.bench_function(
                format!("{layout_name}/{preset_name}/primary_closest/2t"),
                |b| {
                    b.iter(|| {
                        pool.install(|| {
                            primary.par_chunks(4096).for_each(|c| {
                                for r in c {
                                    let mut best = None;
                                    bvh.closest_hit(r, &mut best);
                                    std::hint::black_box(best);
                                }
                            })
                        })
                    })
                },
            );
            group.throughput(Throughput::Elements(shadow.len() as u64));
            group.bench_function(
                format!("{layout_name}/{preset_name}/shadow_occluded/2t"),
                |b| {
                    b.iter(|| {
                        pool.install(|| {
                            shadow
                                .par_chunks(4096)
                                .map(|c| c.iter().filter(|r| bvh.occluded(r)).count())
                                .sum::<usize>()
                        })
                    })
                },
            );
        }
    }
    group.finish();
}

fn config() -> Criterion {
    Criterion::default()
        .sample_size(10)
        .warm_up_time(Duration::from_millis(500))
        .measurement_time(Duration::from_secs(4))
}

criterion_group! {
    name = benches;
    config = config();
    targets = bench_world, bench_layouts
}
criterion_main!(benches);
