//! The effect plan (`src/plan/`) and `--method auto`: what the plan skips
//! costs nothing and changes no bit, and auto reproduces the forced
//! methods light by light.

mod common;

use glam::{DMat4, DVec3, Vec3};
use lmanim::anim::pose::ClipSelection;
use lmanim::backend::Backend;
use lmanim::output::{Image, RenderedFrame};
use lmanim::plan::{Plan, Shadows};
use lmanim::scene::{LightKind, Material, SceneDesc};
use lmanim::schedule::{FrameSet, Timeline};
use lmanim::sequence::Sequence;
use lmanim::settings::{Aov, BackendKind, Method, Settings};
use lmanim::stats::FrameStats;

use common::*;

fn camera_over(scene: &mut SceneDesc) {
    add_camera(
        scene,
        perspective(0.9),
        look_at(DVec3::new(-3.0, 5.0, 6.0), DVec3::ZERO),
    );
}

/// A floor with a box on it, a hard light and a soft lamp.
fn yard() -> SceneDesc {
    let mut scene = empty_scene();
    let grey = add_material(&mut scene, lambert(Vec3::splat(0.6)));
    add_quads(&mut scene, &[floor_quad(0.0, 3.0)], 6, grey);
    add_quads(
        &mut scene,
        &box_quads(Vec3::new(0.0, 0.5, 0.0), 0.5),
        2,
        grey,
    );
    add_light(
        &mut scene,
        LightKind::Point,
        20.0,
        DMat4::from_translation(DVec3::new(2.0, 3.0, 1.0)),
    );
    add_lamp(&mut scene, 15.0, Vec3::new(-2.0, 2.5, -1.0), 0.3);
    scene.lights[0].name = Some("hard".into());
    scene.lights[1].name = Some("soft".into());
    camera_over(&mut scene);
    scene
}

/// `yard` with lights that reach nothing in view: no power, out of range
/// (under the floor), and a spot pointing away from everything.
fn yard_with_useless_lights() -> SceneDesc {
    let mut scene = yard();
    add_light(
        &mut scene,
        LightKind::Point,
        0.0,
        DMat4::from_translation(DVec3::new(0.0, 2.0, 0.0)),
    );
    add_light(
        &mut scene,
        LightKind::Point,
        50.0,
        DMat4::from_translation(DVec3::new(0.0, -1.0, 0.0)),
    );
    scene.lights[3].range = Some(0.5);
    let up = DMat4::from_translation(DVec3::new(0.0, 10.0, 0.0))
        * DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2);
    add_light(
        &mut scene,
        LightKind::Spot {
            inner_cone: 0.2,
            outer_cone: 0.3,
        },
        50.0,
        up,
    );
    scene
}

fn base_settings(method: Method) -> Settings {
    let mut settings = settings(48, 32);
    settings.method = method;
    settings.lightmesh.h = Some(0.1);
    settings.cache_dir = None;
    settings
}

/// Renders `frames` of a planned sequence.
fn render_frames(
    mut sequence: Sequence,
    settings: &Settings,
    frames: &[u32],
) -> Vec<(RenderedFrame, FrameStats)> {
    let mut backend = Backend::new(settings.backend, Some(2)).expect("backend");
    let timeline = Timeline { fps: settings.fps };
    (frames.iter())
        .map(|&frame| {
            let mut stats = FrameStats::default();
            let placed = sequence
                .advance(timeline.time_of(frame), settings, &mut stats)
                .unwrap();
            let image = sequence
                .render_frame(&mut backend, &placed, settings, &mut stats)
                .unwrap();
            (image, stats)
        })
        .collect()
}

fn render_one(scene: SceneDesc, settings: &Settings) -> (Image, FrameStats) {
    let sequence = planned(&scene, settings, "0");
    let (frame, stats) = render_frames(sequence, settings, &[0]).remove(0);
    (frame.image, stats)
}

fn classes(scene: &SceneDesc, settings: &Settings) -> Vec<Shadows> {
    let frames = FrameSet::parse("0").unwrap();
    let plan = Plan::make(scene, settings, ClipSelection::All, &frames).unwrap();
    plan.lights.iter().map(|light| light.shadows).collect()
}

#[test]
fn lights_that_reach_nothing_in_view_cost_nothing_and_change_no_bit() {
    for method in [Method::Whitted, Method::Lmm, Method::Lmm1, Method::Auto] {
        let settings = base_settings(method);
        let scene = yard_with_useless_lights();
        assert_eq!(
            classes(&scene, &settings),
            [
                Shadows::Hard,
                Shadows::Soft,
                Shadows::None,
                Shadows::None,
                Shadows::None
            ],
            "{method}"
        );
        let (with, stats) = render_one(scene, &settings);
        let (without, _) = render_one(yard(), &settings);
        assert_eq!(
            with.pixels, without.pixels,
            "{method}: the image keeps its bits"
        );
        assert_eq!(stats.shadow_classes.none.shadow_rays, 0, "{method}");
        assert_eq!(stats.shadow_classes.none.mask_bits, 0, "{method}");
        let spent = stats.shadow_classes.hard.shadow_rays
            + stats.shadow_classes.soft.shadow_rays
            + stats.shadow_classes.soft.mask_bits
            + stats.shadow_classes.hard.mask_bits;
        assert!(spent > 0, "{method}: the other lights still cost something");
    }
}

#[test]
fn a_light_behind_every_visible_surface_is_none() {
    let mut scene = empty_scene();
    let grey = add_material(&mut scene, lambert(Vec3::splat(0.6)));
    add_quads(&mut scene, &[floor_quad(0.0, 3.0)], 4, grey);
    add_light(
        &mut scene,
        LightKind::Point,
        10.0,
        DMat4::from_translation(DVec3::new(0.0, 2.0, 0.0)),
    );
    add_light(
        &mut scene,
        LightKind::Point,
        10.0,
        DMat4::from_translation(DVec3::new(1.0, -2.0, 0.0)),
    );
    camera_over(&mut scene);
    let settings = base_settings(Method::Whitted);
    assert_eq!(
        classes(&scene, &settings),
        [Shadows::Unshadowed, Shadows::None]
    );
    let (with, _) = render_one(scene.clone(), &settings);
    for node in &mut scene.nodes {
        node.light = node.light.filter(|&light| light != 1);
    }
    let (without, _) = render_one(scene, &settings);
    assert_eq!(with.pixels, without.pixels);
}

#[test]
fn an_unshadowed_light_traces_no_ray_and_matches_whitted() {
    let mut scene = empty_scene();
    let grey = add_material(&mut scene, lambert(Vec3::splat(0.6)));
    add_quads(&mut scene, &[floor_quad(0.0, 3.0)], 4, grey);
    add_light(
        &mut scene,
        LightKind::Point,
        10.0,
        DMat4::from_translation(DVec3::new(0.5, 2.0, 0.0)),
    );
    camera_over(&mut scene);
    for method in [Method::Auto, Method::Whitted] {
        let settings = base_settings(method);
        assert_eq!(classes(&scene, &settings), [Shadows::Unshadowed]);
        let (planned_image, stats) = render_one(scene.clone(), &settings);
        assert_eq!(stats.rays.shadow, 0, "{method}");
        // Without a plan every segment is traced.
        let reference = base_settings(Method::Whitted);
        let (traced, traced_stats) = render_with_stats(scene.clone(), &reference);
        assert!(traced_stats.rays.shadow > 0);
        assert_eq!(planned_image.pixels, traced.pixels, "{method}");
    }
}

#[test]
fn secondary_rays_only_where_a_mirror_is_seen() {
    let settings = base_settings(Method::Auto);
    let (_, stats) = render_one(yard(), &settings);
    assert_eq!(stats.rays.secondary, 0);
    let frames = FrameSet::parse("0").unwrap();
    let plan = Plan::make(&yard(), &settings, ClipSelection::All, &frames).unwrap();
    assert!(plan.materials.iter().all(|m| !m.spawns_secondary));

    let mut scene = yard();
    let mirror = add_material(
        &mut scene,
        Material {
            roughness: 0.0,
            metallic: 1.0,
            ..Material::default()
        },
    );
    let beside_the_box = floor_quad(0.01, 0.4).map(|corner| corner + Vec3::new(1.5, 0.0, 1.5));
    add_quads(&mut scene, &[beside_the_box], 1, mirror);
    let plan = Plan::make(&scene, &settings, ClipSelection::All, &frames).unwrap();
    let spawning: Vec<usize> = (plan.materials.iter())
        .filter(|m| m.spawns_secondary)
        .map(|m| m.index)
        .collect();
    assert_eq!(spawning, [mirror as usize]);
    let (_, stats) = render_one(scene, &settings);
    let pixels = u64::from(settings.width * settings.height);
    assert!(stats.rays.secondary > 0);
    assert!(
        stats.rays.secondary < pixels / 8,
        "only the mirror's pixels: {}",
        stats.rays.secondary
    );
}

/// `yard` with a box that drives off at t = 2 s.
fn yard_with_a_late_car() -> SceneDesc {
    let mut scene = yard();
    let grey = add_material(&mut scene, lambert(Vec3::splat(0.4)));
    let car = add_quads(&mut scene, &box_quads(Vec3::ZERO, 0.3), 1, grey);
    scene.nodes[car].local = DMat4::from_translation(DVec3::new(1.5, 0.3, 1.0));
    let mut channel = linear_translation(
        car,
        Vec3::new(1.5, 0.3, 1.0),
        Vec3::new(-1.5, 0.3, 1.0),
        1.0,
    );
    channel.sampler.times = vec![2.0, 3.0];
    add_clip(&mut scene, "drive", vec![channel]);
    scene.nodes[car].animated = true;
    scene
}

/// A chunk of a shot whose frames show the car parked still plans it
/// dynamic, as the whole shot does: which objects are static follows the
/// clips, not the frames, so both runs trace it alike and share one disk
/// cache file.
#[test]
fn an_object_animated_outside_the_planned_frames_is_dynamic_and_shares_the_cache() {
    let cache = tempfile::tempdir().unwrap();
    let mut settings = base_settings(Method::Lmm);
    settings.cache_dir = Some(cache.path().display().to_string());
    let plan_over = |frames: &str| {
        let frames = FrameSet::parse(frames).unwrap();
        Plan::make(
            &yard_with_a_late_car(),
            &settings,
            ClipSelection::All,
            &frames,
        )
        .unwrap()
    };
    let chunk = plan_over("0..4");
    let car = chunk.objects.last().unwrap();
    assert!(car.dynamic && car.moves_in.is_empty() && !car.deforms);
    assert!(lmanim::plan::report::text(&chunk).contains("animated, still in the planned frames"));
    let whole = plan_over("0..96");
    assert!(whole.objects.last().unwrap().dynamic);
    assert_eq!(whole.objects.last().unwrap().moves_in, ["49..73"]);
    assert_eq!(chunk.dynamic_nodes(), whole.dynamic_nodes());
    let files = || {
        std::fs::read_dir(cache.path())
            .unwrap()
            .filter(|e| {
                e.as_ref()
                    .unwrap()
                    .path()
                    .extension()
                    .is_some_and(|x| x == "lmcache")
            })
            .count()
    };
    let mut sequence = planned(&yard_with_a_late_car(), &settings, "0..4");
    sequence.set_cache_dir(Some(cache.path().to_owned()));
    render_frames(sequence, &settings, &[0]).remove(0);
    assert_eq!(files(), 0, "saved at the end of a run only");

    let mut backend = Backend::new(BackendKind::Cpu, Some(2)).unwrap();
    for frames in ["0..4", "0..96"] {
        let mut sequence = planned(&yard_with_a_late_car(), &settings, frames);
        sequence.set_cache_dir(Some(cache.path().to_owned()));
        let placed = sequence
            .advance(0.0, &settings, &mut FrameStats::default())
            .unwrap();
        sequence
            .render(&mut backend, &placed, &settings, &mut FrameStats::default())
            .unwrap();
        sequence.save_cache().unwrap();
        assert_eq!(files(), 1, "planned over {frames}: one static set, one key");
    }
}

#[test]
fn a_chunk_that_shows_the_object_still_renders_the_bits_of_the_whole_shot() {
    for method in [Method::Whitted, Method::Lmm, Method::Lmm1] {
        let settings = base_settings(method);
        let frames = [0, 1, 2, 3];
        let in_chunk = render_frames(
            planned(&yard_with_a_late_car(), &settings, "0..4"),
            &settings,
            &frames,
        );
        let in_shot = render_frames(
            planned(&yard_with_a_late_car(), &settings, "0..96"),
            &settings,
            &frames,
        );
        for (frame, ((a, _), (b, _))) in frames.iter().zip(in_chunk.iter().zip(&in_shot)) {
            assert!(a.image == b.image, "{method}, frame {frame}");
        }
    }
}

#[test]
fn auto_is_whitted_for_the_hard_light_and_lmm1_for_the_soft_one() {
    let layers = |method| {
        let mut settings = base_settings(method);
        settings.aovs = vec![Aov::Light];
        let sequence = planned(&yard(), &settings, "0");
        let (frame, stats) = render_frames(sequence, &settings, &[0]).remove(0);
        let layer = |name: &str| {
            (frame.aovs.iter())
                .find(|l| l.channels[0] == name)
                .unwrap_or_else(|| panic!("{name}"))
                .values
                .clone()
        };
        (layer("light.hard.R"), layer("light.soft.R"), stats)
    };
    let (auto_hard, auto_soft, auto) = layers(Method::Auto);
    let (whitted_hard, _, _) = layers(Method::Whitted);
    let (_, lmm1_soft, _) = layers(Method::Lmm1);
    assert_eq!(auto_hard, whitted_hard);
    assert_eq!(auto_soft, lmm1_soft);
    assert!(auto.shadow_classes.hard.shadow_rays > 0);
    assert_eq!(
        auto.shadow_classes.hard.mask_bits, 0,
        "hard lights use no mask"
    );
    assert!(auto.shadow_classes.soft.mask_bits > 0);
}

#[test]
fn plan_frames_outside_the_run_is_one_line_and_exit_2() {
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args([
            "plan",
            "animations/courtyard.gltf",
            "--frames",
            "0..10",
            "--plan-frames",
            "20..30",
        ])
        .output()
        .unwrap();
    assert_eq!(output.status.code(), Some(2));
    let stderr = String::from_utf8(output.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(stderr.contains("--plan-frames"), "{stderr}");
}

#[test]
fn plan_json_names_each_light_object_and_material() {
    let output = std::process::Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args([
            "plan",
            "animations/courtyard.gltf",
            "--frames",
            "0..48",
            "--json",
            "--method",
            "auto",
        ])
        .output()
        .unwrap();
    assert!(output.status.success());
    let json: serde_json::Value = serde_json::from_slice(&output.stdout).unwrap();
    let lights = json["lights"].as_array().unwrap();
    assert_eq!(lights.len(), 4);
    for light in lights {
        for key in ["index", "name", "shadows", "reason"] {
            assert!(light.get(key).is_some(), "{key}");
        }
    }
    let objects = json["objects"].as_array().unwrap();
    assert!(objects
        .iter()
        .any(|o| o["dynamic"] == true && o["moves_in"][0] == "1..48"));
    assert!(json["materials"]
        .as_array()
        .unwrap()
        .iter()
        .any(|m| m["spawns_secondary"] == true));
}

#[test]
fn the_gpu_follows_the_plan() {
    let Some((mut gpu, exact)) = common::gpu::backend_to_compare() else {
        return;
    };
    let small = |method| {
        let mut settings = base_settings(method);
        settings.width = 24;
        settings.height = 16;
        settings.aovs = vec![Aov::Light];
        settings
    };
    let on_gpu = |gpu: &mut Backend, scene: SceneDesc, settings: &Settings| {
        let mut sequence = planned(&scene, settings, "0");
        let mut stats = FrameStats::default();
        let placed = sequence.advance(0.0, settings, &mut stats).unwrap();
        let frame = (sequence.render_frame(gpu, &placed, settings, &mut stats)).unwrap();
        (frame, stats)
    };
    let on_cpu = |scene: SceneDesc, settings: &Settings| {
        render_frames(planned(&scene, settings, "0"), settings, &[0]).remove(0)
    };
    // Hard lights and lights that reach nothing: formula (1) alone.
    let mut hard_only = yard_with_useless_lights();
    hard_only.lights[1].radius = None;
    // A hard light and two soft lamps in one frame: formula (1) for the
    // first, then formula (2) for the others, summed in the CPU's order
    // (with two soft terms, adding the hard one last would round apart).
    let mut mixed = yard_with_useless_lights();
    add_lamp(&mut mixed, 9.0, Vec3::new(1.5, 2.0, -2.0), 0.2);
    for scene in [hard_only, mixed] {
        let settings = small(Method::Auto);
        let (cpu, cpu_stats) = on_cpu(scene.clone(), &settings);
        let (frame, stats) = on_gpu(&mut gpu, scene, &settings);
        // What each class cost, shadow rays and mask bits: the CPU's.
        assert_eq!(stats.shadow_classes, cpu_stats.shadow_classes);
        assert!(stats.shadow_classes.hard.shadow_rays > 0);
        assert_eq!(stats.shadow_classes.hard.mask_bits, 0);
        assert_eq!(stats.shadow_classes.none, Default::default());
        if exact {
            let differing = (frame.image.pixels.iter().zip(&cpu.image.pixels))
                .filter(|(gpu, cpu)| gpu != cpu)
                .count();
            assert_eq!(differing, 0, "pixels differing from the CPU's");
            assert_eq!(frame.aovs.len(), cpu.aovs.len());
            for (gpu_layer, cpu_layer) in frame.aovs.iter().zip(&cpu.aovs) {
                assert_eq!(gpu_layer.channels, cpu_layer.channels);
                let same = gpu_layer.values == cpu_layer.values;
                assert!(same, "{:?} differs from the CPU's", gpu_layer.channels);
            }
        }
    }
    // The mixed frame's hard light equals it under `whitted`, its soft
    // lamp equals it under `lmm1`, on the GPU too.
    let layer = |frame: &RenderedFrame, name: &str| {
        (frame.aovs.iter())
            .find(|l| l.channels[0] == name)
            .unwrap_or_else(|| panic!("{name}"))
            .values
            .clone()
    };
    let (auto, _) = on_gpu(&mut gpu, yard(), &small(Method::Auto));
    let (whitted, _) = on_gpu(&mut gpu, yard(), &small(Method::Whitted));
    let (lmm1, _) = on_gpu(&mut gpu, yard(), &small(Method::Lmm1));
    assert_eq!(
        layer(&auto, "light.hard.R"),
        layer(&whitted, "light.hard.R")
    );
    assert_eq!(layer(&auto, "light.soft.R"), layer(&lmm1, "light.soft.R"));
    assert_ne!(
        layer(&auto, "light.soft.R"),
        layer(&whitted, "light.soft.R")
    );
}
