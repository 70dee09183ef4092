//! What crosses between the CPU and the GPU in a frame (`--stats`'s `gpu`
//! object): counted where it crosses, so a frame's waits and bytes are
//! exact. A Whitted frame in one band without mirrors waits three times
//! (for the length of the next level of rays, none here; the band's
//! pixels; its counters) and reads back exactly those; a light-mesh frame waits more, per level, which is what
//! the GPU-resident light mesh (issue 33) must bring down to two.

mod common;

use common::*;
use glam::Vec3;

use lmanim::scene::SceneDesc;
use lmanim::sequence::Sequence;
use lmanim::settings::{Method, Settings};
use lmanim::stats::FrameStats;

const WIDTH: u32 = 48;
const HEIGHT: u32 = 32;

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
    scene
        .animations
        .push(lmanim::scene::animation::AnimationClip {
            name: Some("dolly".into()),
            channels: vec![dolly],
        });
    scene
}

/// Each of `times` rendered in one sequence on the GPU, with its stats.
fn frames_on_the_gpu(settings: &Settings, times: &[f64]) -> Option<Vec<FrameStats>> {
    let (mut gpu, _) = common::gpu::backend_to_compare()?;
    let mut sequence = Sequence::new(box_on_a_floor(1.0), "box".into()).unwrap();
    let frames = (times.iter())
        .map(|&time| {
            let mut stats = FrameStats::default();
            let placed = sequence.advance(time, settings, &mut stats).unwrap();
            sequence
                .render(&mut gpu, &placed, settings, &mut stats)
                .unwrap();
            stats
        })
        .collect();
    Some(frames)
}

fn settings_for(method: Method) -> Settings {
    let mut settings = settings(WIDTH, HEIGHT);
    settings.method = method;
    settings.lightmesh.h = Some(0.1);
    settings
}

#[test]
fn a_whitted_frame_waits_for_its_level_its_pixels_and_its_counters() {
    let Some(frames) = frames_on_the_gpu(&settings_for(Method::Whitted), &[0.0, 0.5]) else {
        return;
    };
    let pixels = u64::from(WIDTH * HEIGHT) * 16;
    let (counters, next_level_length) = (6 * 4, 4);
    for stats in &frames {
        let gpu = stats
            .gpu
            .as_ref()
            .expect("the GPU backend reports its traffic")
            .traffic;
        assert_eq!(gpu.waits, 3, "{gpu:?}");
        assert_eq!(
            gpu.bytes_down,
            next_level_length + pixels + counters,
            "{gpu:?}"
        );
        assert!(gpu.bytes_up > 0, "the frame's uniforms at least");
    }
    // The world went up with the first frame; the second sends only what
    // changed (the camera's rays are made on the GPU).
    let traffic = |i: usize| frames[i].gpu.as_ref().unwrap().traffic;
    let up = |i: usize| traffic(i).bytes_up;
    assert!(up(1) < up(0), "first {} bytes up, then {}", up(0), up(1));
}

#[test]
fn a_light_mesh_frame_counts_its_waits_and_its_mask_traffic() {
    let Some(frames) = frames_on_the_gpu(&settings_for(Method::Lmm1), &[0.0, 0.5]) else {
        return;
    };
    let traffic = |i: usize| frames[i].gpu.as_ref().unwrap().traffic;
    let (cold, steady) = (traffic(0), traffic(1));
    let bricks = |stats: &FrameStats| stats.lightmesh.unwrap().bricks_uploaded;
    eprintln!(
        "cold {cold:?}, {} bricks up; steady {steady:?}, {} bricks up",
        bricks(&frames[0]),
        bricks(&frames[1])
    );
    // Today the CPU owns the masks: each level waits for the points'
    // coverage, their demand and fill, and formula (2)'s counters, beside
    // the film's two.
    assert!(cold.waits > 2, "{cold:?}");
    assert!(steady.waits >= 2, "{steady:?}");
    assert!(bricks(&frames[0]) > 0);
    use lmanim::backend::gpu::mask_pool::MaskPool;
    let brick_bytes = MaskPool::slot_bytes(MaskPool::light_words(2)) as u64;
    assert!(
        cold.bytes_up >= bricks(&frames[0]) * brick_bytes,
        "{cold:?}"
    );
}
