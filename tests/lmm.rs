//! The Light Meshes Method against its contract (paper sections 2–3): equal
//! to Whitted away from shadow edges, the paper's count of step-3 tests, the
//! inward penumbra, LMM against LMM1 at a concave corner, and the hard cases.

mod common;

use common::*;
use glam::{DMat4, DQuat, DVec3, Vec3};
use lmanim::backend::Backend;
use lmanim::lightmesh::kernel::Kernel;
use lmanim::lightmesh::penumbra::Penumbra;
use lmanim::lightmesh::LightMeshStats;
use lmanim::output::Image;
use lmanim::scene::{LightKind, SceneDesc};
use lmanim::sequence::Sequence;
use lmanim::settings::{Method, Settings};

fn with_method(mut settings: Settings, method: Method, h: f32, ki: f32) -> Settings {
    settings.method = method;
    settings.lightmesh.h = Some(h);
    settings.lightmesh.ki = ki;
    settings
}

fn lightmesh_stats(scene: SceneDesc, settings: &Settings) -> (Image, LightMeshStats) {
    let (image, stats) = render_with_stats(scene, settings);
    (
        image,
        stats
            .lightmesh
            .expect("light-mesh methods report their stats"),
    )
}

fn lit_floor() -> SceneDesc {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.6)));
    add_quads(&mut scene, &[floor_quad(0.0, 5.0)], 4, m);
    add_light(
        &mut scene,
        LightKind::Point,
        20.0,
        DMat4::from_translation(DVec3::new(0.3, 2.0, -0.2)),
    );
    add_light(
        &mut scene,
        LightKind::Point,
        5.0,
        DMat4::from_translation(DVec3::new(-1.0, 1.0, 0.7)),
    );
    add_top_camera(&mut scene, 5.0, 2.0);
    scene
}

#[test]
fn without_occluders_all_three_methods_agree() {
    let base = settings(48, 32);
    let whitted = render(lit_floor(), &base);
    for method in [Method::Lmm, Method::Lmm1] {
        let image = render(lit_floor(), &with_method(base.clone(), method, 0.1, 2.5));
        for (a, b) in whitted.pixels.iter().zip(&image.pixels) {
            assert!(
                (*a - *b).abs().max_element() <= 1e-6 * a.max_element(),
                "{method}: {a} vs {b}"
            );
        }
    }
}

/// A plane tilted `tilt_degrees` about X (or lying flat), seen from above.
fn open_plane(tilt_degrees: f64) -> SceneDesc {
    let mut scene = empty_scene();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    let plane = add_quads(&mut scene, &[floor_quad(0.0, 6.0)], 1, m);
    scene.nodes[plane].local = DMat4::from_quat(DQuat::from_rotation_x(tilt_degrees.to_radians()));
    add_light(
        &mut scene,
        LightKind::Point,
        50.0,
        DMat4::from_translation(DVec3::new(0.0, 4.0, 0.0)),
    );
    add_top_camera(&mut scene, 5.0, 2.0);
    scene
}

/// The paper's table of mean step-3 tests per point: on an open plane in
/// general position the half-ball holds (2/3)·π·kI³ nodes on average.
#[test]
fn mean_point_to_node_tests_match_the_half_ball_volume() {
    for (ki, expected) in [(2.1f32, 19.4f64), (2.5, 32.7), (3.0, 56.5)] {
        let settings = with_method(settings(96, 96), Method::Lmm, 0.05, ki);
        let (_, stats) = lightmesh_stats(open_plane(3.0), &settings);
        let volume = 2.0 / 3.0 * std::f64::consts::PI * (ki as f64).powi(3);
        assert!((volume - expected).abs() < 0.05);
        let error = (stats.mean_p2n_tests - volume).abs() / volume;
        assert!(
            error < 0.03,
            "kI {ki}: {} tests vs {volume:.1}",
            stats.mean_p2n_tests
        );
        assert_eq!(stats.mean_p2n_tests, stats.mean_candidates);
        // Nothing occludes the open plane: every candidate passes step 3.
        assert_eq!(stats.mean_interp_set, stats.mean_candidates);
    }
}

/// A plane lying exactly on a lattice plane loses the nodes in the plane:
/// they fail step 2 ((n, x − P) = 0), so the mean falls below the volume.
#[test]
fn a_plane_on_a_lattice_plane_has_fewer_candidates() {
    let h = 0.05f32;
    // LMM walks every point's half-ball (LMM1 takes most points on an
    // open plane from what their nodes agree on, and counts none there).
    let settings = with_method(settings(64, 64), Method::Lmm, h, 2.5);
    let (_, general) = lightmesh_stats(open_plane(0.0), &settings);
    // Render space is world space minus the centre of the scene's bounds.
    // A small marker quad far from the view at height Y puts that centre at
    // Y/2, so the floor sits at −Y/2 in render space; choose Y to land it on
    // the lattice plane one step below the origin's: y = (g − 1)·h.
    let g = lmanim::lightmesh::lattice::GENERAL_POSITION.y;
    let marker_height = 2.0 * (1.0 - g) * h;
    let mut on_lattice = open_plane(0.0);
    let m = add_material(&mut on_lattice, lambert(Vec3::splat(0.5)));
    let corner = Vec3::new(5.9, marker_height, 5.9);
    add_quads(
        &mut on_lattice,
        &[[
            corner,
            corner + Vec3::X * 0.01,
            corner + Vec3::new(0.01, 0.0, -0.01),
            corner - Vec3::Z * 0.01,
        ]],
        1,
        m,
    );
    let (image, on_plane) = lightmesh_stats(on_lattice.clone(), &settings);
    gpu::assert_gpu_frame_is(&on_lattice, &settings, &image);
    let volume = 2.0 / 3.0 * std::f64::consts::PI * 2.5f64.powi(3);
    assert!((general.mean_candidates - volume).abs() / volume < 0.03);
    // On the lattice plane, P's candidates are the nodes of whole layers
    // j·h above it (j ≥ 1), discs of radius √(kI² − j²): on average
    // π·Σ_j (kI² − j²) = 23.6 for kI = 2.5, against the half-ball's 32.7 —
    // the in-plane disc (π·kI² / 2 of the volume's share) is lost to step 2.
    let layers: f64 = (1..=2)
        .map(|j| std::f64::consts::PI * (2.5f64.powi(2) - (j * j) as f64))
        .sum();
    let error = (on_plane.mean_candidates - layers).abs() / layers;
    assert!(error < 0.03, "{} vs {layers:.1}", on_plane.mean_candidates);
    assert!(on_plane.mean_candidates < general.mean_candidates - 5.0);
}

/// A leaf under a street lamp: an occluder smaller than the penumbra. Its
/// Whitted umbra is black; LMM spreads the transition inward too, so the
/// darkest point is clearly lighter — and a smaller h·kI brings it back.
#[test]
fn small_occluders_get_an_inward_penumbra() {
    let leaf_scene = || {
        let mut scene = empty_scene();
        let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
        add_quads(
            &mut scene,
            &[floor_quad(0.0, 4.0), floor_quad(1.0, 0.06)],
            1,
            m,
        );
        add_light(
            &mut scene,
            LightKind::Point,
            20.0,
            DMat4::from_translation(DVec3::new(0.0, 3.0, 0.0)),
        );
        add_top_camera(&mut scene, 0.9, 0.5);
        scene
    };
    let darkest = |image: &Image| {
        image
            .pixels
            .iter()
            .map(|p| p.x)
            .fold(f32::INFINITY, f32::min)
    };
    let brightest = |image: &Image| image.pixels.iter().map(|p| p.x).fold(0.0, f32::max);
    let base = settings(64, 64);
    let whitted = render(leaf_scene(), &base);
    assert_eq!(darkest(&whitted), 0.0, "Whitted has a hard umbra");
    let wide = render(
        leaf_scene(),
        &with_method(base.clone(), Method::Lmm, 0.08, 2.5),
    );
    let narrow = render(
        leaf_scene(),
        &with_method(base.clone(), Method::Lmm, 0.01, 2.5),
    );
    let lit = brightest(&whitted);
    assert!(
        darkest(&wide) > 0.4 * lit,
        "wide penumbra keeps the leaf's shadow light: {}",
        darkest(&wide) / lit
    );
    assert!(
        darkest(&narrow) < 0.05 * lit,
        "small h·kI restores the umbra: {}",
        darkest(&narrow) / lit
    );
}

/// A floor meeting a lit one-sided wall: LMM1 would count the nodes behind
/// the wall, which do not see the light, and darken the floor along the
/// corner; LMM's point-to-node tests drop them all. LMM1 drops those its
/// probes find behind the wall (`lightmesh::enclosure`); the ones by the
/// floor see the floor's front as often as the wall's back and stay, so
/// some darkening remains.
#[test]
fn lmm1_darkens_a_concave_corner_a_little_and_lmm_not_at_all() {
    let corner = || {
        let mut scene = empty_scene();
        let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
        let wall = [
            Vec3::new(0.0, 0.0, -3.0),
            Vec3::new(0.0, 0.0, 3.0),
            Vec3::new(0.0, 3.0, 3.0),
            Vec3::new(0.0, 3.0, -3.0),
        ];
        // The floor runs on past the wall, as a street runs past a facade.
        add_quads(&mut scene, &[floor_quad(0.0, 3.0), wall], 2, m);
        add_light(
            &mut scene,
            LightKind::Point,
            20.0,
            DMat4::from_translation(DVec3::new(-1.5, 2.0, 0.0)),
        );
        // Looking down at the floor on the light's side of the wall (x < 0).
        add_camera(
            &mut scene,
            lmanim::scene::Projection::Orthographic {
                xmag: 0.5,
                ymag: 0.5,
                znear: 0.0,
                zfar: 100.0,
            },
            DMat4::from_rotation_translation(
                DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2),
                DVec3::new(-0.5, 2.0, 0.0),
            ),
        );
        scene
    };
    let base = settings(32, 32);
    let whitted = render(corner(), &base);
    let lmm = render(corner(), &with_method(base.clone(), Method::Lmm, 0.1, 2.5));
    let lmm1 = render(corner(), &with_method(base.clone(), Method::Lmm1, 0.1, 2.5));
    // The right-hand columns are the floor within 0.25 m of the wall.
    let mean_near_wall = |image: &Image| {
        let mut sum = 0.0;
        for y in 0..32 {
            for x in 24..32 {
                sum += pixel(image, x, y).x / pixel(&whitted, x, y).x;
            }
        }
        sum / (32.0 * 8.0)
    };
    let lmm_ratio = mean_near_wall(&lmm);
    let lmm1_ratio = mean_near_wall(&lmm1);
    assert!(
        (lmm_ratio - 1.0).abs() < 1e-5,
        "LMM equals Whitted at the corner: {lmm_ratio}"
    );
    // Without the enclosure flag the corner fell below 0.9.
    assert!(
        (0.92..0.999).contains(&lmm1_ratio),
        "LMM1 leaks a little darkness from behind the wall: {lmm1_ratio}"
    );
}

#[test]
fn points_and_surfaces_on_lattice_nodes_and_planes_stay_finite() {
    // A blocker whose top and edges lie exactly on lattice planes. Render
    // space is centred on the scene's bounds: with the floor at y = 0 and
    // the blocker at y_b, the centre is y_b / 2 (x and z stay 0), so the
    // blocker's render height is y_b / 2 = (g + 2)·h for y_b = 2(g + 2)·h.
    let h = 0.25f32;
    let mut scene = lit_floor();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    let origin = lmanim::lightmesh::lattice::GENERAL_POSITION * h;
    let y = 2.0 * (origin.y + 2.0 * h);
    let x0 = origin.x - h;
    let z0 = origin.z - h;
    let blocker = [
        Vec3::new(x0, y, z0 + 2.0 * h),
        Vec3::new(x0 + 2.0 * h, y, z0 + 2.0 * h),
        Vec3::new(x0 + 2.0 * h, y, z0),
        Vec3::new(x0, y, z0),
    ];
    add_quads(&mut scene, &[blocker], 1, m);
    for (method, kernel) in [Method::Lmm, Method::Lmm1]
        .into_iter()
        .flat_map(|method| [Kernel::Box, Kernel::Smooth].map(|kernel| (method, kernel)))
    {
        let mut settings = with_method(settings(40, 40), method, h, 2.0);
        settings.lightmesh.kernel = kernel;
        let image = render(scene.clone(), &settings);
        assert!(image
            .pixels
            .iter()
            .all(|p| p.is_finite() && p.min_element() >= 0.0));
        // The GPU's half-ball rounds its on-plane tolerance, and its
        // kernel the distances of nodes on lattice planes, as the CPU's.
        gpu::assert_gpu_frame_is(&scene, &settings, &image);
    }
}

/// The top and four sides of the box from `lo` to `hi`, facing out: with
/// a floor under it, closed geometry whose inner nodes see no light.
fn closed_box(lo: Vec3, hi: Vec3) -> [[Vec3; 4]; 5] {
    [
        [
            Vec3::new(lo.x, hi.y, hi.z),
            Vec3::new(hi.x, hi.y, hi.z),
            Vec3::new(hi.x, hi.y, lo.z),
            Vec3::new(lo.x, hi.y, lo.z),
        ],
        [
            Vec3::new(lo.x, lo.y, hi.z),
            Vec3::new(hi.x, lo.y, hi.z),
            Vec3::new(hi.x, hi.y, hi.z),
            Vec3::new(lo.x, hi.y, hi.z),
        ],
        [
            Vec3::new(hi.x, lo.y, lo.z),
            Vec3::new(lo.x, lo.y, lo.z),
            Vec3::new(lo.x, hi.y, lo.z),
            Vec3::new(hi.x, hi.y, lo.z),
        ],
        [
            Vec3::new(hi.x, lo.y, hi.z),
            Vec3::new(hi.x, lo.y, lo.z),
            Vec3::new(hi.x, hi.y, lo.z),
            Vec3::new(hi.x, hi.y, hi.z),
        ],
        [
            Vec3::new(lo.x, lo.y, lo.z),
            Vec3::new(lo.x, lo.y, hi.z),
            Vec3::new(lo.x, hi.y, hi.z),
            Vec3::new(lo.x, hi.y, lo.z),
        ],
    ]
}

#[test]
fn nodes_inside_closed_objects_see_no_light_and_do_not_break_shading() {
    // A closed box on the floor: nodes inside it are occluded from the lamp.
    let mut scene = lit_floor();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    let faces = closed_box(Vec3::new(-0.4, 0.0, -0.4), Vec3::new(0.4, 0.8, 0.4));
    add_quads(&mut scene, &faces, 2, m);
    let whitted = render(scene.clone(), &settings(40, 40));
    let lmm_settings = with_method(settings(40, 40), Method::Lmm, 0.1, 2.5);
    let lmm = render(scene.clone(), &lmm_settings);
    gpu::assert_gpu_frame_is(&scene, &lmm_settings, &lmm);
    for kernel in [Kernel::Box, Kernel::Smooth] {
        let mut lmm1_settings = with_method(settings(40, 40), Method::Lmm1, 0.1, 2.5);
        lmm1_settings.lightmesh.kernel = kernel;
        gpu::assert_gpu_frame_is(
            &scene,
            &lmm1_settings,
            &render(scene.clone(), &lmm1_settings),
        );
    }
    // Far from the box both agree; the box top (lit, its candidate nodes
    // above it) equals Whitted too: nodes inside the box fail step 2.
    assert_eq!(pixel(&whitted, 2, 2), pixel(&lmm, 2, 2));
    assert!(
        (pixel(&whitted, 20, 20).x - pixel(&lmm, 20, 20).x).abs()
            <= 1e-6 * pixel(&whitted, 20, 20).x
    );
}

#[test]
fn more_than_a_hundred_lights_use_several_mask_words() {
    let mut scene = lit_floor();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    add_quads(&mut scene, &[floor_quad(0.5, 0.3)], 1, m);
    for i in 0..130 {
        let angle = i as f64 * 0.37;
        let position = DVec3::new(
            angle.cos() * 2.0,
            1.5 + (i % 7) as f64 * 0.2,
            angle.sin() * 2.0,
        );
        add_light(
            &mut scene,
            LightKind::Point,
            0.5,
            DMat4::from_translation(position),
        );
    }
    let base = settings(32, 32);
    let whitted = render(scene.clone(), &base);
    // On the GPU: five words of 32 lights per node, and as many passes
    // over each point's set, each summing weights into its counters.
    for (method, kernel) in [
        (Method::Lmm1, Kernel::Box),
        (Method::Lmm, Kernel::Box),
        (Method::Lmm1, Kernel::Smooth),
    ] {
        let mut settings = with_method(base.clone(), method, 0.05, 2.5);
        settings.lightmesh.kernel = kernel;
        gpu::assert_gpu_frame_is(&scene, &settings, &render(scene.clone(), &settings));
    }
    let (lmm, stats) = lightmesh_stats(scene, &with_method(base, Method::Lmm, 0.05, 2.5));
    assert!(
        stats.bits_computed > stats.nodes_computed * 64,
        "bits beyond the first word were computed"
    );
    // Soft shadows differ from hard ones only near edges: the mean agrees.
    let mean = |image: &Image| {
        image.pixels.iter().map(|p| p.x as f64).sum::<f64>() / image.pixels.len() as f64
    };
    assert!((mean(&lmm) - mean(&whitted)).abs() / mean(&whitted) < 0.05);
}

/// The many-light floor with lamps of 5 cm, whose penumbrae `blocker`
/// sizes: where a point's set disagrees on a lamp, its nearest blocked
/// node is sought and its level's nodes traced, for every such lamp.
/// With 40 lamps the GPU's frame is the CPU's on every adapter. With 130
/// a point can need more loop iterations than lavapipe (Mesa 22.3) runs
/// in one invocation: it ends every loop after 65,535 of them, silently,
/// and its frame lost lamps the CPU's kept. The shader notices and the
/// frame is refused with an error that says so; a hardware adapter has
/// no such budget and must match. (`wide`, which also walks each point's
/// wide set, passes lavapipe's budget here up to 34 lamps.)
#[test]
fn many_lamps_sized_by_their_blockers_give_the_cpus_frame_on_the_gpu() {
    for lamps in [40, 130] {
        let mut scene = lit_floor();
        let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
        add_quads(&mut scene, &[floor_quad(0.5, 0.3)], 1, m);
        for i in 0..lamps {
            let angle = i as f32 * 0.37;
            let height = 1.5 + (i % 7) as f32 * 0.2;
            add_lamp(
                &mut scene,
                0.5,
                Vec3::new(angle.cos() * 2.0, height, angle.sin() * 2.0),
                0.05,
            );
        }
        let mut settings = with_method(settings(32, 32), Method::Lmm, 0.05, 2.5);
        settings.lightmesh.penumbra = Penumbra::Blocker;
        let (on_cpu, stats) = lightmesh_stats(scene.clone(), &settings);
        assert!(stats.blocker_rays > 0, "lamps were sized by their blockers");
        let Some(gpu) = gpu::backend() else { return };
        let (exact, software) = (gpu.rounds_as_the_cpu(), gpu.is_software());
        let mut backend = Backend::Gpu(Box::new(gpu));
        let mut sequence = Sequence::new(scene, "lamps.gltf".into()).expect("scene");
        let placed = sequence.place(&settings).expect("camera");
        match sequence.render(&mut backend, &placed, &settings, &mut Default::default()) {
            Ok(on_gpu) if exact => {
                assert!(on_gpu == on_cpu, "{lamps} lamps: the GPU's frame differs")
            }
            Ok(on_gpu) => assert!(on_gpu.pixels.iter().all(|p| p.is_finite())),
            Err(error) => {
                assert!(lamps > 40 && software, "{lamps} lamps: {error}");
                assert!(
                    error
                        .to_string()
                        .contains("cut the light mesh's shader loops short"),
                    "{error}"
                );
            }
        }
    }
}

/// The GPU settles a point's set by the summary of the nodes around a tile
/// (`agreement.wgsl`) where they all agree on its lights, instead of
/// walking it, and must get what the walk gets: the CPU's bits. The floor
/// of 33 lights (two mask words) holds a blocker whose top and edges lie
/// on lattice planes, a closed box (enclosed nodes, whose lights hidden
/// from every node no summary may settle), and a tilted quad whose normal
/// points down two axes (the tile is then chosen by the cell's first
/// corner on those). Below kI = 2 a half-ball may hold no node, and no
/// point is settled.
#[test]
fn points_settled_by_tile_summaries_on_the_gpu_get_the_cpus_bits() {
    let h = 0.05f32;
    let mut scene = lit_floor();
    let m = add_material(&mut scene, lambert(Vec3::splat(0.5)));
    let origin = lmanim::lightmesh::lattice::GENERAL_POSITION * h;
    let (x0, y, z0) = (origin.x - h, 2.0 * (origin.y + 2.0 * h), origin.z - h);
    let on_planes = [
        Vec3::new(x0, y, z0 + 2.0 * h),
        Vec3::new(x0 + 2.0 * h, y, z0 + 2.0 * h),
        Vec3::new(x0 + 2.0 * h, y, z0),
        Vec3::new(x0, y, z0),
    ];
    let tilted = [
        Vec3::new(1.0, 0.6, 1.8),
        Vec3::new(1.8, 0.2, 1.8),
        Vec3::new(1.8, 0.6, 1.0),
        Vec3::new(1.0, 1.0, 1.0),
    ];
    add_quads(&mut scene, &[on_planes, tilted], 1, m);
    let closed = closed_box(Vec3::new(-1.6, 0.0, -1.6), Vec3::new(-0.9, 0.5, -0.9));
    add_quads(&mut scene, &closed, 1, m);
    for i in 0..31 {
        let angle = i as f32 * 0.37;
        let height = 1.5 + (i % 7) as f32 * 0.2;
        let position = Vec3::new(angle.cos() * 2.5, height, angle.sin() * 2.5);
        add_lamp(&mut scene, 0.3, position, 0.05);
    }
    for ki in [1.5, 2.0, 2.5] {
        let settings = with_method(settings(32, 32), Method::Lmm1, h, ki);
        let on_cpu = render(scene.clone(), &settings);
        let Some((mut gpu, exact)) = gpu::backend_to_compare() else {
            return;
        };
        let (on_gpu, stats) = render_on(&mut gpu, scene.clone(), &settings);
        match exact {
            true => assert!(on_gpu == on_cpu, "kI {ki}: the GPU's frame differs"),
            false => assert!(on_gpu.pixels.iter().all(|p| p.is_finite())),
        }
        let settled = stats.lightmesh.expect("light-mesh stats").points_settled;
        let points = stats.shading_points;
        match ki < 2.0 {
            true => assert_eq!(settled, 0, "kI {ki}: no summary may settle a point"),
            false => assert!(
                4 * settled > points,
                "kI {ki}: {settled} of {points} points settled"
            ),
        }
    }
}

#[test]
fn a_lattice_too_fine_for_the_memory_limit_is_a_clear_error() {
    let mut settings = with_method(settings(64, 64), Method::Lmm1, 1e-4, 2.5);
    settings.lightmesh.max_memory_mib = 64;
    let mut sequence = lmanim::sequence::Sequence::new(lit_floor(), "floor.gltf".into()).unwrap();
    let mut backend =
        lmanim::backend::Backend::new(lmanim::settings::BackendKind::Cpu, Some(2)).unwrap();
    let placed = sequence.place(&settings).unwrap();
    let mut stats = Default::default();
    let error = sequence
        .render(&mut backend, &placed, &settings, &mut stats)
        .unwrap_err();
    let message = error.to_string();
    assert!(
        message.contains("floor.gltf") && message.contains("MiB") && message.contains("h ="),
        "{message}"
    );
    assert!(error.is_bad_input());
}

#[test]
fn a_light_mesh_method_without_a_light_mesh_is_an_error_not_a_panic() {
    let settings = settings(8, 8);
    let mut sequence = lmanim::sequence::Sequence::new(lit_floor(), "floor.gltf".into()).unwrap();
    let placed = sequence.place(&settings).unwrap();
    let world = lmanim::accel::World::build(&[]);
    let job = lmanim::render::FrameJob {
        scene: sequence.scene(),
        frame: &placed,
        world: &world,
        width: settings.width,
        height: settings.height,
        spp: settings.spp,
        max_depth: settings.max_depth,
        environment: settings.environment(),
        aovs: &[],
        shadows: &Default::default(),
    };
    let backend = lmanim::backend::CpuBackend::new(Some(1)).unwrap();
    for method in [Method::Lmm, Method::Lmm1] {
        let method = job.shadows.resolve(method, &job.frame.lights);
        let error = backend
            .render(&job, method, None, &mut Default::default())
            .unwrap_err();
        assert!(
            matches!(error, lmanim::backend::RenderError::NoLightMesh),
            "{method:?}: {error}"
        );
        assert!(error.to_string().contains("light mesh"), "{error}");
    }
}

#[test]
fn a_light_mesh_method_with_every_light_off_renders_as_whitted() {
    let no_lights = || {
        let mut scene = lit_floor();
        scene.lights.clear();
        scene.nodes.iter_mut().for_each(|node| node.light = None);
        scene
    };
    let lights_off = || {
        let mut scene = lit_floor();
        for light in &mut scene.lights {
            light.intensity = 0.0;
        }
        scene
    };
    let base = settings(16, 16);
    for (name, scene) in [
        ("no light", no_lights as fn() -> SceneDesc),
        ("lights off", lights_off),
    ] {
        let whitted = render(scene(), &base);
        for method in [Method::Lmm, Method::Lmm1, Method::Auto] {
            let image = render(scene(), &with_method(base.clone(), method, 0.1, 2.5));
            assert_eq!(image.pixels, whitted.pixels, "{name}, {method}");
        }
    }
}

#[test]
fn a_lattice_coarser_than_the_scene_still_renders() {
    let image = render(
        lit_floor(),
        &with_method(settings(32, 32), Method::Lmm, 50.0, 2.5),
    );
    let whitted = render(lit_floor(), &settings(32, 32));
    // No occluders: even one enormous cell reproduces formula (1).
    for (a, b) in whitted.pixels.iter().zip(&image.pixels) {
        assert!((*a - *b).abs().max_element() <= 1e-6 * a.max_element());
    }
}
