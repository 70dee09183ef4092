//! Reuse over generated scenes: every frame a run renders, reusing the
//! light mesh's masks from its earlier frames or from a disk cache,
//! equals the same frame rendered cold by a run of its own, bit for bit.
//!
//! Runs are made as the command line makes them, each planned over its
//! own frames (`Plan::make`, `Sequence::planned`): the whole shot as one
//! run; each frame alone; the shot split into two farm chunks; and a
//! chunk that starts from a disk cache `warm` filled. A scene is a
//! ground, static boxes and walls, one to eight lights (some moving, some
//! lamps with a radius), one to four boxes driven along random paths
//! across shadows and lattice planes (some snapped to lattice nodes), with
//! a random lattice step, kI, kernel and penumbra mode, for `lmm`,
//! `lmm1` and `auto`; some lights have a short range, so the plan switches
//! them off in some runs' frames and not in others.
//!
//! Beside reuse, the same generated shots check the backends' parity:
//! every frame on the GPU is the CPU's, bit for bit; and after every
//! frame on the GPU, the mask pool's slots hold the light mesh's bricks
//! word for word (it sends only the words that changed).
//!
//! CI runs a fixed set of cases ([`config`]); `LMANIM_REUSE_CASES=N`
//! runs more (BENCHMARKS.md, "Reuse property"). A failing case is shrunk
//! and kept in `reuse_property.proptest-regressions`, which proptest
//! replays first on every later run. The street of issue 32 (fifty
//! buildings, four cars, four lights) is checked by hand beside them.

mod common;

use std::path::Path;

use common::*;
use glam::{DMat4, DVec3, Vec3};
use proptest::prelude::*;
use proptest::test_runner::{RngSeed, TestRunner};

use lmanim::backend::Backend;
use lmanim::lightmesh::kernel::Kernel;
use lmanim::lightmesh::penumbra::Penumbra;
use lmanim::output::Image;
use lmanim::scene::{LightKind, SceneDesc};
use lmanim::schedule::Timeline;
use lmanim::settings::{BackendKind, Method, Settings};
use lmanim::stats::FrameStats;

/// Frames per second of the generated shots: a box crosses a few metres
/// between frames, so each frame changes many masks.
const FPS: f64 = 4.0;

/// A box standing on the ground (y = 0): centre x and z, half sizes.
#[derive(Clone, Debug)]
struct Block {
    x: f32,
    z: f32,
    half: Vec3,
}

/// A box driven in a straight line from one place on the ground to
/// another over the shot.
#[derive(Clone, Debug)]
struct Mover {
    from: (f32, f32),
    to: (f32, f32),
    half: Vec3,
}

#[derive(Clone, Debug)]
struct Lamp {
    at: Vec3,
    /// Where it is at the end of the shot, for a moving light.
    to: Option<Vec3>,
    intensity: f32,
    /// 0 for an ideal point.
    radius: f32,
    /// A range short enough that the plan may find the light reaching
    /// nothing in view in some frames (then it is switched off there).
    range: Option<f32>,
}

/// One generated case: the scene's parts, the light mesh's settings, the
/// shot's length and where it is split into farm chunks.
#[derive(Clone, Debug)]
struct Case {
    blocks: Vec<Block>,
    movers: Vec<Mover>,
    lamps: Vec<Lamp>,
    /// Movers' ends rounded to lattice nodes: their faces then lie in
    /// lattice planes, and segments graze them.
    on_lattice: bool,
    camera_azimuth: f64,
    method: Method,
    h: f32,
    ki: f32,
    kernel: Kernel,
    penumbra: Penumbra,
    frames: u32,
    split: u32,
}

fn block() -> impl Strategy<Value = Block> {
    let wall = (0.05f32..0.2, 0.5f32..2.5, 1.0f32..4.0);
    let solid = (0.3f32..1.5, 0.3f32..2.5, 0.3f32..1.5);
    let half = prop_oneof![
        solid.prop_map(|(x, y, z)| Vec3::new(x, y, z)),
        wall.prop_map(|(x, y, z)| Vec3::new(x, y, z)),
    ];
    (-6.0f32..6.0, -6.0f32..6.0, half).prop_map(|(x, z, half)| Block { x, z, half })
}

fn mover() -> impl Strategy<Value = Mover> {
    let place = || (-6.0f32..6.0, -6.0f32..6.0);
    let half = (0.2f32..1.0, 0.2f32..0.8, 0.2f32..1.0).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    (place(), place(), half).prop_map(|(from, to, half)| Mover { from, to, half })
}

fn lamp() -> impl Strategy<Value = Lamp> {
    let place =
        || (-6.0f32..6.0, 1.5f32..6.0, -6.0f32..6.0).prop_map(|(x, y, z)| Vec3::new(x, y, z));
    let radius = prop_oneof![Just(0.0f32), 0.05f32..0.4];
    let range = proptest::option::weighted(0.3, 2.0f32..12.0);
    let moves = proptest::option::weighted(0.3, place());
    (place(), moves, 20.0f32..200.0, radius, range).prop_map(
        |(at, to, intensity, radius, range)| Lamp {
            at,
            to,
            intensity,
            radius,
            range,
        },
    )
}

fn case() -> impl Strategy<Value = Case> {
    let scene = (
        proptest::collection::vec(block(), 1..6),
        proptest::collection::vec(mover(), 1..=4),
        proptest::collection::vec(lamp(), 1..=8),
        any::<bool>(),
        0.0f64..std::f64::consts::TAU,
    );
    // `auto` (the default) shades hard lights by shadow rays and soft ones
    // by LMM1, so the plan's shadow classes take part too.
    let method = prop_oneof![Just(Method::Lmm), Just(Method::Lmm1), Just(Method::Auto)];
    let kernel = prop_oneof![Just(Kernel::Box), Just(Kernel::Smooth)];
    let penumbra = prop_oneof![
        Just(Penumbra::Fixed),
        Just(Penumbra::Blocker),
        Just(Penumbra::Wide)
    ];
    let mesh = (method, 0.12f32..0.4, 2.0f32..3.0, kernel, penumbra);
    let shot = (3u32..=6).prop_flat_map(|frames| (Just(frames), 1..frames));
    (scene, mesh, shot).prop_map(
        |(
            (blocks, movers, lamps, on_lattice, camera_azimuth),
            (method, h, ki, kernel, penumbra),
            (frames, split),
        )| Case {
            blocks,
            movers,
            lamps,
            on_lattice,
            camera_azimuth,
            method,
            h,
            ki,
            kernel,
            penumbra,
            frames,
            split,
        },
    )
}

impl Case {
    fn scene(&self) -> SceneDesc {
        let mut scene = empty_scene();
        let grey = add_material(&mut scene, lambert(Vec3::splat(0.6)));
        add_quads(&mut scene, &[floor_quad(0.0, 9.0)], 6, grey);
        for block in &self.blocks {
            add_box(
                &mut scene,
                Vec3::new(block.x, 0.0, block.z),
                block.half,
                grey,
            );
        }
        let duration = (self.frames - 1) as f32 / FPS as f32;
        let snap = |x: f32| match self.on_lattice {
            true => (x / self.h).round() * self.h,
            false => x,
        };
        let mut channels = Vec::new();
        for mover in &self.movers {
            let ground = |(x, z): (f32, f32)| Vec3::new(snap(x), 0.0, snap(z));
            let (from, to) = (ground(mover.from), ground(mover.to));
            let node = add_box(&mut scene, from, mover.half, grey);
            channels.push(linear_translation(node, from, to, duration));
            scene.nodes[node].animated = true;
        }
        for lamp in &self.lamps {
            let node = add_lamp(&mut scene, lamp.intensity, lamp.at, lamp.radius);
            let light = scene.lights.last_mut().unwrap();
            light.range = lamp.range;
            if lamp.radius == 0.0 {
                light.radius = None;
            }
            if let Some(to) = lamp.to {
                channels.push(linear_translation(node, lamp.at, to, duration));
                scene.nodes[node].animated = true;
            }
        }
        let (sin, cos) = self.camera_azimuth.sin_cos();
        let eye = DVec3::new(12.0 * sin, 9.0, 12.0 * cos);
        add_camera(&mut scene, perspective(0.9), look_at(eye, DVec3::ZERO));
        add_clip(&mut scene, "traffic", channels);
        scene
    }

    fn settings(&self, backend: BackendKind) -> Settings {
        let mut settings = settings(40, 24);
        settings.backend = backend;
        settings.method = self.method;
        settings.fps = FPS;
        settings.threads = Some(2);
        settings.cache_dir = None;
        settings.lightmesh.h = Some(self.h);
        settings.lightmesh.ki = self.ki;
        settings.lightmesh.kernel = self.kernel;
        settings.lightmesh.penumbra = self.penumbra;
        settings
    }
}

/// A closed box of half sizes `half` whose base centre is at `base`: a
/// cube on a node that scales it, so that a mover's channel moves its
/// node as it would a car's.
fn add_box(scene: &mut SceneDesc, base: Vec3, half: Vec3, material: u32) -> usize {
    let node = add_quads(scene, &box_quads(Vec3::Y, 1.0), 1, material);
    scene.nodes[node].local =
        DMat4::from_translation(base.as_dvec3()) * DMat4::from_scale(half.as_dvec3());
    node
}

/// One run of `scene` as the command line makes it: planned over
/// `frames`, rendering them in order on `backend`, with the disk cache in
/// `cache` if given; `warm_first` fills that cache over the frames first,
/// as a farm's Warm step does, in a run of its own.
fn run(
    scene: &SceneDesc,
    settings: &Settings,
    frames: &[u32],
    cache: Option<&Path>,
    backend: &mut Backend,
) -> Vec<Image> {
    let mut sequence = planned(scene, settings, &frame_list(frames));
    sequence.set_cache_dir(cache.map(Path::to_owned));
    let timeline = Timeline { fps: settings.fps };
    let images = (frames.iter())
        .map(|&frame| {
            let mut stats = FrameStats::default();
            let placed = (sequence.advance(timeline.time_of(frame), settings, &mut stats)).unwrap();
            let image = (sequence.render(backend, &placed, settings, &mut stats)).unwrap();
            common::gpu::assert_pool_holds_the_store(backend, &sequence, frame);
            image
        })
        .collect();
    sequence.save_cache().unwrap();
    images
}

/// `lmanim warm` over `frames`: their masks computed and their static
/// layer saved to `cache`, nothing shaded.
fn warm(
    scene: &SceneDesc,
    settings: &Settings,
    frames: &[u32],
    cache: &Path,
    backend: &mut Backend,
) {
    let mut sequence = planned(scene, settings, &frame_list(frames));
    sequence.set_cache_dir(Some(cache.to_owned()));
    let timeline = Timeline { fps: settings.fps };
    for &frame in frames {
        let mut stats = FrameStats::default();
        let placed = (sequence.advance(timeline.time_of(frame), settings, &mut stats)).unwrap();
        sequence
            .warm(backend, &placed, settings, &mut stats)
            .unwrap();
    }
    sequence.save_cache().unwrap();
}

/// `frames` as `--frames` takes a list (`0,1,2`).
fn frame_list(frames: &[u32]) -> String {
    (frames.iter().map(u32::to_string))
        .collect::<Vec<_>>()
        .join(",")
}

/// Every way a run can reach frame f (in the whole shot, in its farm
/// chunk, in a chunk started from a warmed disk cache) against frame f
/// rendered alone: the first difference, or None.
fn reuse_fault(
    scene: &SceneDesc,
    settings: &Settings,
    frames: u32,
    split: u32,
    backend: &mut Backend,
) -> Option<String> {
    let shot: Vec<u32> = (0..frames).collect();
    let cold: Vec<Image> = (shot.iter())
        .map(|&frame| run(scene, settings, &[frame], None, backend).remove(0))
        .collect();
    let cache = tempfile::tempdir().unwrap();
    warm(scene, settings, &shot, cache.path(), backend);
    let (first, second) = shot.split_at(split as usize);
    let runs: [(&str, &[u32], Option<&Path>); 4] = [
        ("the whole shot", &shot, None),
        ("the first chunk", first, None),
        ("the second chunk", second, None),
        (
            "the second chunk from a warm cache",
            second,
            Some(cache.path()),
        ),
    ];
    for (name, frames, cache) in runs {
        let images = run(scene, settings, frames, cache, backend);
        for (&frame, image) in frames.iter().zip(&images) {
            let cold = &cold[frame as usize];
            if image != cold {
                let differ = (image.pixels.iter().zip(&cold.pixels))
                    .filter(|(a, b)| a != b)
                    .count();
                return Some(format!(
                    "frame {frame} rendered in {name} differs from it rendered alone in {differ} pixels"
                ));
            }
        }
    }
    None
}

/// The generated cases: `in_ci` of them from a fixed seed, so CI checks
/// the same scenes on every run; `LMANIM_REUSE_CASES` and
/// `LMANIM_REUSE_SEED` ask for others.
fn config(in_ci: u32) -> ProptestConfig {
    let from_env = |name: &str| std::env::var(name).ok().and_then(|v| v.parse().ok());
    ProptestConfig {
        cases: from_env("LMANIM_REUSE_CASES").map_or(in_ci, |cases: u64| cases as u32),
        rng_seed: RngSeed::Fixed(from_env("LMANIM_REUSE_SEED").unwrap_or(32)),
        max_shrink_iters: 200,
        ..ProptestConfig::default()
    }
}

proptest! {
    #![proptest_config(config(24))]

    #[test]
    fn every_frame_equals_its_cold_render_on_the_cpu(case in case()) {
        let mut backend = Backend::new(BackendKind::Cpu, Some(2)).unwrap();
        let settings = case.settings(BackendKind::Cpu);
        let fault = reuse_fault(&case.scene(), &settings, case.frames, case.split, &mut backend);
        prop_assert!(fault.is_none(), "{}", fault.unwrap_or_default());
    }
}

/// The street of issue 32 as it was reported: a ground, fifty buildings
/// along a street, four point lights of different intensities without a
/// lamp radius, four cars driven along the street by one clip so that a
/// car's shadow crosses a far facade.
fn issue_32_street() -> SceneDesc {
    let mut scene = empty_scene();
    let grey = add_material(&mut scene, lambert(Vec3::splat(0.6)));
    add_quads(&mut scene, &[floor_quad(0.0, 70.0)], 8, grey);
    for i in 0..25 {
        let x = -60.0 + 5.0 * i as f32;
        let height = 3.0 + (i * 7 % 5) as f32;
        for side in [-1.0, 1.0] {
            let half = Vec3::new(2.0, height, 3.0);
            add_box(&mut scene, Vec3::new(x, 0.0, side * 12.0), half, grey);
        }
    }
    let mut channels = Vec::new();
    for (car, (lane, start)) in [(-3.0, -40.0), (3.0, 30.0), (-5.0, -10.0), (5.0, 0.0)]
        .into_iter()
        .enumerate()
    {
        let from = Vec3::new(start, 0.0, lane);
        let to = from + Vec3::new(if car % 2 == 0 { 30.0 } else { -30.0 }, 0.0, 0.0);
        let node = add_box(&mut scene, from, Vec3::new(2.0, 0.75, 0.9), grey);
        channels.push(linear_translation(node, from, to, 1.0));
        scene.nodes[node].animated = true;
    }
    for (i, x) in [-30.0f64, -10.0, 10.0, 30.0].into_iter().enumerate() {
        let at = DMat4::from_translation(DVec3::new(x, 6.0, if i % 2 == 0 { -7.0 } else { 7.0 }));
        add_light(&mut scene, LightKind::Point, 800.0 + 400.0 * i as f32, at);
    }
    add_camera(
        &mut scene,
        perspective(0.8),
        look_at(DVec3::new(-45.0, 8.0, 0.0), DVec3::new(0.0, 2.0, 0.0)),
    );
    add_clip(&mut scene, "traffic", channels);
    scene
}

#[test]
fn the_street_of_issue_32_renders_every_frame_as_cold() {
    let scene = issue_32_street();
    let mut backend = Backend::new(BackendKind::Cpu, Some(2)).unwrap();
    for method in [Method::Lmm1, Method::Lmm] {
        let mut settings = settings(120, 68);
        settings.method = method;
        settings.fps = 14.0;
        settings.cache_dir = None;
        let shot: Vec<u32> = (0..14).collect();
        let in_sequence = run(&scene, &settings, &shot, None, &mut backend);
        for frame in [1, 5, 9, 13] {
            let cold = run(&scene, &settings, &[frame], None, &mut backend).remove(0);
            assert!(
                in_sequence[frame as usize] == cold,
                "{method}: frame {frame} in the sequence differs from it rendered alone"
            );
        }
    }
}

/// The same property on the GPU backend, over fewer cases: each case
/// renders some thirty frames, and lavapipe is slow.
#[test]
fn every_frame_equals_its_cold_render_on_the_gpu() {
    let Some((gpu, _)) = common::gpu::backend_to_compare() else {
        return;
    };
    // The runner takes a shared closure; one case renders at a time.
    let gpu = std::cell::RefCell::new(gpu);
    let mut runner = TestRunner::new(ProptestConfig {
        failure_persistence: None,
        ..config(3)
    });
    let result = runner.run(&case(), |case| {
        let settings = case.settings(BackendKind::Gpu);
        let fault = reuse_fault(
            &case.scene(),
            &settings,
            case.frames,
            case.split,
            &mut gpu.borrow_mut(),
        );
        prop_assert!(fault.is_none(), "{}", fault.unwrap_or_default());
        Ok(())
    });
    if let Err(failure) = result {
        panic!("{failure}");
    }
}

/// The backend-parity invariant over the same generated shots: where the
/// adapter rounds as the CPU does, every frame of a shot rendered on the
/// GPU is the CPU's, bit for bit.
#[test]
fn every_frame_on_the_gpu_is_the_cpus() {
    let Some((gpu, exact)) = common::gpu::backend_to_compare() else {
        return;
    };
    if !exact {
        eprintln!("skipped: the adapter does not round as the CPU does");
        return;
    }
    let gpu = std::cell::RefCell::new(gpu);
    let mut cpu = Backend::new(BackendKind::Cpu, Some(2)).unwrap();
    let cpu = std::cell::RefCell::new(&mut cpu);
    let mut runner = TestRunner::new(ProptestConfig {
        failure_persistence: None,
        ..config(3)
    });
    let result = runner.run(&case(), |case| {
        let scene = case.scene();
        let shot: Vec<u32> = (0..case.frames).collect();
        let on_cpu = run(
            &scene,
            &case.settings(BackendKind::Cpu),
            &shot,
            None,
            &mut cpu.borrow_mut(),
        );
        let on_gpu = run(
            &scene,
            &case.settings(BackendKind::Gpu),
            &shot,
            None,
            &mut gpu.borrow_mut(),
        );
        for (frame, (cpu, gpu)) in on_cpu.iter().zip(&on_gpu).enumerate() {
            prop_assert!(
                cpu == gpu,
                "frame {frame}: the GPU's differs from the CPU's"
            );
        }
        Ok(())
    });
    if let Err(failure) = result {
        panic!("{failure}");
    }
}
