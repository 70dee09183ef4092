//! Frames rendered in a sequence, reusing the light mesh's masks, equal the
//! same frames rendered cold, bit for bit — with a truck passing between a
//! lamp and a facade more than 15 m from it, a moving light and a moving
//! camera, or a sheet that a morph target bends on one side only.
//! Camera-only animation recomputes no bit; a still sequence copies its
//! frames. Animated light colours and intensities, material factors
//! and fields of view (KHR_animation_pointer) re-render every frame but
//! invalidate and recompute no bit.

mod common;

use common::*;
use glam::{DMat4, DVec3, Vec3};

use lmanim::backend::Backend;
use lmanim::lightmesh::kernel::Kernel;
use lmanim::lightmesh::penumbra::Penumbra;
use lmanim::output::Image;
use lmanim::scene::animation::{Channel, Interpolation, Sampler};
use lmanim::scene::pose::dynamic_nodes;
use lmanim::scene::{
    CameraProperty, LightKind, LightProperty, MaterialProperty, SceneDesc, Target,
};
use lmanim::sequence::Sequence;
use lmanim::settings::{BackendKind, Method, Settings};
use lmanim::stats::FrameStats;

const TIMES: [f64; 4] = [0.0, 1.0, 2.0, 3.0];

/// A street with a facade at x = 30, a lamp at the origin, a second lamp
/// and a camera looking at the facade; what moves is up to `animate`.
fn street(truck_moves: bool, light_moves: bool, camera_moves: bool) -> SceneDesc {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.6)));
    let facade = [
        Vec3::new(30.0, 0.0, -10.0),
        Vec3::new(30.0, 0.0, 10.0),
        Vec3::new(30.0, 12.0, 10.0),
        Vec3::new(30.0, 12.0, -10.0),
    ];
    add_quads(&mut scene, &[floor_quad(0.0, 40.0), facade], 8, m);
    // A truck 2 × 3.5 × 2 m: a 2 m box standing on its node, stretched.
    let truck = add_quads(&mut scene, &box_quads(Vec3::Y, 1.0), 1, m);
    scene.nodes[truck].local = DMat4::from_scale(DVec3::new(1.0, 1.75, 1.0));
    add_light(
        &mut scene,
        LightKind::Point,
        400.0,
        DMat4::from_translation(DVec3::new(0.0, 5.0, 0.0)),
    );
    let second = add_light(
        &mut scene,
        LightKind::Point,
        200.0,
        DMat4::from_translation(DVec3::new(25.0, 6.0, 9.0)),
    );
    let camera = add_camera(
        &mut scene,
        perspective(0.9),
        look_at(DVec3::new(18.0, 4.0, 14.0), DVec3::new(30.0, 2.0, 0.0)),
    );
    for light in &mut scene.lights {
        light.radius = Some(0.3);
    }
    let mut channels = Vec::new();
    if truck_moves {
        channels.push(linear_translation(
            truck,
            Vec3::new(-30.0, 0.0, 0.0),
            Vec3::new(11.0, 0.0, 0.0),
            3.0,
        ));
        scene.nodes[truck].animated = true;
    }
    if light_moves {
        channels.push(linear_translation(
            second,
            Vec3::new(25.0, 6.0, 9.0),
            Vec3::new(22.0, 6.0, -6.0),
            3.0,
        ));
        scene.nodes[second].animated = true;
    }
    if camera_moves {
        channels.push(linear_translation(
            camera,
            Vec3::new(18.0, 4.0, 14.0),
            Vec3::new(14.0, 5.0, 10.0),
            3.0,
        ));
        scene.nodes[camera].animated = true;
    }
    if !channels.is_empty() {
        add_clip(&mut scene, "street", channels);
    }
    scene
}

fn settings_for(method: Method) -> Settings {
    let mut settings = settings(48, 32);
    settings.method = method;
    settings.lightmesh.h = Some(0.25);
    settings
}

/// Every time rendered by one sequence on `backend`, with its stats.
fn rendered_in_sequence(
    scene: &SceneDesc,
    settings: &Settings,
    backend: &mut Backend,
) -> Vec<(Image, FrameStats)> {
    let mut sequence = Sequence::new(scene.clone(), "street".into()).unwrap();
    TIMES
        .iter()
        .map(|&time| {
            let mut stats = FrameStats::default();
            let placed = sequence.advance(time, settings, &mut stats).unwrap();
            let image = sequence
                .render(backend, &placed, settings, &mut stats)
                .unwrap();
            (image, stats)
        })
        .collect()
}

/// `time` rendered by a sequence of its own (a light mesh of its own, so
/// no mask is reused) on `backend`.
fn rendered_cold(
    scene: &SceneDesc,
    settings: &Settings,
    time: f64,
    backend: &mut Backend,
) -> Image {
    let mut sequence = Sequence::new(scene.clone(), "street".into()).unwrap();
    let mut stats = FrameStats::default();
    let placed = sequence.advance(time, settings, &mut stats).unwrap();
    sequence
        .render(backend, &placed, settings, &mut stats)
        .unwrap()
}

fn cpu() -> Backend {
    Backend::new(BackendKind::Cpu, Some(2)).unwrap()
}

/// The light-mesh runs reuse is checked for: both methods with the
/// paper's kernel, LMM1 with the smooth one, and LMM1 with each light's
/// set sized by its blocker's distance, with and without the wide set
/// (whose nodes are filled with the mesh's and reused like them).
type Variant = (Method, Kernel, Penumbra);
const VARIANTS: [Variant; 5] = [
    (Method::Lmm1, Kernel::Box, Penumbra::Fixed),
    (Method::Lmm, Kernel::Box, Penumbra::Fixed),
    (Method::Lmm1, Kernel::Smooth, Penumbra::Fixed),
    (Method::Lmm1, Kernel::Smooth, Penumbra::Blocker),
    (Method::Lmm1, Kernel::Box, Penumbra::Wide),
];

fn settings_for_variant((method, kernel, penumbra): Variant) -> Settings {
    let mut settings = settings_for(method);
    settings.lightmesh.kernel = kernel;
    settings.lightmesh.penumbra = penumbra;
    settings
}

/// For each of [`VARIANTS`]: every time rendered by one sequence on
/// `backend`, checked equal to the same time rendered cold, bit for bit.
fn sequences_equal_cold(scene: &SceneDesc, backend: &mut Backend) -> Vec<Vec<(Image, FrameStats)>> {
    VARIANTS
        .into_iter()
        .map(|variant| {
            let settings = settings_for_variant(variant);
            let frames = rendered_in_sequence(scene, &settings, backend);
            for (&time, (image, _)) in TIMES.iter().zip(&frames) {
                assert_eq!(
                    *image,
                    rendered_cold(scene, &settings, time, backend),
                    "{variant:?} at t = {time}"
                );
            }
            frames
        })
        .collect()
}

#[test]
fn frames_with_reused_masks_equal_frames_rendered_cold() {
    let scene = street(true, true, true);
    let runs = sequences_equal_cold(&scene, &mut cpu());
    for ((_, _, penumbra), frames) in VARIANTS.into_iter().zip(runs) {
        if penumbra.sizes_by_blocker() {
            let rays = |(_, stats): &(Image, FrameStats)| stats.lightmesh.unwrap().blocker_rays;
            assert!(
                frames.iter().all(|frame| rays(frame) > 0),
                "penumbrae were sized"
            );
        }
        for (&time, (_, stats)) in TIMES.iter().zip(&frames) {
            if time > 0.0 {
                assert!(stats.objects_moved == 1 && stats.lights_moved == 1 && stats.camera_moved);
                assert!(
                    stats.bits_invalidated > 0,
                    "the truck and the light drop bits at t = {time}"
                );
                let mesh = stats.lightmesh.unwrap();
                assert!(mesh.bits_reused > 0, "most bits are reused at t = {time}");
            }
        }
        // The truck's shadow reaches the facade by the last frame.
        assert_ne!(frames[0].0, frames[3].0);
    }
}

#[test]
fn camera_only_animation_recomputes_no_bit() {
    let scene = street(false, false, true);
    let settings = settings_for(Method::Lmm1);
    let mut backend =
        lmanim::backend::Backend::new(lmanim::settings::BackendKind::Cpu, Some(2)).unwrap();
    let mut sequence = Sequence::new(scene, "street".into()).unwrap();
    let mut computed = 0;
    for (index, &time) in TIMES.iter().enumerate() {
        let mut stats = FrameStats::default();
        let placed = sequence.advance(time, &settings, &mut stats).unwrap();
        sequence
            .render(&mut backend, &placed, &settings, &mut stats)
            .unwrap();
        if index > 0 {
            assert!(stats.camera_moved && stats.objects_moved == 0 && stats.lights_moved == 0);
            assert_eq!(stats.bits_invalidated, 0);
            assert!(!stats.copied);
        }
        computed += stats.lightmesh.unwrap().bits_computed;
    }
    // Nodes coming into view are computed once; none twice.
    let cached = sequence.light_mesh().unwrap().masks().static_bits();
    assert_eq!(computed, cached);
}

#[test]
fn a_still_sequence_copies_its_frames() {
    let frames = rendered_in_sequence(
        &street(false, false, false),
        &settings_for(Method::Lmm1),
        &mut cpu(),
    );
    assert!(!frames[0].1.copied);
    for (image, stats) in &frames[1..] {
        assert!(stats.copied);
        assert_eq!(*image, frames[0].0);
        assert_eq!(stats.shading_points, 0, "nothing was rendered");
    }
}

/// `target` keyed at each of [`TIMES`] with `values` (width components
/// each) under `interpolation`.
fn keyed(target: Target, interpolation: Interpolation, values: &[f32]) -> Channel {
    Channel {
        target,
        sampler: Sampler {
            interpolation,
            times: TIMES.iter().map(|&t| t as f32).collect(),
            values: values.to_vec(),
            width: values.len() / TIMES.len(),
        },
    }
}

/// The still street with `channels` playing.
fn street_animating(channels: Vec<Channel>) -> SceneDesc {
    let mut scene = street(false, false, false);
    add_clip(&mut scene, "looks", channels);
    scene
}

/// Sums of the red, green and blue channels of an image.
fn channel_sums(image: &Image) -> [f64; 3] {
    image.pixels.iter().fold([0.0; 3], |sums, p| {
        [
            sums[0] + f64::from(p.x),
            sums[1] + f64::from(p.y),
            sums[2] + f64::from(p.z),
        ]
    })
}

/// Frames after the first of a sequence that changes no geometry and no
/// light position, rendered with `settings`: rendered anew (not copied),
/// each different from the one before, equal to the same frame rendered
/// cold, and not one mask bit invalidated or computed again.
fn assert_re_rendered_with_every_bit_kept(
    scene: &SceneDesc,
    settings: &Settings,
    frames: &[(Image, FrameStats)],
) {
    assert!(frames[0].1.lightmesh.unwrap().bits_computed > 0);
    for (index, (image, stats)) in frames.iter().enumerate().skip(1) {
        let time = TIMES[index];
        assert!(!stats.copied, "re-rendered at t = {time}");
        assert!(stats.shading_points > 0);
        assert_eq!((stats.lights_moved, stats.objects_moved), (0, 0));
        assert_eq!(stats.bits_invalidated, 0, "t = {time}");
        assert_eq!(stats.lightmesh.unwrap().bits_computed, 0, "t = {time}");
        assert_ne!(
            *image,
            frames[index - 1].0,
            "the picture changes at t = {time}"
        );
        assert_eq!(
            *image,
            rendered_cold(scene, settings, time, &mut cpu()),
            "t = {time}"
        );
    }
}

#[test]
fn light_colour_animation_re_renders_but_invalidates_and_recomputes_nothing() {
    // The second lamp, which lights most of the view, turns from white to
    // orange-red (LINEAR) and steps its intensity; nothing else changes.
    let scene = street_animating(vec![
        keyed(
            Target::Light(1, LightProperty::Color),
            Interpolation::Linear,
            &[1.0, 1.0, 1.0, 1.0, 0.8, 0.6, 1.0, 0.5, 0.3, 1.0, 0.3, 0.1],
        ),
        keyed(
            Target::Light(1, LightProperty::Intensity),
            Interpolation::Step,
            &[200.0, 150.0, 250.0, 300.0],
        ),
    ]);
    // A lamp's light decides which lamps are faint at a point
    // (`lightmesh::faint`), and a faint lamp's wide set is not demanded:
    // with none faint, nothing is computed again.
    let mut every_lamp = settings_for(Method::Lmm);
    every_lamp.lightmesh.faint_lamps = 0.0;
    let frames = rendered_in_sequence(&scene, &every_lamp, &mut cpu());
    for (_, stats) in &frames[1..] {
        assert!(!stats.camera_moved);
    }
    assert_re_rendered_with_every_bit_kept(&scene, &every_lamp, &frames);
    // With faint lamps (the default), a lamp that stops being faint asks
    // for its wide set's bits: some are new, none is invalidated, and the
    // frames are still the cold ones.
    let settings = settings_for(Method::Lmm);
    let defaults = rendered_in_sequence(&scene, &settings, &mut cpu());
    for (index, (image, stats)) in defaults.iter().enumerate().skip(1) {
        assert_eq!(stats.bits_invalidated, 0);
        let cold = rendered_cold(&scene, &settings, TIMES[index], &mut cpu());
        assert_eq!(*image, cold, "t = {}", TIMES[index]);
    }
    // White light on grey gives grey; by the end the lamp is orange-red.
    let [r0, g0, b0] = channel_sums(&frames[0].0);
    assert!((r0 - g0).abs() < 1e-3 * r0 && (g0 - b0).abs() < 1e-3 * g0);
    let [r, g, b] = channel_sums(&frames[3].0);
    assert!(r > 1.5 * g && g > 1.5 * b, "{r} {g} {b}");
}

#[test]
fn material_animation_re_renders_but_invalidates_nothing_and_moves_nothing() {
    let scene = street_animating(vec![keyed(
        Target::Material(0, MaterialProperty::BaseColor),
        Interpolation::Linear,
        &[
            0.6, 0.6, 0.6, 1.0, 0.7, 0.4, 0.4, 1.0, 0.8, 0.3, 0.2, 1.0, 0.9, 0.2, 0.1, 1.0,
        ],
    )]);
    // A material change makes no object dynamic: the world stays static.
    assert!(dynamic_nodes(&scene).iter().all(|&dynamic| !dynamic));
    let frames = rendered_in_sequence(&scene, &settings_for(Method::Lmm), &mut cpu());
    for (_, stats) in &frames[1..] {
        assert!(!stats.camera_moved);
    }
    assert_re_rendered_with_every_bit_kept(&scene, &settings_for(Method::Lmm), &frames);
}

#[test]
fn field_of_view_animation_moves_the_camera_and_invalidates_nothing() {
    let scene = street_animating(vec![keyed(
        Target::Camera(0, CameraProperty::Yfov),
        Interpolation::Linear,
        &[0.9, 0.8, 0.7, 0.6],
    )]);
    let settings = settings_for(Method::Lmm);
    let frames = rendered_in_sequence(&scene, &settings, &mut cpu());
    for (index, (image, stats)) in frames.iter().enumerate().skip(1) {
        let time = TIMES[index];
        assert!(stats.camera_moved && !stats.copied, "t = {time}");
        assert_eq!(stats.bits_invalidated, 0, "t = {time}");
        assert_ne!(*image, frames[index - 1].0, "t = {time}");
        assert_eq!(
            *image,
            rendered_cold(&scene, &settings, time, &mut cpu()),
            "t = {time}"
        );
    }
}

/// The still street with a sheet between lamp 0 and the facade, whose
/// z > 0 half a morph target bends down frame by frame (its other half
/// stays): the deformed object's changed regions are its moving clusters'
/// boxes, and every frame rendered with reused masks equals the same frame
/// rendered cold.
/// `scene` with a sheet at x = 15 whose one half a morph target bends
/// down and back over the sequence.
fn with_bending_sheet(mut scene: SceneDesc) -> SceneDesc {
    scene
        .meshes
        .push(half_morphing_sheet(15.0, 3.0, 3.5, 0.25, 1.5));
    let sheet = add_node(&mut scene, DMat4::IDENTITY);
    scene.nodes[sheet].mesh = Some(scene.meshes.len() - 1);
    scene.nodes[sheet].deforms = true;
    let bend = keyed(
        Target::Weights(sheet),
        Interpolation::Linear,
        &[0.0, 0.5, 1.0, 0.25],
    );
    add_clip(&mut scene, "bend", vec![bend]);
    scene
}

#[test]
fn a_mesh_deforming_in_part_renders_every_frame_like_cold() {
    let scene = with_bending_sheet(street(false, false, false));
    for frames in sequences_equal_cold(&scene, &mut cpu()) {
        for (&time, (_, stats)) in TIMES.iter().zip(&frames) {
            if time > 0.0 {
                assert_eq!((stats.objects_moved, stats.camera_moved), (1, false));
                assert!(
                    stats.bits_invalidated > 0,
                    "the bending drops bits at t = {time}"
                );
                assert!(stats.lightmesh.unwrap().bits_reused > 0);
            }
        }
        assert_ne!(frames[0].0, frames[2].0, "the bent half's shadow moves");
    }
}

/// The GPU backend keeps the masks resident across frames and uploads
/// only the bricks edited since: with a truck whose shadow crosses the far
/// facade, a moving lamp and a bending sheet, for each of [`VARIANTS`], its frames
/// equal its own frames rendered cold, and (where it rounds as the CPU
/// does) the CPU backend's, bit for bit.
#[test]
fn gpu_frames_with_resident_masks_equal_cold_frames_and_the_cpus() {
    let Some((mut gpu, exact)) = common::gpu::backend_to_compare() else {
        return;
    };
    let scene = with_bending_sheet(street(true, true, false));
    let on_gpu = sequences_equal_cold(&scene, &mut gpu);
    for (variant, gpu_frames) in VARIANTS.into_iter().zip(on_gpu) {
        let cpu_frames = rendered_in_sequence(&scene, &settings_for_variant(variant), &mut cpu());
        for (&time, ((gpu, gpu_stats), (cpu, _))) in
            TIMES.iter().zip(gpu_frames.iter().zip(&cpu_frames))
        {
            if time > 0.0 {
                let mesh = gpu_stats.lightmesh.expect("light-mesh stats");
                assert!(
                    mesh.bits_reused > 0,
                    "{variant:?} reuses bits at t = {time}"
                );
                assert!(
                    gpu_stats.bits_invalidated > 0,
                    "{variant:?} drops bits at t = {time}"
                );
            }
            if exact {
                assert_eq!(gpu, cpu, "{variant:?} at t = {time}");
            }
        }
    }
}

/// On the GPU, where nothing that shadows moves (only a light's colour
/// animates), frames after the first find every mask they read resident:
/// no point goes back to the CPU for demand, no brick is copied again,
/// and the frames are the CPU's.
#[test]
fn gpu_frames_that_move_nothing_send_no_point_to_the_cpu() {
    let Some((mut gpu, exact)) = common::gpu::backend_to_compare() else {
        return;
    };
    let scene = street_animating(vec![keyed(
        Target::Light(1, LightProperty::Color),
        Interpolation::Linear,
        &[1.0, 1.0, 1.0, 1.0, 0.8, 0.6, 1.0, 0.5, 0.3, 1.0, 0.3, 0.1],
    )]);
    for method in [Method::Lmm1, Method::Lmm] {
        let settings = settings_for(method);
        let frames = rendered_in_sequence(&scene, &settings, &mut gpu);
        let first = frames[0].1.lightmesh.expect("light-mesh stats");
        assert!(first.points_demanded > 0 && first.bricks_uploaded > 0);
        for (index, (_, stats)) in frames.iter().enumerate().skip(1) {
            let mesh = stats.lightmesh.expect("light-mesh stats");
            assert!(stats.shading_points > 0, "{method}: re-rendered");
            assert_eq!(mesh.points_demanded, 0, "{method} at t = {}", TIMES[index]);
            assert_eq!(mesh.bricks_uploaded, 0, "{method} at t = {}", TIMES[index]);
        }
        if exact {
            let on_cpu = rendered_in_sequence(&scene, &settings, &mut cpu());
            for ((gpu, _), (cpu, _)) in frames.iter().zip(&on_cpu) {
                assert_eq!(gpu, cpu, "{method}");
            }
        }
    }
}
