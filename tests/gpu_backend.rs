//! The GPU backend against the CPU's: ray by ray on adversarial sets (rays
//! through shared edges and vertices, axis-parallel rays, coordinates near
//! 1e5 m, a wall 1 cm thick, a rotated dynamic instance), formula (1) point
//! by point at hard points (on edges and vertices, lights on surfaces and
//! in their planes, every kind of light and lobe), shading points field
//! by field on every camera and Whitted ray of the sample scenes, a
//! textured model and skinned and morphing meshes, frame by frame on the
//! same (jittered samples and an orthographic camera included, and enough
//! samples that the recursion's compaction spans hundreds of workgroups),
//! the same bits twice, a silent
//! headless run, work the device refuses as an error, and the one-line
//! error where no adapter exists.
//!
//! These run on whatever adapter wgpu finds: lavapipe (software Vulkan,
//! Debian's mesa-vulkan-drivers) in CI. Without one a test says so and
//! passes on a developer's machine, but fails when `CI` is set.

mod anim_support;
mod common;

use std::path::Path;

use glam::IVec3;
use glam::{Affine3A, DMat4, DQuat, DVec3, Quat, Vec2, Vec3};
use lmanim::accel::{Hit, Ray, World, WorldObject};
use lmanim::backend::gpu::enclosure::ProbeSite;
use lmanim::backend::gpu::fill::SEGMENTS_PER_WAIT;
use lmanim::backend::gpu::mask_pool::MaskPool;
use lmanim::backend::gpu::{FrameLights, GpuError};
use lmanim::backend::{Backend, GpuBackend};
use lmanim::lightmesh::demand::{BrickDemand, Demand};
use lmanim::lightmesh::enclosure::{self, ProbeList};
use lmanim::lightmesh::lattice::Lattice;
use lmanim::lightmesh::masks::{self, BRICK_NODES};
use lmanim::lightmesh::segments::Shafts;
use lmanim::lightmesh::{LightMesh, LightMeshStats};
use lmanim::output::{read_exr, Image};
use lmanim::render::frame::FrameScene;
use lmanim::render::light::RenderLight;
use lmanim::render::material::SurfaceMaterial;
use lmanim::render::omega::LightLanes;
use lmanim::render::scatter::secondary_rays;
use lmanim::render::surface::ShadingPoint;
use lmanim::render::whitted;
use lmanim::render::FrameJob;
use lmanim::scene::SceneDesc;
use lmanim::scene::{Light, LightKind};
use lmanim::schedule::FrameDelta;
use lmanim::sequence::Sequence;
use lmanim::settings::{BackendKind, Method, Settings};
use lmanim::stats::FrameStats;
use lmanim_authoring::city::{city_block, CityParams};

use anim_support::lmanim;
use common::cube;
use common::gpu::backend as gpu;

/// Rays from `origins` at every vertex and edge midpoint of the placed
/// mesh (ties on shared edges and vertices by construction), and the same
/// as segments ending there.
fn rays_at_features(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    to_render: Affine3A,
    origins: &[Vec3],
) -> Vec<Ray> {
    let placed = |v: u32| to_render.transform_point3(positions[v as usize]);
    let mut targets: Vec<Vec3> = (0..positions.len() as u32).map(placed).collect();
    for t in triangles {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            targets.push((placed(a) + placed(b)) * 0.5);
        }
    }
    let mut rays = Vec::new();
    for &origin in origins {
        for &target in &targets {
            rays.push(Ray::new(origin, target - origin, f32::INFINITY));
            rays.push(Ray::segment(origin, target));
        }
    }
    rays
}

/// Axis-parallel rays (some exactly in the planes of box faces) over a grid.
fn axis_parallel_rays(centre: Vec3, half: f32) -> Vec<Ray> {
    let mut rays = Vec::new();
    for axis in 0..3 {
        let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
        for i in -4..=4 {
            for j in -4..=4 {
                let across = u * (i as f32 * half / 4.0) + v * (j as f32 * half / 4.0);
                for sign in [-1.0f32, 1.0] {
                    let origin = centre + across - Vec3::AXES[axis] * (sign * 3.0 * half);
                    rays.push(Ray::new(origin, Vec3::AXES[axis] * sign, f32::INFINITY));
                }
            }
        }
    }
    rays
}

/// Asserts that the GPU answers every ray as the CPU does: the same
/// triangle at the same `t` and barycentrics (to the bit, where the adapter
/// has f64) and the same any-hit answer.
fn assert_same_answers(gpu: &mut GpuBackend, world: &World, rays: &[Ray]) {
    let passes = gpu.passes_for(world).expect("upload");
    let (context, scene) = (passes.context, passes.scene);
    let exact = context.exact;
    let closest = passes
        .queries
        .closest_hits(context, scene, world, rays)
        .expect("closest hits");
    let occluded = passes
        .queries
        .occluded(context, scene, rays)
        .expect("any hit");
    let mut hits = 0;
    for ((ray, gpu_hit), gpu_blocked) in rays.iter().zip(&closest).zip(&occluded) {
        let cpu_hit: Option<Hit> = world.closest_hit(ray);
        hits += cpu_hit.is_some() as usize;
        assert_eq!(*gpu_blocked, world.occluded(ray), "any hit of {ray:?}");
        if exact {
            assert_eq!(*gpu_hit, cpu_hit, "closest hit of {ray:?}");
        } else {
            // Without f64 a tie on a shared edge may go to the neighbour,
            // at the same distance.
            assert_eq!(gpu_hit.is_some(), cpu_hit.is_some(), "{ray:?}");
            if let (Some(g), Some(c)) = (gpu_hit, cpu_hit) {
                assert!(
                    (g.t - c.t).abs() <= 1e-5 * c.t.abs(),
                    "{ray:?}: {g:?} {c:?}"
                );
            }
        }
    }
    assert!(hits > rays.len() / 4, "too few rays hit: {hits}");
}

/// Where the test cube goes, and whether it is dynamic: at the origin,
/// near 1e5 m, rotated as a dynamic instance, and squashed into a static
/// wall 1 cm thick.
fn hard_placements() -> [(Affine3A, bool); 4] {
    let far = Vec3::new(1.0e5, -2.0e4, 1.0e5);
    let spin = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize(), 0.7);
    [
        (Affine3A::IDENTITY, false),
        (Affine3A::from_translation(far), false),
        (
            Affine3A::from_rotation_translation(spin, Vec3::new(5.0, 0.0, 0.0)),
            true,
        ),
        (
            Affine3A::from_scale_rotation_translation(
                Vec3::new(2.0, 2.0, 0.005),
                Quat::IDENTITY,
                Vec3::new(-5.0, 0.0, 0.0),
            ),
            false,
        ),
    ]
}

/// The world of the test cube at each of `placements`.
fn world_of(positions: &[Vec3], triangles: &[[u32; 3]], placements: &[(Affine3A, bool)]) -> World {
    let objects: Vec<WorldObject> = placements
        .iter()
        .map(|&(to_render, dynamic)| WorldObject {
            positions,
            triangles,
            to_render,
            dynamic,
        })
        .collect();
    World::build(&objects)
}

#[test]
fn rays_reach_the_same_triangles_as_on_the_cpu() {
    let Some(mut gpu) = gpu() else { return };
    let (positions, triangles) = cube(6);
    let placements = hard_placements();
    let world = world_of(&positions, &triangles, &placements);
    let mut rays = Vec::new();
    for &(to_render, _) in &placements {
        let inside = [Vec3::ZERO, Vec3::new(0.3, -0.2, 0.1)].map(|p| to_render.transform_point3(p));
        let outside = to_render.transform_point3(Vec3::new(3.0, 2.5, -4.0));
        let origins = [inside[0], inside[1], outside];
        rays.extend(rays_at_features(
            &positions, &triangles, to_render, &origins,
        ));
        rays.extend(axis_parallel_rays(to_render.translation.into(), 1.0));
    }
    // Through the thin wall, grazing and square on.
    for i in 0..200 {
        let y = -1.5 + i as f32 * 0.015;
        rays.push(Ray::segment(
            Vec3::new(-5.3, y, -1.0),
            Vec3::new(-4.7, -y, 1.0),
        ));
        rays.push(Ray::new(
            Vec3::new(-5.0 + y, y, 3.0),
            Vec3::NEG_Z,
            f32::INFINITY,
        ));
    }
    assert!(rays.len() > 20_000);
    assert_same_answers(&mut gpu, &world, &rays);
}

/// Lights of every kind around a cube centred at `centre`: near and far,
/// with and without range (points beyond it), spots with smooth and hard
/// cones aimed at it and away, directional ones, one lying on a face and
/// one in the plane of the top face (grazing every point there).
fn lights_around(centre: Vec3) -> Vec<RenderLight> {
    let light = |kind, intensity: f32, range| Light {
        name: None,
        kind,
        color: Vec3::new(1.0, 0.7, 0.4),
        intensity,
        range,
        radius: None,
        group: None,
    };
    let centre = centre.as_dvec3();
    // Spots and directional lights shine down −Z of their node.
    let aimed = |at: DVec3, towards: DVec3| {
        let rotation = DQuat::from_rotation_arc(DVec3::NEG_Z, (towards - at).normalize());
        DMat4::from_rotation_translation(rotation, at)
    };
    let spot = |inner_cone, outer_cone| LightKind::Spot {
        inner_cone,
        outer_cone,
    };
    let placed = [
        (
            light(LightKind::Point, 40.0, None),
            DMat4::from_translation(centre + DVec3::new(0.0, 3.0, 0.0)),
        ),
        (
            light(LightKind::Point, 30.0, Some(2.5)),
            DMat4::from_translation(centre + DVec3::new(2.0, 0.5, 1.0)),
        ),
        (
            light(spot(0.2, 0.5), 60.0, None),
            aimed(centre + DVec3::new(0.0, 0.5, 4.0), centre),
        ),
        (
            light(spot(0.4, 0.4), 60.0, None),
            aimed(centre + DVec3::new(3.0, 3.0, 0.0), centre),
        ),
        (
            light(spot(0.1, 0.3), 60.0, None),
            aimed(
                centre + DVec3::new(-3.0, 2.0, 0.0),
                centre - DVec3::new(6.0, 0.0, 0.0),
            ),
        ),
        (
            light(LightKind::Directional, 2.0, None),
            aimed(centre, centre + DVec3::new(-1.0, -2.0, -0.5)),
        ),
        (
            light(LightKind::Point, 10.0, None),
            DMat4::from_translation(centre + DVec3::new(1.0, 0.25, 0.5)),
        ),
        (
            light(LightKind::Point, 10.0, None),
            DMat4::from_translation(centre + DVec3::new(4.0, 1.0, 0.0)),
        ),
        (
            light(LightKind::Point, 20.0, Some(40.0)),
            DMat4::from_translation(centre + DVec3::new(0.3, -3.0, 0.2)),
        ),
    ];
    placed
        .iter()
        .map(|(light, node)| RenderLight::place(light, *node, DVec3::ZERO, 0.0))
        .collect()
}

/// A shading point on the cube at `position` with outward normal `normal`,
/// seen from `eye`; the shading normal leans by `lean`.
fn point_at(
    position: Vec3,
    normal: Vec3,
    eye: Vec3,
    lean: Vec3,
    material: SurfaceMaterial,
) -> ShadingPoint {
    let leaned = (normal + lean).normalize();
    ShadingPoint {
        sample: 0,
        weight: Vec3::ONE,
        depth: 0,
        position,
        geometric_normal: normal,
        shading_normal: if leaned.dot(normal) > 0.0 {
            leaned
        } else {
            normal
        },
        front_face: true,
        view: (eye - position).normalize(),
        material,
    }
}

/// Shading points on every triangle's corners (shared vertices), edge
/// midpoints (shared edges) and centre of the placed cubes, each seen from
/// in front and from behind the surface, with and without a leaning
/// shading normal, over four lobes (Lambert, dielectric, mirror-like metal,
/// part metal part glass).
fn hard_points(
    positions: &[Vec3],
    triangles: &[[u32; 3]],
    placements: &[(Affine3A, bool)],
) -> Vec<ShadingPoint> {
    let material = |metallic, roughness, specular, transmission| SurfaceMaterial {
        base_color: Vec3::new(0.8, 0.6, 0.4),
        metallic,
        roughness,
        specular,
        transmission,
        ior: 1.5,
        emissive: Vec3::ZERO,
    };
    let materials = [
        material(0.0, 1.0, 0.0, 0.0),
        material(0.0, 0.5, 1.0, 0.0),
        material(1.0, 0.05, 1.0, 0.0),
        material(0.4, 0.3, 1.0, 0.5),
    ];
    let mut points = Vec::new();
    for (to_render, _) in placements {
        let eye = to_render.transform_point3(Vec3::new(4.0, 5.0, 6.0));
        for (t, triangle) in triangles.iter().enumerate() {
            let [a, b, c] = triangle.map(|i| to_render.transform_point3(positions[i as usize]));
            let normal = (b - a).cross(c - a).normalize();
            let material = materials[t % materials.len()];
            for p in [a, (a + b) * 0.5, (a + b + c) / 3.0] {
                points.push(point_at(p, normal, eye, Vec3::ZERO, material));
                points.push(point_at(
                    p,
                    normal,
                    eye,
                    Vec3::new(0.3, -0.2, 0.1),
                    material,
                ));
            }
        }
    }

    points
}

/// Formula (1) at `points` on the GPU: each point's light, the segments
/// traced, and whether the adapter rounds as the CPU does.
fn gpu_direct_light(
    gpu: &mut GpuBackend,
    world: &World,
    lights: &[RenderLight],
    points: &[ShadingPoint],
) -> (Vec<Vec3>, u64, bool) {
    let passes = gpu.passes_for(world).expect("upload");
    let frame_lights = FrameLights::upload(passes.context, lights).expect("lights");
    let (light, rays) = passes
        .direct
        .run(passes.context, passes.scene, &frame_lights, points)
        .expect("direct light");
    (light, rays, passes.context.exact)
}

#[test]
fn formula_one_on_the_gpu_gives_the_cpus_light_at_hard_points() {
    let Some(mut gpu) = gpu() else { return };
    let (positions, triangles) = cube(4);
    let placements = hard_placements();
    let world = world_of(&positions, &triangles, &placements);
    let lights: Vec<RenderLight> = placements
        .iter()
        .flat_map(|(to_render, _)| lights_around(to_render.translation.into()))
        .collect();
    assert!(
        lights.len() > 32,
        "the lights span more than one group of 32"
    );
    let points = hard_points(&positions, &triangles, &placements);
    let (gpu_light, gpu_rays, exact) = gpu_direct_light(&mut gpu, &world, &lights, &points);
    let lanes = LightLanes::new(&lights);
    let (mut cpu_rays, mut lit, mut shadowed) = (0, 0, 0);
    for (point, gpu_value) in points.iter().zip(&gpu_light) {
        let (cpu_value, rays) = whitted::direct_light(point, &lanes, &world);
        cpu_rays += rays;
        lit += (cpu_value != Vec3::ZERO) as usize;
        shadowed += (rays > 0 && cpu_value == Vec3::ZERO) as usize;
        if exact {
            assert_eq!(*gpu_value, cpu_value, "{point:?}");
        } else {
            let error = (*gpu_value - cpu_value).abs().max_element();
            assert!(
                error <= 1e-4 * cpu_value.max_element().max(1e-6),
                "{point:?}: {gpu_value} against {cpu_value}"
            );
        }
    }
    assert_eq!(gpu_rays, cpu_rays);
    assert!(
        lit > points.len() / 4,
        "too few points lit: {lit} of {}",
        points.len()
    );
    assert!(shadowed > 0, "no point is in full shadow");
}

/// Lights so faint that their terms fall below f32's smallest normal: the
/// adapter may flush such a term to zero (and then trace no segment for
/// it) where the CPU keeps it, and must give the CPU's bits everywhere
/// else.
#[test]
fn denormal_terms_are_the_cpus_or_flushed() {
    let Some(mut gpu) = gpu() else { return };
    let (positions, triangles) = cube(2);
    let placements = [(Affine3A::IDENTITY, false)];
    let world = world_of(&positions, &triangles, &placements);
    let faint = |intensity: f32, at: DVec3| {
        let light = Light {
            name: None,
            kind: LightKind::Point,
            color: Vec3::ONE,
            intensity,
            range: None,
            radius: None,
            group: None,
        };
        RenderLight::place(&light, DMat4::from_translation(at), DVec3::ZERO, 0.0)
    };
    let lights = [
        faint(1e-36, DVec3::new(0.0, 3.0, 0.0)),
        faint(4e-38, DVec3::new(3.0, 0.5, 0.0)),
        faint(1.0, DVec3::new(0.0, 0.0, 4.0)),
    ];
    let points = hard_points(&positions, &triangles, &placements);
    let (gpu_light, _, exact) = gpu_direct_light(&mut gpu, &world, &lights, &points);
    let lanes = LightLanes::new(&lights);
    // What the faint lights alone bring.
    let faint_only = LightLanes::new(&lights[..2]);
    let mut tiny = 0;
    for (point, gpu_value) in points.iter().zip(&gpu_light) {
        let (cpu_value, _) = whitted::direct_light(point, &lanes, &world);
        let (faint_value, _) = whitted::direct_light(point, &faint_only, &world);
        tiny +=
            (faint_value != Vec3::ZERO && faint_value.max_element() < f32::MIN_POSITIVE) as usize;
        let difference = (*gpu_value - cpu_value).abs().max_element();
        if exact {
            assert!(
                *gpu_value == cpu_value || difference <= f32::MIN_POSITIVE,
                "{point:?}: {gpu_value} against {cpu_value}"
            );
        } else {
            assert!(difference <= 1e-4 * cpu_value.max_element().max(f32::MIN_POSITIVE));
        }
    }
    assert!(tiny > 0, "no term is denormal on the CPU");
}

/// Renders `scene` in `dir` on `backend` with `args`; the frames' paths.
fn render(dir: &Path, scene: &Path, backend: &str, frames: &str, args: &[&str]) -> Vec<Image> {
    try_render(dir, scene, backend, frames, args)
        .unwrap_or_else(|stderr| panic!("{backend}: {stderr}"))
}

/// [`render`], or the run's stderr where it failed.
fn try_render(
    dir: &Path,
    scene: &Path,
    backend: &str,
    frames: &str,
    args: &[&str],
) -> Result<Vec<Image>, String> {
    let out = dir.join(format!("{backend}.####.exr"));
    let scene = scene.to_str().expect("UTF-8 path");
    let out_arg = out.to_str().expect("UTF-8 path");
    let mut all = vec![
        scene,
        "--backend",
        backend,
        "--frames",
        frames,
        "--out",
        out_arg,
        "--exr-float",
        "--no-cache",
        "--quiet",
    ];
    all.extend(args);
    // As on a farm node or in a container: no desktop session. A quiet
    // run prints nothing there either (no Vulkan layer's complaint).
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args(&all)
        .current_dir(dir)
        .env_remove("XDG_RUNTIME_DIR")
        .output()
        .expect("run lmanim");
    let stderr = String::from_utf8_lossy(&run.stderr);
    if !run.status.success() {
        return Err(stderr.into_owned());
    }
    assert!(stderr.is_empty(), "{backend} --quiet printed: {stderr}");
    let frames: Vec<String> = std::fs::read_dir(dir)
        .expect("dir")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|name| name.starts_with(&format!("{backend}.")) && name.ends_with(".exr"))
        .collect();
    let mut frames = frames;
    frames.sort();
    assert!(!frames.is_empty());
    Ok(frames
        .iter()
        .map(|name| read_exr(&dir.join(name)).expect("read EXR"))
        .collect())
}

/// Share of pixels whose every channel is within 1e-3 relative of the
/// other image's (absolute below 1e-6, where relative means nothing).
fn agreeing_share(a: &Image, b: &Image) -> f64 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let close = |x: f32, y: f32| (x - y).abs() <= 1e-3 * x.abs().max(y.abs()).max(1e-3);
    let agreeing = (a.pixels.iter().zip(&b.pixels))
        .filter(|(p, q)| (0..4).all(|k| close(p[k], q[k])))
        .count();
    agreeing as f64 / a.pixels.len() as f64
}

/// Renders on both backends and holds the GPU to the CPU: at least 99.9%
/// of pixels within 1e-3, and the same bits where the adapter has f64 (the
/// queries then answer alike, and everything else is the same code).
fn assert_backends_agree(scene: &Path, frames: &str, args: &[&str]) {
    assert_backends_agree_within(scene, frames, args, LoopBudget::MustSuffice);
}

/// Whether a run may find its shader loops cut short on a software
/// adapter (`GpuError::LoopsCutShort`): lavapipe ends them after 65,535
/// iterations per invocation, and a frame that needs more is refused.
#[derive(PartialEq)]
enum LoopBudget {
    MustSuffice,
    MayRunOut,
}

/// [`assert_backends_agree`]; under `MayRunOut`, a software adapter may
/// refuse the frame instead, with the error that says why (never a wrong
/// frame), while a hardware one must still render it.
fn assert_backends_agree_within(scene: &Path, frames: &str, args: &[&str], budget: LoopBudget) {
    let Some(gpu) = gpu() else { return };
    let exact = gpu.rounds_as_the_cpu();
    let dir = tempfile::tempdir().expect("tempdir");
    let cpu_frames = render(dir.path(), scene, "cpu", frames, args);
    let gpu_frames = match try_render(dir.path(), scene, "gpu", frames, args) {
        Ok(frames) => frames,
        Err(stderr) if budget == LoopBudget::MayRunOut && gpu.is_software() => {
            eprintln!(
                "{} {args:?}: the software adapter ran out of loop budget",
                scene.display()
            );
            assert!(
                stderr.contains("cut the light mesh's shader loops short"),
                "{stderr}"
            );
            assert_eq!(stderr.trim().lines().count(), 1, "one line: {stderr}");
            return;
        }
        Err(stderr) => panic!("gpu: {stderr}"),
    };
    assert_eq!(cpu_frames.len(), gpu_frames.len());
    for (cpu, gpu) in cpu_frames.iter().zip(&gpu_frames) {
        let share = agreeing_share(cpu, gpu);
        assert!(
            share >= 0.999,
            "{}: {share} of pixels agree",
            scene.display()
        );
        if exact {
            assert_eq!(cpu.pixels, gpu.pixels, "{}", scene.display());
        }
    }
}

fn sample(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("animations")
        .join(name)
}

#[test]
fn courtyard_whitted_frames_match_the_cpu() {
    // Mirror and glass spheres (the Whitted recursion), three lamps, a
    // rolling ball over three frames; 14 400 samples, so the compaction of
    // the recursion's rays sums over hundreds of workgroups.
    let args = ["--method", "whitted", "--width", "160", "--height", "90"];
    assert_backends_agree(&sample("courtyard.gltf"), "0..3", &args);
}

#[test]
fn courtyard_area_lamps_match_the_cpu() {
    let args = [
        "--method", "area", "--spp", "4", "--width", "48", "--height", "27",
    ];
    assert_backends_agree(&sample("courtyard.gltf"), "0", &args);
}

#[test]
fn skinned_and_morphing_animations_match_the_cpu() {
    let dir = tempfile::tempdir().expect("tempdir");
    let args = ["--method", "whitted", "--width", "48", "--height", "32"];
    assert_backends_agree(&anim_support::skinned(dir.path()), "0..4", &args);
    assert_backends_agree(&anim_support::morph(dir.path()), "0..4", &args);
}

/// The background and the ambient sky on both backends: the sky on every
/// surface's diffuse part, at every depth of the recursion, and the
/// background where camera samples miss (two samples a pixel, so edge
/// pixels mix the two); the frames are also checked to have changed.
#[test]
fn background_and_ambient_sky_match_the_cpu() {
    let dir = tempfile::tempdir().expect("tempdir");
    let settings = dir.path().join("environment.ron");
    std::fs::write(
        &settings,
        "(background: Some((0.2, 0.3, 0.5)), ambient: Some((0.05, 0.06, 0.08)))",
    )
    .expect("write settings");
    let settings = settings.to_str().expect("UTF-8 path");
    for method in ["whitted", "area", "lmm1"] {
        let args = [
            "--method", method, "--spp", "2", "--width", "40", "--height", "24",
        ];
        let with = [&args[..], &["--settings", settings]].concat();
        assert_backends_agree(&sample("courtyard.gltf"), "0", &with);
        let plain = tempfile::tempdir().expect("tempdir");
        let lit = render(plain.path(), &sample("courtyard.gltf"), "cpu", "0", &with);
        let unlit = render(plain.path(), &sample("courtyard.gltf"), "cpu", "0", &args);
        let changed = (lit[0].pixels.iter().zip(&unlit[0].pixels))
            .filter(|(a, b)| a != b)
            .count();
        assert!(
            changed > lit[0].pixels.len() / 2,
            "{method}: {changed} changed"
        );
        assert!(lit[0].pixels.iter().all(|p| p.w == 1.0), "{method}: opaque");
    }
}

/// The sample courtyard as `edit` changes it, written to `dir/name`.
fn courtyard_variant(
    dir: &Path,
    name: &str,
    edit: impl FnOnce(&mut serde_json::Value),
) -> std::path::PathBuf {
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(sample("courtyard.gltf")).expect("read"))
            .expect("JSON");
    edit(&mut doc);
    let path = dir.join(name);
    std::fs::write(&path, doc.to_string()).expect("write");
    path
}

/// The courtyard seen through an orthographic camera.
fn orthographic_courtyard(dir: &Path) -> std::path::PathBuf {
    courtyard_variant(dir, "orthographic.gltf", |doc| {
        doc["cameras"][0] = serde_json::json!({
            "type": "orthographic",
            "orthographic": { "xmag": 8.0, "ymag": 4.5, "znear": 0.1, "zfar": 100.0 }
        });
    })
}

/// Camera rays made on the GPU are the CPU's: at 5 samples per pixel
/// (four strata and one free sample, each drawn from the CPU's PCG32
/// streams), through the perspective camera and an orthographic one.
#[test]
fn jittered_samples_and_orthographic_cameras_match_the_cpu() {
    let dir = tempfile::tempdir().expect("tempdir");
    let args = [
        "--method", "whitted", "--spp", "5", "--width", "40", "--height", "24",
    ];
    assert_backends_agree(&sample("courtyard.gltf"), "0", &args);
    assert_backends_agree(&orthographic_courtyard(dir.path()), "0", &args);
}

/// The courtyard with textures: a checker as the base colour of stone,
/// plaster and wood (nearest and linear filtering, repeat and mirrored
/// repeat), and as the emission of the blue paint.
fn textured_courtyard(dir: &Path) -> std::path::PathBuf {
    let checker = image::RgbaImage::from_fn(8, 8, |x, y| {
        if (x + y) % 2 == 0 {
            image::Rgba([230, 200, 120, 255])
        } else {
            image::Rgba([40, 90, 160, 255])
        }
    });
    checker.save(dir.join("checker.png")).expect("write PNG");
    courtyard_variant(dir, "textured.gltf", |doc| {
        doc["images"] = serde_json::json!([{ "uri": "checker.png" }]);
        doc["samplers"] = serde_json::json!([
            { "magFilter": 9728, "minFilter": 9728, "wrapS": 10497, "wrapT": 10497 },
            { "magFilter": 9729, "minFilter": 9729, "wrapS": 33648, "wrapT": 33648 },
        ]);
        doc["textures"] =
            serde_json::json!([{ "source": 0, "sampler": 0 }, { "source": 0, "sampler": 1 }]);
        let materials = doc["materials"].as_array_mut().expect("materials");
        for (index, material) in materials.iter_mut().enumerate() {
            match material["name"].as_str() {
                Some("Stone" | "Plaster" | "Wood") => {
                    material["pbrMetallicRoughness"]["baseColorTexture"] =
                        serde_json::json!({ "index": index % 2 });
                }
                Some("BluePaint") => {
                    material["emissiveTexture"] = serde_json::json!({ "index": 1 });
                    material["emissiveFactor"] = serde_json::json!([0.5, 0.5, 0.5]);
                }
                _ => {}
            }
        }
    })
}

#[test]
fn a_textured_model_matches_the_cpu() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = textured_courtyard(dir.path());
    let args = ["--method", "whitted", "--width", "64", "--height", "36"];
    assert_backends_agree(&scene, "0", &args);
}

/// Camera rays through every pixel centre of `placed`'s camera, and the
/// mirror and glass rays of the points they hit, as the CPU makes them.
fn camera_and_secondary_rays(
    scene: &SceneDesc,
    placed: &FrameScene,
    world: &World,
    (width, height): (u32, u32),
) -> Vec<Ray> {
    let film_rays = placed.camera.film(width, height);
    let mut rays: Vec<Ray> = (0..width * height)
        .map(|i| {
            let film = Vec2::new((i % width) as f32 + 0.5, (i / width) as f32 + 0.5);
            film_rays.through(film)
        })
        .collect();
    let secondary: Vec<Ray> = (rays.iter())
        .filter_map(|ray| {
            let hit = world.closest_hit(ray)?;
            Some(ShadingPoint::from_hit(
                scene,
                placed,
                ray,
                &hit,
                0,
                Vec3::ONE,
                0,
            ))
        })
        .flat_map(|point| secondary_rays(&point).map(|s| s.ray).collect::<Vec<_>>())
        .collect();
    rays.extend(secondary);
    rays
}

/// Shading points made on the GPU are the CPU's, field for field, on every
/// camera and Whitted ray of the courtyard (mirror, glass, a rolling
/// ball), the textured courtyard (base colour and emissive textures,
/// repeat and mirrored repeat, nearest and linear) and skinned and
/// morphing meshes over several frames: to the bit where the adapter has
/// f64, within float noise where it has not.
#[test]
fn shading_points_made_on_the_gpu_are_the_cpus() {
    let Some(mut gpu) = gpu() else { return };
    let exact = gpu.rounds_as_the_cpu();
    let dir = tempfile::tempdir().expect("tempdir");
    let scenes = [
        (sample("courtyard.gltf"), vec![0.0, 0.5]),
        (textured_courtyard(dir.path()), vec![0.0]),
        (anim_support::skinned(dir.path()), vec![0.0, 0.3, 0.7]),
        (anim_support::morph(dir.path()), vec![0.0, 0.4]),
    ];
    let settings = Settings::default();
    let size = (64, 36);
    for (path, times) in scenes {
        let mut sequence = Sequence::load(&path).expect("load");
        let mut world: Option<World> = None;
        for time in times {
            let placed = sequence
                .advance(time, &settings, &mut Default::default())
                .expect("place");
            let world = world.get_or_insert_with(|| placed.build_world(sequence.scene()));
            FrameDelta::first(&placed).update_world(world, &placed);
            let scene = sequence.scene();
            let rays = camera_and_secondary_rays(scene, &placed, world, size);
            let job = FrameJob {
                scene,
                frame: &placed,
                world,
                width: size.0,
                height: size.1,
                spp: 1,
                max_depth: settings.max_depth,
                environment: settings.environment(),
                aovs: &[],
                shadows: &Default::default(),
            };
            let gpu_points = gpu.shading_points(&job, &rays).expect("GPU points");
            let mut hits = 0;
            for (ray, gpu_point) in rays.iter().zip(&gpu_points) {
                let cpu_point = world
                    .closest_hit(ray)
                    .map(|hit| ShadingPoint::from_hit(scene, &placed, ray, &hit, 0, Vec3::ONE, 0));
                hits += cpu_point.is_some() as usize;
                let at = format!("{} at {time}: {ray:?}", path.display());
                if exact {
                    assert_eq!(*gpu_point, cpu_point, "{at}");
                } else if let (Some(g), Some(c)) = (gpu_point, cpu_point) {
                    assert!((g.position - c.position).length() < 1e-4, "{at}");
                    assert!(
                        (g.material.base_color - c.material.base_color).length() < 1e-3,
                        "{at}"
                    );
                }
            }
            assert!(hits > 100, "{}: {hits} hits", path.display());
        }
    }
}

/// Work the device refuses (here a buffer beyond its limit) is an error
/// naming what failed, not wgpu's panic.
#[test]
fn work_the_device_refuses_is_an_error() {
    let Some(mut gpu) = gpu() else { return };
    let passes = gpu.passes_for(&World::build(&[])).expect("upload");
    let context = passes.context;
    let too_large = context.limits.max_buffer_size + 4;
    let refused = context.checked("a test buffer", || {
        Ok(context.device.create_buffer(&wgpu::BufferDescriptor {
            label: None,
            size: too_large,
            usage: wgpu::BufferUsages::STORAGE,
            mapped_at_creation: false,
        }))
    });
    match refused {
        Err(error @ GpuError::Refused { .. }) => {
            let message = error.to_string();
            assert!(message.contains("a test buffer"), "{message}");
            assert!(!message.contains('\n'), "{message}");
        }
        other => panic!("expected a refusal, got {other:?}"),
    }
}

#[test]
fn the_same_frame_twice_is_the_same_bits() {
    if gpu().is_none() {
        return;
    }
    let args = [
        "--method", "area", "--spp", "2", "--width", "48", "--height", "27",
    ];
    let dir = tempfile::tempdir().expect("tempdir");
    let first = render(dir.path(), &sample("courtyard.gltf"), "gpu", "5", &args);
    let second_dir = tempfile::tempdir().expect("tempdir");
    let second = render(
        second_dir.path(),
        &sample("courtyard.gltf"),
        "gpu",
        "5",
        &args,
    );
    assert_eq!(first[0].pixels, second[0].pixels);
}

#[test]
fn no_adapter_is_one_clear_line_and_exit_1() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = sample("courtyard.gltf");
    let run = std::process::Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args([
            scene.to_str().expect("UTF-8"),
            "--backend",
            "gpu",
            "--method",
            "whitted",
        ])
        .current_dir(dir.path())
        // No Vulkan driver, and no other backend to fall back on.
        .env("VK_ICD_FILENAMES", "/nonexistent.json")
        .env("VK_DRIVER_FILES", "/nonexistent.json")
        .env("WGPU_BACKEND", "vulkan")
        .output()
        .expect("run lmanim");
    let stderr = String::from_utf8_lossy(&run.stderr);
    let ours: Vec<&str> = stderr.lines().filter(|l| l.starts_with("lmanim")).collect();
    assert_eq!(run.status.code(), Some(1), "{stderr}");
    assert_eq!(ours.len(), 1, "{stderr}");
    assert!(ours[0].contains("no GPU adapter"), "{stderr}");
    assert!(ours[0].contains("mesa-vulkan-drivers"), "{stderr}");
    assert!(!stderr.contains("panicked"), "{stderr}");
}

/// The light-mesh methods on `--backend gpu` from the command line: the
/// frame is written, and the run reports the adapter it ran on.
#[test]
fn light_mesh_methods_render_on_the_gpu_from_the_command_line() {
    if gpu().is_none() {
        return;
    }
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = sample("courtyard.gltf");
    let args = [
        scene.to_str().expect("UTF-8"),
        "--backend",
        "gpu",
        "--method",
        "lmm1",
        "--width",
        "32",
        "--height",
        "18",
        "--out",
        "out.####.exr",
    ];
    let run = lmanim(&args, dir.path());
    let stderr = String::from_utf8_lossy(&run.stderr);
    assert!(run.status.success(), "{stderr}");
    assert!(dir.path().join("out.0000.exr").is_file());
}

/// A city block with 64 street lamps (two words of lights per node mask)
/// and cars in the dynamic layer, over two frames (the second reuses the
/// first's masks): LMM1 and LMM frames on the GPU, shaded by formula (2)
/// from its resident mask pool, are the CPU's, with the paper's fixed
/// radius and with penumbrae sized by their blockers. The latter traces
/// a level's segments for each lamp a point's set disagrees on: more loop
/// iterations than lavapipe allows an invocation, so there the frame is
/// refused in one line (on a hardware adapter it must match).
#[test]
fn city_light_mesh_frames_with_64_lamps_match_the_cpu() {
    let dir = tempfile::tempdir().expect("tempdir");
    let city = dir.path().join("city64.glb");
    let params = CityParams {
        blocks: 4,
        lamps: 64,
        cars: 3,
        ..CityParams::default()
    };
    city_block(&params)
        .and_then(|builder| builder.write_glb(&city))
        .expect("city");
    for method in ["lmm1", "lmm"] {
        let size = ["--method", method, "--width", "64", "--height", "36"];
        let fixed = [&size[..], &["--penumbra", "fixed"]].concat();
        assert_backends_agree(&city, "0..2", &fixed);
        let blocker = [&size[..], &["--penumbra", "blocker"]].concat();
        assert_backends_agree_within(&city, "0..2", &blocker, LoopBudget::MayRunOut);
    }
    // The default: most of the 64 lamps are faint at most points
    // (`lightmesh::faint`), and both backends find the same ones; and with
    // none faint, every lamp's penumbra sized.
    let wide = ["--method", "lmm1", "--width", "64", "--height", "36"];
    assert_backends_agree_within(&city, "0..2", &wide, LoopBudget::MayRunOut);
    let every_lamp = [&wide[..], &["--penumbra", "blocker", "--faint-lamps", "0"]].concat();
    assert_backends_agree_within(&city, "0..2", &every_lamp, LoopBudget::MayRunOut);
    // The courtyard's three lamps fit every adapter's budget with none
    // faint: the coverage pass keeps them all without weighing them.
    let courtyard = ["--method", "lmm1", "--width", "48", "--height", "27"];
    let every_lamp = [&courtyard[..], &["--faint-lamps", "0"]].concat();
    assert_backends_agree(&sample("courtyard.gltf"), "0", &every_lamp);
}

/// The courtyard by LMM1 at 64×36 with h = 0.1 m.
fn courtyard_lmm1() -> Settings {
    let mut settings = Settings {
        width: 64,
        height: 36,
        method: Method::Lmm1,
        ..Settings::default()
    };
    settings.lightmesh.h = Some(0.1);
    settings
}

/// The courtyard's frames at `times` (one sequence, masks reused) by
/// [`courtyard_lmm1`] on `backend`, whose mask pool (on a GPU backend)
/// may take `limit` bytes: each image with the light mesh's stats, or the
/// refusal's message.
fn courtyard_frames_with_mask_pool(
    backend: &mut Backend,
    limit: usize,
    times: &[f64],
) -> Result<Vec<(Image, LightMeshStats)>, String> {
    backend.limit_mask_memory(limit);
    let settings = courtyard_lmm1();
    let mut sequence = Sequence::load(&sample("courtyard.gltf")).expect("courtyard");
    let mut frames = Vec::new();
    for &time in times {
        let mut stats = FrameStats::default();
        let placed = (sequence.advance(time, &settings, &mut stats)).expect("camera");
        let image = sequence
            .render(backend, &placed, &settings, &mut stats)
            .map_err(|error| error.to_string())?;
        frames.push((image, stats.lightmesh.expect("light-mesh stats")));
    }
    Ok(frames)
}

/// The courtyard's first frame, as [`courtyard_frames_with_mask_pool`].
fn courtyard_with_mask_pool(
    backend: &mut Backend,
    limit: usize,
) -> Result<(Image, LightMeshStats), String> {
    let mut frames = courtyard_frames_with_mask_pool(backend, limit, &[0.0])?;
    Ok(frames.remove(0))
}

/// The pool's slots hold the store's bricks word for word after every
/// frame, while the ball rolls (its swept bits invalidated, refilled)
/// and the camera level, the mirror's and the glass's read bricks; frames
/// after the first send the words their bricks changed, not the bricks.
#[test]
fn the_mask_pool_holds_the_stores_bricks_after_every_frame() {
    let Some(gpu) = gpu() else { return };
    let mut backend = Backend::Gpu(Box::new(gpu));
    let settings = courtyard_lmm1();
    let mut sequence = Sequence::load(&sample("courtyard.gltf")).expect("courtyard");
    let slot_bytes = MaskPool::slot_bytes(1) as u64;
    for frame in 0..4 {
        let time = frame as f64 / 24.0;
        let mut stats = FrameStats::default();
        let placed = (sequence.advance(time, &settings, &mut stats)).expect("camera");
        sequence
            .render(&mut backend, &placed, &settings, &mut stats)
            .expect("frame");
        assert!(sequence.light_mesh().is_some(), "a light mesh");
        common::gpu::assert_pool_holds_the_store(&backend, &sequence, frame);
        let bricks = stats.lightmesh.expect("light-mesh stats").bricks_uploaded;
        let bytes_up = stats.gpu.expect("GPU stats").traffic.bytes_up;
        if frame > 0 {
            // The whole frame's uploads (points, segments, uniforms
            // included) take less than its bricks would have.
            assert!(bricks > 0, "frame {frame} changed no brick");
            let whole = bricks * slot_bytes;
            assert!(
                bytes_up < whole,
                "frame {frame}: {bytes_up} bytes up, bricks {whole}"
            );
        }
    }
}

/// A fill without shafts makes a segment for every missing bit: the
/// courtyard's frames (the ball rolling, masks reused) come out the same
/// bits as with them, with no shaft tested and more segments traced.
#[test]
fn a_fill_without_shafts_renders_the_same_frames() {
    let times = [0.0, 1.0 / 24.0, 2.0 / 24.0];
    let mut frames = Vec::new();
    for shafts in [Shafts::Test, Shafts::Skip] {
        let Some(gpu) = gpu() else { return };
        let mut backend = Backend::Gpu(Box::new(gpu));
        backend.set_fill_shafts(shafts);
        let limit = 256 << 20;
        frames.push(courtyard_frames_with_mask_pool(&mut backend, limit, &times).expect("frames"));
    }
    let (with, without) = (&frames[0], &frames[1]);
    for (frame, ((image, stats), (image_without, stats_without))) in
        with.iter().zip(without).enumerate()
    {
        assert!(image == image_without, "frame {frame} differs");
        assert_eq!(stats_without.fill_shafts, 0, "frame {frame}");
        assert_eq!(
            stats_without.bits_computed, stats.bits_computed,
            "frame {frame}"
        );
        if frame == 0 {
            assert!(stats.fill_shafts > 0, "{stats:?}");
            assert!(stats_without.fill_segments > stats.fill_segments);
        }
    }
}

/// LMM1's enclosure probes on the GPU give the CPU's flag at every node
/// of twelve bricks around a box resting on a floor and a tilted box
/// beside it: nodes inside, outside, under the floor, and on the boxes'
/// faces and the floor's plane (the lattice puts nodes on them, where
/// probes graze the faces they start on).
#[test]
fn gpu_enclosure_probes_give_the_cpus_flags() {
    let Some(mut gpu) = gpu() else { return };
    if !gpu.rounds_as_the_cpu() {
        eprintln!("skipped: {} does not round as the CPU does", gpu.adapter());
        return;
    }
    let (positions, triangles) = cube(2);
    let floor = [
        Vec3::new(-3.0, 0.0, -3.0),
        Vec3::new(-3.0, 0.0, 3.0),
        Vec3::new(3.0, 0.0, 3.0),
        Vec3::new(3.0, 0.0, -3.0),
    ];
    let object = |positions, triangles, to_render| WorldObject {
        positions,
        triangles,
        to_render,
        dynamic: false,
    };
    let tilt = Quat::from_axis_angle(Vec3::new(1.0, 0.0, 1.0).normalize(), 0.5);
    let world = World::build(&[
        object(&floor, &[[0, 1, 2], [0, 2, 3]], Affine3A::IDENTITY),
        object(
            &positions,
            &triangles,
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.5),
                Quat::IDENTITY,
                Vec3::new(-0.3, 0.5, -0.3),
            ),
        ),
        object(
            &positions,
            &triangles,
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.25),
                tilt,
                Vec3::new(0.45, 0.3, 0.4),
            ),
        ),
    ]);
    let lattice = Lattice::new(0.1);
    let reach = 0.8;
    let bricks: Vec<IVec3> = (0..12)
        .map(|i: i32| IVec3::new(i % 2 - 1, i / 2 % 3 - 1, i / 6 - 1))
        .collect();
    let probes = ProbeList {
        bricks: vec![(0..BRICK_NODES as u16).collect(); bricks.len()],
        reused: 0,
    };
    let on_cpu: Vec<bool> = (probes.nodes())
        .map(|(brick, slot)| {
            let at = lattice.node_position(masks::join(bricks[brick], slot as usize));
            enclosure::is_enclosed(&world, at, reach)
        })
        .collect();
    let passes = gpu.passes_for(&world).expect("upload");
    let on_gpu = (passes.probes)
        .trace(
            passes.context,
            passes.scene,
            (&lattice, reach),
            &bricks,
            &probes,
        )
        .expect("GPU probes");
    let enclosed = on_cpu.iter().filter(|&&enclosed| enclosed).count();
    assert!(
        enclosed > 500 && enclosed < on_cpu.len() - 500,
        "{enclosed} of {} nodes enclosed",
        on_cpu.len()
    );
    let differing: Vec<IVec3> = (probes.nodes().zip(on_cpu.iter().zip(&on_gpu)))
        .filter(|(_, (cpu, gpu))| cpu != gpu)
        .map(|((brick, slot), _)| masks::join(bricks[brick], slot as usize))
        .collect();
    assert!(differing.is_empty(), "flags differ at nodes {differing:?}");
}

/// The courtyard's frames (the ball rolling, masks reused) are the same
/// images whether LMM1's probes run on the CPU or the GPU, which probes
/// the same nodes and writes their flags into the pool as the store
/// records them; with the probes on the GPU, no brick goes up for a flag.
#[test]
fn enclosure_probes_on_the_gpu_render_the_same_frames() {
    let settings = courtyard_lmm1();
    let mut frames = Vec::new();
    for site in [ProbeSite::Cpu, ProbeSite::Gpu] {
        let Some(mut gpu) = gpu() else { return };
        if !gpu.rounds_as_the_cpu() {
            eprintln!("skipped: {} does not round as the CPU does", gpu.adapter());
            return;
        }
        gpu.set_probe_site(site);
        let mut backend = Backend::Gpu(Box::new(gpu));
        let mut sequence = Sequence::load(&sample("courtyard.gltf")).expect("courtyard");
        let mut rendered = Vec::new();
        for frame in 0..3 {
            let mut stats = FrameStats::default();
            let time = frame as f64 / 24.0;
            let placed = (sequence.advance(time, &settings, &mut stats)).expect("camera");
            let image =
                (sequence.render(&mut backend, &placed, &settings, &mut stats)).expect("frame");
            common::gpu::assert_pool_holds_the_store(&backend, &sequence, frame);
            rendered.push((image, stats.lightmesh.expect("light-mesh stats")));
        }
        frames.push(rendered);
    }
    let (on_cpu, on_gpu) = (&frames[0], &frames[1]);
    for (frame, ((image, stats), (gpu_image, gpu_stats))) in on_cpu.iter().zip(on_gpu).enumerate() {
        assert!(image == gpu_image, "frame {frame} differs");
        assert_eq!(gpu_stats.nodes_probed, stats.nodes_probed, "frame {frame}");
        assert_eq!(
            gpu_stats.enclosure_reused, stats.enclosure_reused,
            "frame {frame}"
        );
    }
    assert!(on_cpu[0].1.nodes_probed > 0, "the first frame probes");
    let uploaded = |frames: &[(Image, LightMeshStats)]| -> u64 {
        frames.iter().map(|(_, stats)| stats.bricks_uploaded).sum()
    };
    assert!(
        uploaded(on_gpu) < uploaded(on_cpu),
        "bricks up: {} with the GPU's probes, {} with the CPU's",
        uploaded(on_gpu),
        uploaded(on_cpu)
    );
}

/// A mask pool smaller than the frame's bricks evicts bricks no level
/// reads and gives the unbounded pool's image; one smaller than a single
/// level's bricks refuses the frame, naming h and the setting to raise.
/// The courtyard's mirror and glass levels read bricks its camera level
/// does not, so the smallest pool that serves the frame must evict.
#[test]
fn a_small_mask_pool_evicts_without_changing_the_image_or_refuses_clearly() {
    let Some(gpu) = gpu() else { return };
    let exact = gpu.rounds_as_the_cpu();
    let mut backend = Backend::Gpu(Box::new(gpu));
    let (reference, unbounded) =
        courtyard_with_mask_pool(&mut backend, usize::MAX).expect("unbounded pool");
    assert_eq!(unbounded.bricks_evicted, 0);
    if exact {
        let mut cpu = Backend::new(BackendKind::Cpu, Some(2)).expect("CPU backend");
        let (on_cpu, _) = courtyard_with_mask_pool(&mut cpu, 0).expect("CPU frame");
        assert_eq!(reference, on_cpu, "the GPU's frame is the CPU's");
    }
    // Bisect for the smallest pool that serves the frame: `refused`
    // bricks are too few, `served` enough.
    // One u32 of lights per node group: the courtyard has a few lamps.
    let slot = MaskPool::slot_bytes(1);
    let (mut refused, mut served) = (0, unbounded.bricks_uploaded as usize);
    let mut smallest = None;
    while served - refused > 1 {
        let slots = (refused + served) / 2;
        match courtyard_with_mask_pool(&mut backend, slots * slot) {
            Ok((image, stats)) => {
                assert_eq!(image, reference, "a pool of {slots} bricks");
                (served, smallest) = (slots, Some(stats));
            }
            Err(message) => {
                assert!(
                    message.contains("h = 0.1 m") && message.contains("lightmesh.gpu_memory_mib"),
                    "{message}"
                );
                refused = slots;
            }
        }
    }
    let smallest = smallest.expect("a pool smaller than every upload serves the frame");
    assert!(refused > 0, "even a one-brick pool served the frame");
    assert!(
        smallest.bricks_evicted > 0,
        "a pool of {served} bricks served the frame without evicting"
    );
    // Over the rolling ball's frames, with the smallest pool (a little
    // larger) that serves them all: later frames read most bricks
    // resident (points the pool serves, whose bricks must not be
    // evicted), admit the others and evict.
    if exact {
        let times = [0.0, 1.0 / 24.0, 2.0 / 24.0];
        let mut cpu = Backend::new(BackendKind::Cpu, Some(2)).expect("CPU backend");
        let on_cpu = courtyard_frames_with_mask_pool(&mut cpu, 0, &times).expect("CPU frames");
        let evicting = (0..8)
            .filter_map(|step| {
                let slots = served + step * served / 16;
                courtyard_frames_with_mask_pool(&mut backend, slots * slot, &times).ok()
            })
            .find(|frames| {
                frames[1..]
                    .iter()
                    .any(|(_, stats)| stats.bricks_evicted > 0)
            })
            .expect("a pool that serves every frame by evicting");
        for (time, ((gpu, stats), (cpu, _))) in times.iter().zip(evicting.iter().zip(&on_cpu)) {
            assert_eq!(gpu, cpu, "t = {time}");
            if *time > 0.0 {
                assert!(stats.points_demanded > 0 && stats.bricks_uploaded > 0);
            }
        }
    }
}

/// The fill on the GPU settles groups with the CPU's shafts and traces
/// each bit left as its own segment; the CPU's also remembers walls and
/// hides whole boxes behind one wall. Over every node of eight bricks and
/// 130 lights (every kind, one inside a dynamic box, some behind a wall
/// that hides whole bricks, shadow edges across bricks), both layers'
/// bits and validity are the same, brick for brick.
#[test]
fn gpu_fill_bits_equal_the_cpu_fill() {
    let Some(mut gpu) = gpu() else { return };
    let exact = gpu.rounds_as_the_cpu();
    // A floor slab, a dynamic box, and a wall of one large triangle at
    // x = 0.9 (one triangle, so it can hide a whole brick at once).
    let (positions, triangles) = cube(4);
    let wall = [
        Vec3::new(0.9, -1.0, -8.0),
        Vec3::new(0.9, -1.0, 8.0),
        Vec3::new(0.9, 8.0, 0.0),
    ];
    let spin = Quat::from_axis_angle(Vec3::new(1.0, 1.0, 0.0).normalize(), 0.6);
    let object = |positions, triangles, to_render, dynamic| WorldObject {
        positions,
        triangles,
        to_render,
        dynamic,
    };
    let world = World::build(&[
        object(
            &positions,
            &triangles,
            Affine3A::from_scale_rotation_translation(
                Vec3::new(3.0, 0.05, 3.0),
                Quat::IDENTITY,
                Vec3::new(0.0, -1.2, 0.0),
            ),
            false,
        ),
        object(&wall, &[[0, 1, 2]], Affine3A::IDENTITY, false),
        object(
            &positions,
            &triangles,
            Affine3A::from_scale_rotation_translation(
                Vec3::splat(0.35),
                spin,
                Vec3::new(-0.7, 0.1, 0.5),
            ),
            true,
        ),
    ]);
    let mut lights = lights_around(Vec3::ZERO);
    let point = Light {
        name: None,
        kind: LightKind::Point,
        color: Vec3::ONE,
        intensity: 5.0,
        range: None,
        radius: Some(0.1),
        group: None,
    };
    let place = |light: &Light, at: Vec3| {
        RenderLight::place(
            light,
            DMat4::from_translation(at.as_dvec3()),
            DVec3::ZERO,
            0.0,
        )
    };
    // One inside the dynamic box, the rest on a ring through the wall.
    lights.push(place(&point, Vec3::new(-0.7, 0.1, 0.5)));
    while lights.len() < 130 {
        let angle = lights.len() as f32 * 0.41;
        let at = Vec3::new(
            2.5 * angle.cos(),
            0.3 + (lights.len() % 5) as f32 * 0.3,
            2.5 * angle.sin(),
        );
        lights.push(place(&point, at));
    }
    let words = lights.len().div_ceil(64);
    let demand = Demand {
        bricks: (0..8)
            .map(|corner: i32| BrickDemand {
                brick: IVec3::new(corner & 1, corner >> 1 & 1, corner >> 2 & 1) - IVec3::ONE,
                needed: vec![u64::MAX >> (64 * words - lights.len()).min(63); BRICK_NODES * words]
                    .into_iter()
                    .enumerate()
                    .map(|(at, last)| {
                        if at % words == words - 1 {
                            last
                        } else {
                            u64::MAX
                        }
                    })
                    .collect(),
            })
            .collect(),
        reach: Vec::new(),
        faint: Vec::new(),
        words,
    };
    let mut on_cpu = LightMesh::new(Lattice::new(0.2), 2.5, lights.len(), 1 << 30);
    let before_fill = on_cpu.clone();
    let mut cpu_stats = LightMeshStats::default();
    on_cpu
        .fill(&demand, &lights, &world, &mut cpu_stats)
        .expect("CPU fill");
    assert!(
        cpu_stats.fill_shafts > 0
            && cpu_stats.fill_hidden_groups > 0
            && cpu_stats.fill_remembered > 0,
        "the CPU fill took every shortcut: {cpu_stats:?}"
    );

    // The fill with shafts (the CPU's, a software adapter's) and without
    // (a GPU's): the same bits.
    let mut segments_with_shafts = 0;
    for shafts in [Shafts::Test, Shafts::Skip] {
        let mut on_gpu = before_fill.clone();
        let fill = on_gpu
            .fill_segments(&demand, &lights, &world, shafts)
            .expect("segments");
        let answers = {
            let passes = gpu.passes_for(&world).expect("upload");
            let frame_lights = FrameLights::upload(passes.context, &lights).expect("lights");
            let bricks: Vec<IVec3> = demand.bricks.iter().map(|brick| brick.brick).collect();
            let place = (&on_gpu.lattice, &bricks[..]);
            let trace = |per_wait| {
                (passes.fill)
                    .trace(
                        passes.context,
                        passes.scene,
                        &frame_lights,
                        place,
                        &fill,
                        per_wait,
                    )
                    .expect("GPU fill")
            };
            let answers = trace(SEGMENTS_PER_WAIT);
            // A fill too big for one wait (a cold frame's tens of millions of
            // segments) is traced in groups, a wait after each but the last:
            // the same answers, in the same order.
            let per_wait = (fill.len() / 3).next_multiple_of(8);
            assert_eq!(trace(per_wait), answers, "in groups of {per_wait}");
            answers
        };
        let mut gpu_stats = LightMeshStats::default();
        on_gpu.merge_segments(&demand, &fill, &answers, &mut gpu_stats);
        assert_eq!(gpu_stats.bits_computed, cpu_stats.bits_computed);
        match shafts {
            Shafts::Test => assert!(
                gpu_stats.fill_shafts > 0
                    && gpu_stats.fill_hidden_groups > 0
                    && gpu_stats.fill_segments > 0,
                "{gpu_stats:?}"
            ),
            // A fill for a GPU traces every bit the shafts and walls
            // settled too.
            Shafts::Skip => assert!(
                gpu_stats.fill_shafts == 0
                    && gpu_stats.fill_hidden_groups == 0
                    && gpu_stats.fill_segments > segments_with_shafts,
                "{gpu_stats:?}"
            ),
        }
        segments_with_shafts = gpu_stats.fill_segments;

        let mut differing = 0usize;
        let mut dynamic_blocked = 0usize;
        for brick in &demand.bricks {
            let (cpu, gpu) = (
                on_cpu.masks().brick(brick.brick),
                on_gpu.masks().brick(brick.brick),
            );
            let (Some(cpu), Some(gpu)) = (cpu, gpu) else {
                panic!("brick {} was not filled", brick.brick);
            };
            differing += cpu
                .iter()
                .zip(gpu)
                .map(|(a, b)| (a ^ b).count_ones() as usize)
                .sum::<usize>();
            for slot in 0..BRICK_NODES {
                let mask = on_cpu.masks().slot_mask(cpu, slot);
                dynamic_blocked += (0..words)
                    .map(|word| mask.dynamic_layer(word).0.count_ones() as usize)
                    .sum::<usize>();
            }
        }
        assert!(dynamic_blocked > 0, "the dynamic box blocks some node");
        if exact {
            assert_eq!(differing, 0, "bits differ between the fills");
        } else {
            assert!(differing * 1000 < answers.len(), "{differing} bits differ");
        }
    }
}

/// The disk cache on the GPU backend: a second run starts from the static
/// bits the first saved (the CPU's light mesh loads them; the pool copies
/// the bricks up) and renders the same frame as the first, and as the CPU.
#[test]
fn gpu_light_mesh_frames_start_from_the_disk_cache() {
    let Some(gpu) = gpu() else { return };
    let exact = gpu.rounds_as_the_cpu();
    let mut backend = Backend::Gpu(Box::new(gpu));
    let cache = tempfile::tempdir().expect("tempdir");
    let settings = courtyard_lmm1();
    let run = |backend: &mut Backend| {
        let mut sequence = Sequence::load(&sample("courtyard.gltf")).expect("courtyard");
        sequence.set_cache_dir(Some(cache.path().to_path_buf()));
        let placed = sequence.place(&settings).expect("camera");
        let mut stats = FrameStats::default();
        let image = (sequence.render(backend, &placed, &settings, &mut stats)).expect("frame");
        sequence.save_cache().expect("cache saved");
        (image, stats.lightmesh.expect("light-mesh stats"))
    };
    let (first, cold) = run(&mut backend);
    let (second, warm) = run(&mut backend);
    assert_eq!(cold.bits_loaded, 0);
    assert!(
        warm.bits_loaded > 0,
        "the second run loads the first's bits"
    );
    assert!(warm.bits_computed < cold.bits_computed);
    assert_eq!(first, second);
    if exact {
        let mut cpu = Backend::new(BackendKind::Cpu, Some(2)).expect("CPU backend");
        let (on_cpu, _) = courtyard_with_mask_pool(&mut cpu, 0).expect("CPU frame");
        assert_eq!(first, on_cpu);
    }
}

/// A pane of glass over a floor, filling the view: every camera point
/// spawns a reflected and a refracted ray, so the next level of a band of
/// 540 672 samples holds more than a batch (2^20 rays). The GPU waits for
/// that level's length (the only waits a Whitted band makes besides its
/// end), splits it into batches, and still gives the CPU's frame.
#[test]
fn a_next_level_over_a_batch_is_split_and_matches_the_cpu() {
    let mut scene = common::empty_scene();
    let floor = common::add_material(&mut scene, common::lambert(Vec3::splat(0.6)));
    let glass = common::add_material(
        &mut scene,
        lmanim::scene::Material {
            roughness: 0.0,
            transmission: 1.0,
            ..common::lambert(Vec3::ONE)
        },
    );
    common::add_quads(&mut scene, &[common::floor_quad(0.0, 40.0)], 1, floor);
    common::add_quads(&mut scene, &[common::floor_quad(0.5, 40.0)], 1, glass);
    common::add_light(
        &mut scene,
        LightKind::Point,
        20.0,
        DMat4::from_translation(DVec3::new(0.3, 2.0, -0.2)),
    );
    common::add_top_camera(&mut scene, 5.0, 2.0);
    let (width, height) = (1024, 528);
    let mut settings = common::settings(width, height);
    settings.method = Method::Whitted;
    let Some((mut gpu, exact)) = common::gpu::backend_to_compare() else {
        return;
    };
    let (on_gpu, stats) = common::render_on(&mut gpu, scene.clone(), &settings);
    assert!(
        stats.rays.secondary > (1 << 20),
        "{} secondary rays: more than a batch",
        stats.rays.secondary
    );
    let waits = stats.gpu.as_ref().expect("GPU stats").traffic.waits;
    // A level whose bound (two rays a point) exceeds a batch waits for
    // its length: the camera level's next one, and that level's first
    // batch's next one (its second batch is small); then the band's end.
    assert_eq!(waits, 3, "two levels' lengths, then the band's end");
    let (on_cpu, cpu_stats) = common::render_with_stats(scene, &settings);
    assert_eq!(stats.rays, cpu_stats.rays);
    assert_eq!(stats.shading_points, cpu_stats.shading_points);
    if exact {
        assert!(on_gpu == on_cpu, "the GPU's frame differs from the CPU's");
    }
}
