//! The scenes and rays of the ray-tracing benches (`rays.rs`, and
//! `embree.rs`, which traces the very same rays through Embree): a
//! procedural city of 1.8M triangles and a one-block one of 1.4k, 1080p
//! primary rays, and shadow segments from their hits to 8 point lights.

use glam::Vec3;
use lmanim::accel::{offset_ray_origin, Ray, World};

pub const WIDTH: u32 = 1920;
pub const HEIGHT: u32 = 1080;
/// Shadow rays start from every `SHADOW_STRIDE`-th primary hit in x and y,
/// to keep one iteration near a second.
pub const SHADOW_STRIDE: u32 = 2;

pub struct Mesh {
    pub positions: Vec<Vec3>,
    pub triangles: Vec<[u32; 3]>,
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

pub struct Scene {
    pub name: &'static str,
    pub mesh: Mesh,
    pub eye: Vec3,
    pub look_at: Vec3,
    pub lights: Vec<Vec3>,
}

pub fn scenes() -> Vec<Scene> {
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
pub fn camera_ray(eye: Vec3, look_at: Vec3, x: u32, y: u32) -> Ray {
    let forward = (look_at - eye).normalize();
    let right = forward.cross(Vec3::Y).normalize();
    let up = right.cross(forward);
    let half = (30f32).to_radians().tan();
    let aspect = WIDTH as f32 / HEIGHT as f32;
    let sx = (2.0 * (x as f32 + 0.5) / WIDTH as f32 - 1.0) * half * aspect;
    let sy = (1.0 - 2.0 * (y as f32 + 0.5) / HEIGHT as f32) * half;
    Ray::new(eye, forward + sx * right + sy * up, f32::INFINITY)
}

pub fn primary_rays(scene: &Scene) -> Vec<Ray> {
    (0..HEIGHT)
        .flat_map(|y| (0..WIDTH).map(move |x| (x, y)))
        .map(|(x, y)| camera_ray(scene.eye, scene.look_at, x, y))
        .collect()
}

/// Shadow segments from the (offset) primary hits to every light on the
/// hit's side.
pub fn shadow_rays(scene: &Scene, world: &World) -> Vec<Ray> {
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

pub fn pools() -> Vec<(usize, rayon::ThreadPool)> {
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
