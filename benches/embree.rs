//! Our BVH against Embree 4, side by side, on the very rays of `rays.rs`:
//! the same scenes, the same 1080p primary rays (closest hit) and shadow
//! segments (any hit), traced by `World` and, in the same run, by Embree
//! through its Python binding `embreex` (`benches/embree/trace.py`).
//!
//! Run it with `benches/embree/run.sh`, which installs `embreex` into
//! `target/embree-venv` and points `LMANIM_EMBREE_PYTHON` at it. Figures go
//! to BENCHMARKS.md ("Against Embree, side by side").
//!
//! The binding traces one ray per `rtcIntersect1` / `rtcOccluded1` call in
//! a loop that holds Python's lock, so Embree's two-thread figure comes
//! from two processes, each with its own copy of the scene, tracing half
//! the rays; and the loop's own cost per ray (measured on rays that miss
//! the scene's bounds) is reported beside it, so Embree's traversal alone
//! can be told apart from the binding.
//!
//! Embree runs twice: with its default scene flags, and robust
//! (`RTC_SCENE_FLAG_ROBUST`, which gives up the optimisations that cost
//! accuracy). `World` always keeps that guarantee (conservative box tests,
//! the watertight triangle test), so the robust figures are the like for
//! like ones.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::time::Instant;

use glam::{Affine3A, Vec3};
use lmanim::accel::{Ray, World, WorldObject};
use rayon::prelude::*;

mod ray_scenes;
use ray_scenes::{pools, primary_rays, scenes, shadow_rays, Scene};

/// Timed passes over each ray set; the fastest is kept.
const REPEATS: usize = 3;

/// The tracers of the table.
const LMANIM: &str = "lmanim World";
const EMBREE: &str = "Embree (embreex)";
/// Embree with `RTC_SCENE_FLAG_ROBUST`, which gives up the optimisations
/// that cost accuracy: the guarantee `World`'s traversal always keeps.
const EMBREE_ROBUST: &str = "Embree robust (embreex)";

/// One figure of the table: a tracer, a query, threads, rays per second
/// and the answers it gave (hits, or occluded segments).
struct Figure {
    tracer: String,
    query: &'static str,
    threads: usize,
    rays_per_second: f64,
    answers: u64,
}

fn main() {
    let Some(python) = std::env::var_os("LMANIM_EMBREE_PYTHON") else {
        eprintln!(
            "embree: LMANIM_EMBREE_PYTHON is not set; run benches/embree/run.sh, which installs \
             embreex into target/embree-venv and runs this bench with it"
        );
        std::process::exit(2);
    };
    let exchange = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("embree-rays");
    std::fs::create_dir_all(&exchange).expect("create the ray exchange folder");
    for scene in scenes() {
        let world = World::build(&[WorldObject {
            positions: &scene.mesh.positions,
            triangles: &scene.mesh.triangles,
            to_render: Affine3A::IDENTITY,
            dynamic: false,
        }]);
        let primary = primary_rays(&scene);
        let shadow = shadow_rays(&scene, &world);
        write_scene(&exchange, &scene, &primary, &shadow);
        let mut figures = ours(&world, &primary, &shadow);
        figures.extend(embree(Path::new(&python), &exchange));
        print_table(&scene, world.triangle_count(), &primary, &shadow, &figures);
    }
}

/// `World`'s rays per second, 1 and 2 threads.
fn ours(world: &World, primary: &[Ray], shadow: &[Ray]) -> Vec<Figure> {
    let mut figures = Vec::new();
    for (threads, pool) in pools() {
        let closest = |rays: &[Ray]| -> u64 {
            (rays.par_chunks(4096))
                .map(|c| c.iter().filter(|r| world.closest_hit(r).is_some()).count() as u64)
                .sum()
        };
        let occluded = |rays: &[Ray]| -> u64 {
            (rays.par_chunks(4096))
                .map(|c| c.iter().filter(|r| world.occluded(r)).count() as u64)
                .sum()
        };
        for (query, rays, trace) in [
            (
                "primary closest hit",
                primary,
                &closest as &(dyn Fn(&[Ray]) -> u64 + Sync),
            ),
            ("shadow segments", shadow, &occluded),
        ] {
            let (seconds, answers) = fastest(|| pool.install(|| trace(rays)));
            figures.push(Figure {
                tracer: LMANIM.into(),
                query,
                threads,
                rays_per_second: rays.len() as f64 / seconds,
                answers,
            });
        }
    }
    figures
}

/// The fastest of [`REPEATS`] runs of `trace`, and its answer.
fn fastest(trace: impl Fn() -> u64) -> (f64, u64) {
    (0..REPEATS)
        .map(|_| {
            let start = Instant::now();
            let answers = trace();
            (start.elapsed().as_secs_f64(), answers)
        })
        .min_by(|a, b| a.0.total_cmp(&b.0))
        .expect("at least one run")
}

/// The scene's triangles and both ray sets as raw little-endian arrays,
/// which `trace.py` reads with `numpy.fromfile`.
fn write_scene(dir: &Path, scene: &Scene, primary: &[Ray], shadow: &[Ray]) {
    let floats = |values: &mut dyn Iterator<Item = Vec3>| -> Vec<u8> {
        values
            .flat_map(|v| v.to_array())
            .flat_map(f32::to_le_bytes)
            .collect()
    };
    let write = |name: &str, bytes: Vec<u8>| {
        std::fs::write(dir.join(name), bytes).expect("write the ray exchange");
    };
    write(
        "positions.f32",
        floats(&mut scene.mesh.positions.iter().copied()),
    );
    write(
        "triangles.u32",
        (scene.mesh.triangles.iter().flatten())
            .flat_map(|i| i.to_le_bytes())
            .collect(),
    );
    for (name, rays) in [("primary", primary), ("shadow", shadow)] {
        write(
            &format!("{name}-origins.f32"),
            floats(&mut rays.iter().map(|r| r.origin)),
        );
        write(
            &format!("{name}-directions.f32"),
            floats(&mut rays.iter().map(|r| r.direction)),
        );
        let tmax = rays.iter().flat_map(|r| r.t_max.to_le_bytes()).collect();
        write(&format!("{name}-tmax.f32"), tmax);
    }
}

/// Embree's figures from `trace.py`, one line per figure:
/// `mode<TAB>query<TAB>threads<TAB>rays per second<TAB>answers`.
fn embree(python: &Path, dir: &Path) -> Vec<Figure> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("benches/embree/trace.py");
    let output = Command::new(python)
        .arg(script)
        .arg(dir)
        .arg(REPEATS.to_string())
        .output()
        .expect("run benches/embree/trace.py");
    if !output.status.success() {
        eprintln!("{}", String::from_utf8_lossy(&output.stderr));
        panic!("benches/embree/trace.py failed: {}", output.status);
    }
    String::from_utf8_lossy(&output.stdout)
        .lines()
        .map(|line| {
            let fields: Vec<&str> = line.split('\t').collect();
            let [mode, query, threads, rate, answers] = fields[..] else {
                panic!("trace.py printed {line:?}");
            };
            Figure {
                tracer: match mode {
                    "default" => EMBREE,
                    "robust" => EMBREE_ROBUST,
                    other => panic!("trace.py ran Embree in mode {other:?}"),
                }
                .into(),
                query: match query {
                    "primary" => "primary closest hit",
                    "shadow" => "shadow segments",
                    "primary-binding" => "binding alone, closest",
                    "shadow-binding" => "binding alone, any hit",
                    other => panic!("trace.py measured {other:?}"),
                },
                threads: threads.parse().expect("threads"),
                rays_per_second: rate.parse().expect("rays per second"),
                answers: answers.parse().expect("answers"),
            }
        })
        .collect()
}

fn print_table(
    scene: &Scene,
    triangles: usize,
    primary: &[Ray],
    shadow: &[Ray],
    figures: &[Figure],
) {
    println!(
        "\n{}: {triangles} triangles, {} primary rays, {} shadow segments to {} lights",
        scene.name,
        primary.len(),
        shadow.len(),
        scene.lights.len()
    );
    println!("| tracer | query | threads | Mrays/s | answers |");
    println!("|---|---|---|---|---|");
    for figure in figures {
        println!(
            "| {} | {} | {} | {:.2} | {} |",
            figure.tracer,
            figure.query,
            figure.threads,
            figure.rays_per_second / 1e6,
            figure.answers
        );
    }
    // Embree's traversal alone: its time per ray less the binding's loop.
    let rate = |tracer: &str, query: &str, threads: usize| {
        (figures.iter())
            .find(|f| f.tracer == tracer && f.query == query && f.threads == threads)
            .map(|f| f.rays_per_second)
    };
    for embree in [EMBREE, EMBREE_ROBUST] {
        for (query, binding) in [
            ("primary closest hit", "binding alone, closest"),
            ("shadow segments", "binding alone, any hit"),
        ] {
            for threads in [1, 2] {
                let (Some(ours), Some(through_binding), Some(loop_alone)) = (
                    rate(LMANIM, query, threads),
                    rate(embree, query, threads),
                    rate(embree, binding, threads),
                ) else {
                    continue;
                };
                let traversal = 1.0 / (1.0 / through_binding - 1.0 / loop_alone);
                println!(
                    "{query}, {threads} thread(s): lmanim / {embree} = {:.2} through the \
                     binding, {:.2} against its traversal alone ({:.2} Mrays/s)",
                    ours / through_binding,
                    ours / traversal,
                    traversal / 1e6
                );
            }
        }
    }
}
