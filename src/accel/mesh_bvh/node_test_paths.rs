//! The AVX2 node test against the portable one, through whole queries: on
//! every kind of ray that stresses a box test (random, exactly axis-parallel,
//! grazing a face, aimed at shared edges and vertices of closed meshes,
//! huge coordinates, even non-finite directions), closest hits must agree
//! bit for bit and occlusion
//! answers (down to the slot found) must be the same.

use glam::Vec3;

use super::*;

#[test]
fn avx2_and_portable_node_tests_give_identical_hits() {
    let detected = NodeTestPath::detect();
    if detected == NodeTestPath::Portable {
        println!("no AVX2 on this CPU: only the portable node test ran");
    } else {
        println!("comparing the AVX2 node test with the portable one");
    }
    let (cube_positions, cube_triangles) = cube(6);
    let (sphere_positions, sphere_triangles) = uv_sphere(Vec3::new(0.3, 3.1, -0.7), 1.3, 24, 48);
    let mut random = Random(7);
    let meshes = [
        (cube_positions, cube_triangles),
        (sphere_positions, sphere_triangles),
        triangle_soup(&mut random, 3000),
    ];
    let mut compared = 0;
    let mut hits = 0;
    for (object, (positions, triangles)) in meshes.iter().enumerate() {
        let build: Vec<BuildTriangle> = (triangles.iter().enumerate())
            .map(|(i, t)| BuildTriangle {
                vertices: t.map(|v| positions[v as usize]),
                source: TriangleRef {
                    object: object as u32,
                    triangle: i as u32,
                },
            })
            .collect();
        let mut bvh = MeshBvh::build(&build, Layout::Wide, BvhBuildParams::medium_build());
        for ray in rays(&mut random, positions, triangles) {
            bvh.node_test = NodeTestPath::Portable;
            let portable = answers(&bvh, &ray);
            bvh.node_test = detected;
            let tested = answers(&bvh, &ray);
            assert_eq!(portable, tested, "{ray:?}");
            compared += 1;
            hits += usize::from(portable.0.is_some());
        }
    }
    assert!(
        compared > 20_000 && hits > compared / 4,
        "{hits} hits of {compared}"
    );
}

/// Closest hit as bits (t, source, barycentrics), whether occluded, and the
/// occluder found without a hint.
type Answers = (Option<(u32, TriangleRef, [u32; 2])>, bool, Option<u32>);

fn answers(bvh: &MeshBvh, ray: &Ray) -> Answers {
    let mut best = None;
    bvh.closest_hit(ray, &mut best);
    let closest = best.map(|h: MeshHit| {
        let barycentric = h.barycentric.to_array().map(f32::to_bits);
        (h.t.to_bits(), h.source, barycentric)
    });
    (closest, bvh.occluded(ray), bvh.occluder(ray, None))
}

/// The rays for one mesh: each kind many times over, from finite segments
/// to unbounded rays.
fn rays(random: &mut Random, positions: &[Vec3], triangles: &[[u32; 3]]) -> Vec<Ray> {
    let (min, max) = positions
        .iter()
        .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(min, max), &p| {
            (min.min(p), max.max(p))
        });
    let (centre, reach) = ((min + max) / 2.0, (max - min).max_element());
    let outside = |random: &mut Random| centre + random.unit() * reach * random.range(0.7, 3.0);
    let t_max = |random: &mut Random| match random.below(3) {
        0 => f32::INFINITY,
        1 => f32::MAX,
        _ => random.range(0.5, 4.0),
    };
    let mut rays = Vec::new();
    for _ in 0..2000 {
        // Random: anywhere near the mesh, any direction.
        let origin = centre + (random.unit() * random.range(0.0, 2.0)) * reach;
        rays.push(Ray::new(origin, random.unit(), t_max(random)));

        // Aimed at a shared vertex, or a point on a shared edge.
        let [a, b, c] = triangles[random.below(triangles.len())].map(|v| positions[v as usize]);
        let target = match random.below(3) {
            0 => a,
            1 => a + (b - a) * 0.5,
            _ => b.lerp(c, random.range(0.0, 1.0)),
        };
        let origin = outside(random);
        rays.push(Ray::new(origin, target - origin, t_max(random)));
        rays.push(Ray::segment(origin, target + (target - origin)));
        // From the vertex itself, on the faces of the boxes around it.
        rays.push(Ray::new(a, random.unit(), t_max(random)));

        // Axis-parallel: one, two or three exactly zero direction components,
        // from origins on the mesh's own planes (a vertex's coordinates).
        let mut direction = random.unit();
        for k in 0..3 {
            if random.below(2) == 0 {
                direction[k] = 0.0;
            }
        }
        if direction == Vec3::ZERO {
            direction[random.below(3)] = if random.below(2) == 0 { 1.0 } else { -1.0 };
        }
        let on_planes = positions[random.below(positions.len())];
        let origin = Vec3::select(direction.cmpeq(Vec3::ZERO), on_planes, outside(random));
        rays.push(Ray::new(origin, direction, t_max(random)));

        // Grazing: nearly in the plane of a triangle, through its vertex.
        let normal = (b - a).cross(c - a).normalize();
        let along = (b - a).normalize() + normal * random.range(-1e-6, 1e-6);
        rays.push(Ray::new(a - along * reach, along, t_max(random)));

        // Huge coordinates and extreme directions, aimed at the mesh.
        let far = random.unit() * 10f32.powf(random.range(5.0, 30.0));
        rays.push(Ray::new(centre + far, -far, 2.0));
        let tiny = Vec3::new(1e-30, -1e-38, random.range(-1.0, 1.0));
        rays.push(Ray::new(a - tiny * 1e30, tiny, f32::INFINITY));

        // Not finite: slabs of `0 * inf` or NaN, where `min`/`max` answer
        // by operand order.
        let mut direction = random.unit();
        direction[random.below(3)] = [f32::INFINITY, f32::NEG_INFINITY, f32::NAN][random.below(3)];
        rays.push(Ray::new(outside(random), direction, t_max(random)));
    }
    rays
}

/// The cube `[-1, 1]^3`, each face split into `n × n` quads, vertices
/// shared along face borders: closed, with edges and vertices on box planes.
fn cube(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let index = |p: [u32; 3]| p[0] + (n + 1) * (p[1] + (n + 1) * p[2]);
    let positions = (0..(n + 1).pow(3))
        .map(|i| {
            let (x, y, z) = (i % (n + 1), i / (n + 1) % (n + 1), i / (n + 1).pow(2));
            Vec3::new(x as f32, y as f32, z as f32) * (2.0 / n as f32) - 1.0
        })
        .collect();
    let mut triangles = Vec::new();
    for axis in 0..3 {
        for side in [0, n] {
            for j in 0..n {
                for i in 0..n {
                    let at = |di: u32, dj: u32| {
                        let mut p = [0; 3];
                        p[axis] = side;
                        p[(axis + 1) % 3] = i + di;
                        p[(axis + 2) % 3] = j + dj;
                        index(p)
                    };
                    let quad = [at(0, 0), at(1, 0), at(1, 1), at(0, 1)];
                    triangles.push([quad[0], quad[1], quad[2]]);
                    triangles.push([quad[0], quad[2], quad[3]]);
                }
            }
        }
    }
    (positions, triangles)
}

/// A closed latitude-longitude sphere: poles shared by their fans, the seam
/// shared by index.
fn uv_sphere(centre: Vec3, radius: f32, rings: u32, segments: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut positions = vec![centre + Vec3::Y * radius, centre - Vec3::Y * radius];
    for ring in 1..rings {
        let polar = std::f32::consts::PI * ring as f32 / rings as f32;
        for segment in 0..segments {
            let azimuth = std::f32::consts::TAU * segment as f32 / segments as f32;
            let (sin, cos) = polar.sin_cos();
            let p = Vec3::new(sin * azimuth.cos(), cos, sin * azimuth.sin());
            positions.push(centre + p * radius);
        }
    }
    let at = |ring: u32, segment: u32| 2 + (ring - 1) * segments + segment % segments;
    let mut triangles = Vec::new();
    for segment in 0..segments {
        triangles.push([0, at(1, segment + 1), at(1, segment)]);
        triangles.push([1, at(rings - 1, segment), at(rings - 1, segment + 1)]);
        for ring in 1..rings - 1 {
            let quad = [
                at(ring, segment),
                at(ring, segment + 1),
                at(ring + 1, segment + 1),
                at(ring + 1, segment),
            ];
            triangles.push([quad[0], quad[1], quad[2]]);
            triangles.push([quad[0], quad[2], quad[3]]);
        }
    }
    (positions, triangles)
}

/// Small triangles scattered through a cube of side 100: a deep tree with
/// many overlapping boxes.
fn triangle_soup(random: &mut Random, count: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let positions: Vec<Vec3> = (0..count)
        .flat_map(|_| {
            let a = (random.unit() * random.range(0.0, 50.0)).round();
            [a, a + random.unit() * 2.0, a + random.unit() * 2.0]
        })
        .collect();
    let triangles = (0..count).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect();
    (positions, triangles)
}

/// A small deterministic generator (SplitMix64), so failures reproduce.
struct Random(u64);

impl Random {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    fn range(&mut self, low: f32, high: f32) -> f32 {
        low + (high - low) * (self.next() >> 40) as f32 / (1u64 << 24) as f32
    }

    fn below(&mut self, n: usize) -> usize {
        (self.next() % n as u64) as usize
    }

    fn unit(&mut self) -> Vec3 {
        loop {
            let v = Vec3::new(
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
                self.range(-1.0, 1.0),
            );
            if (1e-3..=1.0).contains(&v.length_squared()) {
                return v.normalize();
            }
        }
    }
}
