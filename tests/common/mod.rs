//! Scenes built in memory for the renderer's tests: quads, lights and
//! cameras as plain `SceneDesc` data, so each test states its geometry;
//! and ([`cli`]) running the binary and what its tests assert of failures;
//! ([`gpu`]) the GPU backend where tests have one.
#![allow(dead_code)] // each test file uses its own subset

pub mod cli;
pub mod gpu;

use glam::{DMat4, DQuat, DVec3, Vec3, Vec4};
use lmanim::anim::pose::ClipSelection;
use lmanim::output::Image;
use lmanim::plan::Plan;
use lmanim::scene::{Camera, Light, LightKind, Material, Mesh, Node, Projection, SceneDesc};
use lmanim::schedule::{FrameSet, Timeline};
use lmanim::sequence::Sequence;
use lmanim::settings::Settings;
use lmanim::stats::FrameStats;

/// The Python interpreter with the `OpenEXR` package, another tool's EXR
/// reader and writer (`.ci/run` makes a virtual environment with it and
/// names it in `LMANIM_OPENEXR_PYTHON`), or None off CI when none is named.
pub fn openexr_python() -> Option<String> {
    match std::env::var("LMANIM_OPENEXR_PYTHON") {
        Ok(python) => Some(python),
        Err(_) if std::env::var_os("CI").is_none() => {
            eprintln!("skipped: LMANIM_OPENEXR_PYTHON names no Python with OpenEXR");
            None
        }
        Err(_) => panic!("CI must name a Python with OpenEXR in LMANIM_OPENEXR_PYTHON"),
    }
}

pub fn empty_scene() -> SceneDesc {
    SceneDesc {
        name: "test".into(),
        ..SceneDesc::default()
    }
}

/// A purely Lambertian material (KHR_materials_specular factor 0).
pub fn lambert(albedo: Vec3) -> Material {
    Material {
        base_color: albedo.extend(1.0),
        metallic: 0.0,
        roughness: 1.0,
        specular: 0.0,
        ..Material::default()
    }
}

pub fn add_material(scene: &mut SceneDesc, material: Material) -> u32 {
    scene.materials.push(material);
    (scene.materials.len() - 1) as u32
}

/// A root node with the given transform and optional mesh/light/camera.
pub fn add_node(scene: &mut SceneDesc, local: DMat4) -> usize {
    scene.nodes.push(Node {
        local,
        ..Node::default()
    });
    let index = scene.nodes.len() - 1;
    scene.roots.push(index);
    index
}

/// A mesh made of quads given by their four corners (counter-clockwise seen
/// from the side the normal faces), each split into `cells × cells` squares.
pub fn add_quads(scene: &mut SceneDesc, quads: &[[Vec3; 4]], cells: u32, material: u32) -> usize {
    let mut mesh = Mesh::default();
    for corners in quads {
        let normal = (corners[1] - corners[0])
            .cross(corners[3] - corners[0])
            .normalize();
        let base = mesh.positions.len() as u32;
        for j in 0..=cells {
            for i in 0..=cells {
                let (s, t) = (i as f32 / cells as f32, j as f32 / cells as f32);
                let bottom = corners[0].lerp(corners[1], s);
                let top = corners[3].lerp(corners[2], s);
                mesh.positions.push(bottom.lerp(top, t));
                mesh.normals.push(normal);
            }
        }
        let row = cells + 1;
        for j in 0..cells {
            for i in 0..cells {
                let a = base + j * row + i;
                mesh.triangles.push([a, a + 1, a + row + 1]);
                mesh.triangles.push([a, a + row + 1, a + row]);
                mesh.triangle_materials.extend([material, material]);
            }
        }
    }
    scene.meshes.push(mesh);
    let mesh = scene.meshes.len() - 1;
    let node = add_node(scene, DMat4::IDENTITY);
    scene.nodes[node].mesh = Some(mesh);
    node
}

/// A horizontal square at height `y`, half-size `half`, facing +Y.
pub fn floor_quad(y: f32, half: f32) -> [Vec3; 4] {
    [
        Vec3::new(-half, y, half),
        Vec3::new(half, y, half),
        Vec3::new(half, y, -half),
        Vec3::new(-half, y, -half),
    ]
}

pub fn add_light(scene: &mut SceneDesc, kind: LightKind, intensity: f32, local: DMat4) -> usize {
    scene.lights.push(Light {
        name: Some(format!("light{}", scene.lights.len())),
        kind,
        color: Vec3::ONE,
        intensity,
        range: None,
        radius: None,
        group: None,
    });
    let node = add_node(scene, local);
    scene.nodes[node].light = Some(scene.lights.len() - 1);
    node
}

/// Adds an animation clip named `name` playing `channels`.
pub fn add_clip(
    scene: &mut SceneDesc,
    name: &str,
    channels: Vec<lmanim::scene::animation::Channel>,
) {
    (scene.animations).push(lmanim::scene::animation::AnimationClip {
        name: Some(name.into()),
        channels,
    });
}

/// A perspective projection of vertical field of view `yfov` radians,
/// the image's aspect, near plane 0.1 m, no far plane.
pub fn perspective(yfov: f32) -> Projection {
    Projection::Perspective {
        yfov,
        aspect_ratio: None,
        znear: 0.1,
        zfar: None,
    }
}

pub fn add_camera(scene: &mut SceneDesc, projection: Projection, local: DMat4) -> usize {
    scene.cameras.push(Camera {
        name: Some("cam".into()),
        projection,
    });
    let node = add_node(scene, local);
    scene.nodes[node].camera = Some(scene.cameras.len() - 1);
    node
}

/// An orthographic camera at height `y` looking straight down (−Y), image
/// top towards −Z, seeing `2·ymag` metres vertically.
pub fn add_top_camera(scene: &mut SceneDesc, y: f64, ymag: f32) -> usize {
    add_camera(
        scene,
        Projection::Orthographic {
            xmag: ymag,
            ymag,
            znear: 0.0,
            zfar: 1e4,
        },
        look_down(y),
    )
}

pub fn look_down(y: f64) -> DMat4 {
    DMat4::from_rotation_translation(
        DQuat::from_rotation_x(-std::f64::consts::FRAC_PI_2),
        DVec3::new(0.0, y, 0.0),
    )
}

/// World (x, z) seen by pixel (px, py)'s centre under [`add_top_camera`].
pub fn top_camera_ground(px: u32, py: u32, width: u32, height: u32, ymag: f32) -> (f32, f32) {
    let aspect = width as f32 / height as f32;
    let ndc_x = 2.0 * (px as f32 + 0.5) / width as f32 - 1.0;
    let ndc_y = 1.0 - 2.0 * (py as f32 + 0.5) / height as f32;
    (ndc_x * ymag * aspect, -ndc_y * ymag)
}

/// `scene` as the command line runs it: played by every clip, planned
/// over `frames` (`--frames` text, e.g. `0..4`), starting at the first.
pub fn planned(scene: &SceneDesc, settings: &Settings, frames: &str) -> Sequence {
    let frames = FrameSet::parse(frames).expect("a frame set");
    let plan = Plan::make(scene, settings, ClipSelection::All, &frames).expect("the scene places");
    let first = Timeline { fps: settings.fps }.time_of(frames.frames()[0]);
    Sequence::planned(
        scene.clone(),
        "test".into(),
        ClipSelection::All,
        first,
        plan,
    )
    .expect("the scene places")
}

pub fn settings(width: u32, height: u32) -> Settings {
    Settings {
        width,
        height,
        ..Settings::default()
    }
}

/// A camera node transform at `eye` looking at `target`, +Y up.
pub fn look_at(eye: DVec3, target: DVec3) -> DMat4 {
    let backward = (eye - target).normalize();
    let right = DVec3::Y.cross(backward).normalize();
    let up = backward.cross(right);
    DMat4::from_cols(
        right.extend(0.0),
        up.extend(0.0),
        backward.extend(0.0),
        eye.extend(1.0),
    )
}

pub fn render(scene: SceneDesc, settings: &Settings) -> Image {
    render_with_stats(scene, settings).0
}

pub fn render_with_stats(scene: SceneDesc, settings: &Settings) -> (Image, FrameStats) {
    let mut backend =
        lmanim::backend::Backend::new(lmanim::settings::BackendKind::Cpu, settings.threads)
            .expect("thread pool");
    render_on(&mut backend, scene, settings)
}

/// The scene's first frame rendered on `backend`, with its stats.
pub fn render_on(
    backend: &mut lmanim::backend::Backend,
    scene: SceneDesc,
    settings: &Settings,
) -> (Image, FrameStats) {
    let mut sequence = Sequence::new(scene, "test".into()).expect("scene places");
    let placed = sequence.place(settings).expect("camera");
    let mut stats = FrameStats::default();
    let image = sequence
        .render(backend, &placed, settings, &mut stats)
        .expect("frame renders");
    (image, stats)
}

pub fn pixel(image: &Image, x: u32, y: u32) -> Vec4 {
    image.pixels[(y * image.width + x) as usize]
}

/// The six faces of an axis-aligned cube of half-size `half` around
/// `centre`, each counter-clockwise seen from outside (for [`add_quads`]).
pub fn box_quads(centre: Vec3, half: f32) -> [[Vec3; 4]; 6] {
    lmanim_authoring::shapes::CUBE_FACES.map(|(n, t1, t2)| {
        let c = centre + n * half;
        [
            c + (-t1 - t2) * half,
            c + (t1 - t2) * half,
            c + (t1 + t2) * half,
            c + (-t1 + t2) * half,
        ]
    })
}

/// A point light at `position` standing for a spherical lamp of `radius`
/// metres (the light's `extras.radius`).
pub fn add_lamp(scene: &mut SceneDesc, intensity: f32, position: Vec3, radius: f32) -> usize {
    let node = add_light(
        scene,
        LightKind::Point,
        intensity,
        DMat4::from_translation(position.as_dvec3()),
    );
    if let Some(light) = scene.lights.last_mut() {
        light.radius = Some(radius);
    }
    node
}

/// Root-mean-square difference of the colour channels of two images of the
/// same size.
pub fn rms_difference(a: &Image, b: &Image) -> f32 {
    assert_eq!((a.width, a.height), (b.width, b.height));
    let sum: f64 = a
        .pixels
        .iter()
        .zip(&b.pixels)
        .map(|(p, q)| (p.truncate() - q.truncate()).length_squared() as f64)
        .sum();
    (sum / (3 * a.pixels.len()) as f64).sqrt() as f32
}

/// A LINEAR translation channel from `from` at time 0 to `to` at `duration`.
pub fn linear_translation(
    node: usize,
    from: Vec3,
    to: Vec3,
    duration: f32,
) -> lmanim::scene::animation::Channel {
    use lmanim::scene::animation::{Channel, Interpolation, Sampler, Target};
    Channel {
        target: Target::Translation(node),
        sampler: Sampler {
            interpolation: Interpolation::Linear,
            times: vec![0.0, duration],
            values: vec![from.x, from.y, from.z, to.x, to.y, to.z],
            width: 3,
        },
    }
}

/// A sheet standing in the plane x = `x` over z in [-half_width, half_width]
/// and y in [0, height], in cells of `cell` metres (two triangles each),
/// with one morph target that lowers the top edge of its z > 0 half, by
/// `drop` metres at the far end (vertices sink in proportion to y and z),
/// and leaves its z ≤ 0 half still. Normals face −X.
pub fn half_morphing_sheet(x: f32, half_width: f32, height: f32, cell: f32, drop: f32) -> Mesh {
    let (columns, rows) = (
        (2.0 * half_width / cell).round() as u32,
        (height / cell).round() as u32,
    );
    let mut mesh = Mesh::default();
    let mut offsets = Vec::new();
    for j in 0..=rows {
        for i in 0..=columns {
            let (y, z) = (
                height * j as f32 / rows as f32,
                -half_width + cell * i as f32,
            );
            mesh.positions.push(Vec3::new(x, y, z));
            mesh.normals.push(Vec3::NEG_X);
            let sink = if z > 0.0 {
                drop * (y / height) * (z / half_width)
            } else {
                0.0
            };
            offsets.push(Vec3::new(0.0, -sink, 0.0));
        }
    }
    let row = columns + 1;
    for j in 0..rows {
        for i in 0..columns {
            let a = j * row + i;
            mesh.triangles.push([a, a + 1, a + row + 1]);
            mesh.triangles.push([a, a + row + 1, a + row]);
            mesh.triangle_materials.extend([0, 0]);
        }
    }
    mesh.morph_targets = vec![lmanim::scene::MorphTarget {
        positions: offsets,
        normals: Vec::new(),
    }];
    mesh.morph_weights = vec![0.0];
    mesh
}

/// A cube `[-1, 1]^3` with each face split into `n × n` quads, vertices shared
/// along face borders.
pub fn cube(n: u32) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let mut index = std::collections::HashMap::new();
    let mut p = Vec::new();
    let mut tris = Vec::new();
    let mut vertex = |v: Vec3, p: &mut Vec<Vec3>| {
        let key = (v * n as f32).round().as_ivec3().to_array();
        *index.entry(key).or_insert_with(|| {
            p.push(v);
            p.len() as u32 - 1
        })
    };
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let (u, v) = (Vec3::AXES[(axis + 1) % 3], Vec3::AXES[(axis + 2) % 3]);
            let w = Vec3::AXES[axis] * side;
            let at = |i: u32, j: u32| {
                w + u * (2.0 * i as f32 / n as f32 - 1.0) + v * (2.0 * j as f32 / n as f32 - 1.0)
            };
            for j in 0..n {
                for i in 0..n {
                    let q = [at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1)]
                        .map(|x| vertex(x, &mut p));
                    tris.push([q[0], q[1], q[2]]);
                    tris.push([q[0], q[2], q[3]]);
                }
            }
        }
    }
    (p, tris)
}

/// A box on a floor under a lamp (radius 0.2 m) and a point light, seen
/// from above by a camera at (0, 6, 6): the scene and the camera's node.
pub fn box_under_a_lamp() -> (SceneDesc, usize) {
    let mut scene = empty_scene();
    let grey = add_material(&mut scene, lambert(Vec3::splat(0.6)));
    add_quads(&mut scene, &[floor_quad(0.0, 6.0)], 4, grey);
    add_quads(
        &mut scene,
        &box_quads(Vec3::new(0.0, 0.5, 0.0), 0.5),
        1,
        grey,
    );
    add_lamp(&mut scene, 300.0, Vec3::new(1.0, 4.0, 0.5), 0.2);
    add_light(
        &mut scene,
        LightKind::Point,
        100.0,
        DMat4::from_translation(DVec3::new(-2.0, 3.0, 1.0)),
    );
    let camera = add_camera(
        &mut scene,
        perspective(0.9),
        look_at(DVec3::new(0.0, 6.0, 6.0), DVec3::ZERO),
    );
    (scene, camera)
}
