//! What crosses between the CPU and the GPU in a frame (`--stats`'s `gpu`
//! object): counted where it crosses, so a frame's waits and bytes are
//! exact. A Whitted frame in one band waits once, at the band's end, for
//! its pixels and its counters together, mirrors or not: each next level's
//! length stays on the GPU, which dispatches the level's passes
//! indirectly and counts its rays with the film's counters. A light-mesh
//! frame waits once more per level, for the coverage flags and the points
//! the pool does not serve, which the demand on the CPU needs; their
//! fill is traced into the pool on the GPU, and its answers come back
//! with the next wait. Demand on the GPU (issue 33) is what removes the
//! coverage's wait.

mod common;

use common::*;
use glam::Vec3;

use lmanim::backend::gpu::enclosure::ProbeSite;
use lmanim::backend::gpu::traffic::GpuTraffic;

use lmanim::backend::Backend;
use lmanim::scene::SceneDesc;
use lmanim::sequence::Sequence;
use lmanim::settings::{BackendKind, Method, Settings};
use lmanim::stats::FrameStats;

const WIDTH: u32 = 48;
const HEIGHT: u32 = 32;
/// What a frame of one band reads back at its end: its pixels and the
/// film's seven counters (shading points, other rays, three classes of
/// shadow rays, secondary rays).
const BAND_BYTES: u64 = (WIDTH * HEIGHT) as u64 * 16 + 7 * 4;

/// A box on a floor under a lamp, seen from above, the camera dollying
/// in over `seconds` (it moves, so no frame is a copy, and it
/// invalidates no mask bit).
fn box_on_a_floor(seconds: f32) -> SceneDesc {
    let (mut scene, camera) = box_under_a_lamp();
    let dolly = linear_translation(
        camera,
        Vec3::new(0.0, 6.0, 6.0),
        Vec3::new(0.0, 5.0, 5.0),
        seconds,
    );
    scene.nodes[camera].animated = true;
    add_clip(&mut scene, "dolly", vec![dolly]);
    scene
}

/// Each of `times` of `scene` rendered in one sequence on `backend`, with
/// its stats (its `seconds` the frame's wall time).
fn frames_on(
    mut backend: Backend,
    scene: SceneDesc,
    settings: &Settings,
    times: &[f64],
) -> Vec<FrameStats> {
    let mut sequence = Sequence::new(scene, "box".into()).unwrap();
    (times.iter())
        .map(|&time| {
            let started = std::time::Instant::now();
            let mut stats = FrameStats::default();
            let placed = sequence.advance(time, settings, &mut stats).unwrap();
            sequence
                .render(&mut backend, &placed, settings, &mut stats)
                .unwrap();
            stats.seconds = started.elapsed().as_secs_f64();
            stats
        })
        .collect()
}

/// Each of `times` rendered in one sequence on the GPU, with its stats.
fn frames_on_the_gpu(settings: &Settings, times: &[f64]) -> Option<Vec<FrameStats>> {
    let (gpu, _) = common::gpu::backend_to_compare()?;
    Some(frames_on(gpu, box_on_a_floor(1.0), settings, times))
}

/// The GPU backend with LMM1's enclosure probes on the CPU, as a
/// software adapter runs them, so that a test of what goes up holds on
/// any adapter: there every brick the pool takes new goes up with its
/// nodes' flags. (Where the probes run on the GPU, the probe pass writes
/// the flags into the slot itself, and a new brick holding nothing else
/// yet goes up as nothing.)
fn backend_probing_on_the_cpu() -> Option<Backend> {
    let mut gpu = common::gpu::backend()?;
    gpu.set_probe_site(ProbeSite::Cpu);
    Some(Backend::Gpu(Box::new(gpu)))
}

fn settings_for(method: Method) -> Settings {
    let mut settings = settings(WIDTH, HEIGHT);
    settings.method = method;
    settings.lightmesh.h = Some(0.1);
    settings
}

fn traffic(stats: &FrameStats) -> GpuTraffic {
    stats
        .gpu
        .as_ref()
        .expect("the GPU backend reports its traffic")
        .traffic
}

#[test]
fn a_whitted_frame_waits_once_for_its_pixels_and_its_counters() {
    let Some(frames) = frames_on_the_gpu(&settings_for(Method::Whitted), &[0.0, 0.5]) else {
        return;
    };
    for stats in &frames {
        let gpu = traffic(stats);
        assert_eq!(gpu.waits, 1, "{gpu:?}");
        assert_eq!(gpu.bytes_down, BAND_BYTES, "{gpu:?}");
        assert!(gpu.bytes_up > 0, "the frame's uniforms at least");
    }
    // The world went up with the first frame; the second sends only what
    // changed (the camera's rays are made on the GPU).
    let up = |i: usize| traffic(&frames[i]).bytes_up;
    assert!(up(1) < up(0), "first {} bytes up, then {}", up(0), up(1));
}

/// Every surface of the box and the floor a mirror: five levels of
/// mirror rays, each dispatched from the length the compaction wrote,
/// and still one wait. The secondary rays the film's counters bring back
/// are the CPU's count.
#[test]
fn mirror_levels_wait_for_no_length() {
    let Some(gpu) = common::gpu::backend() else {
        return;
    };
    let mut scene = box_on_a_floor(1.0);
    for material in &mut scene.materials {
        material.metallic = 1.0;
        material.roughness = 0.0;
    }
    let settings = settings_for(Method::Whitted);
    let gpu = Backend::Gpu(Box::new(gpu));
    let [on_gpu] = &frames_on(gpu, scene.clone(), &settings, &[0.0])[..] else {
        unreachable!("one frame")
    };
    let cpu = Backend::new(BackendKind::Cpu, Some(2)).unwrap();
    let [on_cpu] = &frames_on(cpu, scene, &settings, &[0.0])[..] else {
        unreachable!("one frame")
    };
    let gpu = traffic(on_gpu);
    assert_eq!(gpu.waits, 1, "{gpu:?}");
    assert_eq!(gpu.bytes_down, BAND_BYTES, "{gpu:?}");
    assert!(on_cpu.rays.secondary > 0);
    assert_eq!(on_gpu.rays, on_cpu.rays);
}

/// The box under its lamp, the camera still, and a tile far below the
/// floor sliding over `seconds`: frames after the first are steady, every
/// point served by masks the pool already holds (no point sees the tile,
/// and no segment from the floor's nodes to the lights above passes
/// near it).
fn a_tile_sliding_far_below(seconds: f32) -> SceneDesc {
    let (mut scene, _) = box_under_a_lamp();
    let grey = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    let tile = add_quads(&mut scene, &[floor_quad(-50.0, 1.0)], 1, grey);
    let slide = linear_translation(tile, Vec3::ZERO, Vec3::X, seconds);
    scene.nodes[tile].animated = true;
    add_clip(&mut scene, "slide", vec![slide]);
    scene
}

#[test]
fn a_light_mesh_frame_waits_for_its_coverage_flags_and_its_band() {
    let settings = settings_for(Method::Lmm1);
    let Some(gpu) = backend_probing_on_the_cpu() else {
        return;
    };
    let dolly = frames_on(gpu, box_on_a_floor(1.0), &settings, &[0.0, 0.5]);
    let gpu = backend_probing_on_the_cpu().expect("a GPU, as above");
    let still = frames_on(gpu, a_tile_sliding_far_below(1.0), &settings, &[0.0, 0.5]);
    let [cold, moved, steady] = [&dolly[0], &dolly[1], &still[1]].map(traffic);
    let lightmesh = |stats: &FrameStats| stats.lightmesh.unwrap();
    eprintln!("cold {cold:?}, moved {moved:?}, steady {steady:?}");
    for frame in [&dolly[0], &dolly[1], &still[1]] {
        eprintln!("light mesh: {:?}", frame.lightmesh);
    }
    // The CPU owns the masks. The frame's one level (no mirrors) waits
    // for its points' coverage flags, and the copies of the points the
    // pool does not serve come back with them where the pass had room
    // (as many as the last pass left, and some). Where the pool does not
    // serve every point (the cold frame, and the camera's new view), the
    // GPU traces the fill's segments into the pool itself, and their
    // answers come back with the band's wait: no wait of their own. The
    // cold frame leaves more points than there was room for, and gathers
    // them after one more wait. Then the band's one wait brings the
    // pixels, the film's counters, formula (2)'s counters and the fill's
    // answers back together.
    assert_eq!(cold.waits, 3, "{cold:?}");
    assert_eq!(moved.waits, 2, "{moved:?}");
    assert_eq!(steady.waits, 2, "{steady:?}");
    assert!(lightmesh(&dolly[0]).points_demanded > 0);
    assert!(lightmesh(&dolly[1]).points_demanded > 0);
    let steady_work = lightmesh(&still[1]);
    assert_eq!(
        (steady_work.points_demanded, steady_work.bricks_uploaded),
        (0, 0)
    );
    // The fill's segments all went to the GPU, and only where points
    // were not served: each answers the static test, the dynamic one or
    // both, and `fill_segments` counts each test. The pool took the cold
    // frame's bricks as new ones.
    for (stats, gpu) in [(&dolly[0], cold), (&dolly[1], moved), (&still[1], steady)] {
        let tests = lightmesh(stats).fill_segments;
        let traced = gpu.segments_traced;
        assert!(
            traced <= tests && tests <= 2 * traced,
            "{gpu:?}, {tests} tests"
        );
    }
    assert!(cold.segments_traced > 0, "{cold:?}");
    assert_eq!(steady.segments_traced, 0, "{steady:?}");
    let cold_work = lightmesh(&dolly[0]);
    assert!(cold_work.bricks_inserted > 0);
    assert_eq!(cold_work.bricks_inserted, cold_work.bricks_uploaded);
    assert_eq!(steady_work.bricks_inserted, 0);
    // A brick goes up as the words that differ from its slot's
    // (`tests/gpu_backend.rs` checks that the slots then hold the
    // store's bricks): the steady frame sends its uniforms, less than one
    // brick.
    use lmanim::backend::gpu::mask_pool::MaskPool;
    let brick_bytes = MaskPool::slot_bytes(MaskPool::light_words(2)) as u64;
    assert!(steady.bytes_up < brick_bytes, "{steady:?}");
}

/// The showcase fly-through, its cars driving: after the first frame, a
/// frame waits twice (its coverage, its band), though its new view and
/// the cars leave bits to fill.
#[test]
fn a_city_fly_through_frame_waits_twice() {
    let Some((gpu, _)) = common::gpu::backend_to_compare() else {
        return;
    };
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/city.gltf");
    let city = lmanim::import::load(&path).expect("import animations/city.gltf");
    let mut settings = settings(160, 90);
    settings.method = Method::Lmm1;
    let frames = frames_on(gpu, city, &settings, &[0.0, 1.0 / 24.0, 2.0 / 24.0]);
    for stats in &frames[1..] {
        let gpu = traffic(stats);
        let work = stats.lightmesh.expect("a light-mesh frame");
        assert!(
            gpu.segments_traced > 0 && work.points_demanded > 0,
            "{gpu:?}"
        );
        assert_eq!(gpu.waits, 2, "{gpu:?}");
    }
}

/// Where the adapter has timestamp queries (lavapipe has), a frame's
/// stats say how long each of its passes ran on the GPU: a Whitted
/// frame's camera rays, closest hits, shading points, direct light and
/// film; a cold light-mesh frame's coverage, fill and formula (2) in
/// place of the direct light. Each pass ran within its frame.
#[test]
fn a_frame_says_how_long_its_passes_ran_on_the_gpu() {
    let Some(gpu) = common::gpu::backend() else {
        return;
    };
    assert!(
        gpu.times_passes() || !gpu.is_software(),
        "the software adapter here, lavapipe, has timestamp queries"
    );
    if !gpu.times_passes() {
        eprintln!("this adapter has no timestamp queries: no pass times to check");
        return;
    }
    let gpu = Backend::Gpu(Box::new(gpu));
    let whitted = settings_for(Method::Whitted);
    let [whitted_frame] = &frames_on(gpu, box_on_a_floor(1.0), &whitted, &[0.0])[..] else {
        unreachable!("one frame")
    };
    let (gpu, _) = common::gpu::backend_to_compare().expect("a GPU, as above");
    let lmm1 = settings_for(Method::Lmm1);
    let [lmm1_frame] = &frames_on(gpu, box_on_a_floor(1.0), &lmm1, &[0.0])[..] else {
        unreachable!("one frame")
    };
    let common = [
        "camera_rays",
        "closest_hit",
        "surface",
        "accumulate",
        "resolve",
    ];
    let light_mesh = ["light_mesh_coverage", "fill_segments", "light_mesh"];
    for (stats, own) in [
        (whitted_frame, &["direct_light"][..]),
        (lmm1_frame, &light_mesh[..]),
    ] {
        let passes = &stats.gpu.as_ref().expect("GPU stats").passes;
        for name in common.iter().chain(own) {
            let seconds = passes.seconds.get(name).copied().unwrap_or_default();
            assert!(
                seconds > 0.0 && seconds <= stats.seconds,
                "{name}: {seconds} s in a frame of {} s ({passes:?})",
                stats.seconds
            );
        }
        assert_eq!(passes.untimed, 0, "{passes:?}");
    }
    let times = |stats: &FrameStats| stats.gpu.as_ref().unwrap().passes.seconds.clone();
    assert!(!times(whitted_frame).contains_key("light_mesh"));
    assert!(!times(lmm1_frame).contains_key("direct_light"));
}
