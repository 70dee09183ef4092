//! Rays per second of the ray tracing core: closest-hit primary rays from a
//! 1920×1080 pinhole camera and shadow segments from the primary hits to 8
//! point lights, on a procedural city block of more than 1M triangles and on
//! a ~1k triangle scene, on one thread and on two (rayon). Also the static
//! BVH's build time, and the wide layout against BVH2 on the city. Figures go
//! to BENCHMARKS.md ("Ray tracing core").

use std::time::{Duration, Instant};

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Affine3A;
use lmanim::accel::mesh_bvh::{BuildTriangle, Layout, MeshBvh, TriangleRef};
use lmanim::accel::{World, WorldObject};
use obvhs::BvhBuildParams;
use rayon::prelude::*;

mod ray_scenes;
use ray_scenes::{pools, primary_rays, scenes, shadow_rays};

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
