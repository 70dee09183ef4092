//! Animated glTF test models written with the authoring builder: every
//! interpolation mode on node TRS, a skinned strip with a morph target,
//! morph weights on two nodes sharing a mesh, and KHR_animation_pointer
//! channels on lights, a camera and a material. The inspect and three.js
//! tests pose the same files (three.js all but the pointer model).
#![allow(dead_code)] // each test file uses its own subset

use std::path::{Path, PathBuf};

use glam::{DMat4, DVec3, Quat, Vec3};
use lmanim::scene::{
    AnimationClip, Camera, CameraProperty, Channel, Interpolation, JointSet, Light, LightKind,
    LightProperty, Material, MaterialProperty, MorphTarget, Projection, Sampler, Skin, Target,
};
use lmanim_authoring::Geometry;
use lmanim_authoring::{GltfBuilder, NodeDesc, Primitive};

/// Times that cover before the first key, between keys, on keys and after
/// the last key of every model.
pub const TIMES: &[f64] = &[
    0.0, 0.1, 0.25, 0.4, 0.6, 0.75, 0.9, 1.0, 1.1, 1.3, 1.5, 1.8, 2.0, 3.0,
];

pub fn channel(
    target: Target,
    interpolation: Interpolation,
    times: &[f32],
    values: Vec<f32>,
) -> Channel {
    // Morph weights: as many per key as the values hold.
    let elements_per_key = match interpolation {
        Interpolation::CubicSpline => 3,
        Interpolation::Step | Interpolation::Linear => 1,
    };
    let width = target.width(|_| values.len() / times.len() / elements_per_key);
    Channel {
        target,
        sampler: Sampler {
            interpolation,
            times: times.to_vec(),
            values,
            width,
        },
    }
}

fn flat<const N: usize>(items: &[[f32; N]]) -> Vec<f32> {
    items.iter().flatten().copied().collect()
}

fn quat(axis: Vec3, degrees: f32) -> [f32; 4] {
    Quat::from_axis_angle(axis.normalize(), degrees.to_radians()).to_array()
}

fn negated(q: [f32; 4]) -> [f32; 4] {
    q.map(|v| -v)
}

fn clip(name: &str, channels: Vec<Channel>) -> AnimationClip {
    AnimationClip {
        name: Some(name.into()),
        channels,
    }
}

fn cube(b: &mut GltfBuilder) -> lmanim_authoring::MeshId {
    let geometry = b
        .add_geometry(&lmanim_authoring::shapes::cuboid(Vec3::splat(0.5)))
        .expect("cube");
    b.add_mesh(
        "cube",
        &[Primitive {
            geometry,
            material: None,
        }],
    )
    .expect("mesh")
}

/// Node TRS under STEP, LINEAR and CUBICSPLINE, with a rotation key whose
/// sign is flipped, a camera and a light riding on animated nodes.
pub fn interpolations(dir: &Path) -> PathBuf {
    let mut b = GltfBuilder::new();
    let mesh = cube(&mut b);
    let camera = b
        .add_camera(&Camera {
            name: Some("eye".into()),
            projection: Projection::Perspective {
                yfov: 0.8,
                aspect_ratio: None,
                znear: 0.1,
                zfar: Some(100.0),
            },
        })
        .expect("camera");
    let light = b
        .add_light(&Light {
            name: Some("lamp".into()),
            kind: LightKind::Point,
            color: Vec3::ONE,
            intensity: 10.0,
            range: None,
            radius: Some(0.1),
            group: None,
        })
        .expect("light");
    let stepper = b
        .add_node(NodeDesc {
            mesh: Some(mesh),
            translation: Vec3::new(-2.0, 0.0, 0.0),
            ..NodeDesc::named("stepper")
        })
        .expect("node");
    let spinner = b
        .add_node(NodeDesc {
            mesh: Some(mesh),
            translation: Vec3::new(0.0, 1.0, 0.0),
            ..NodeDesc::named("spinner")
        })
        .expect("node");
    let eye = b
        .add_node(NodeDesc {
            camera: Some(camera),
            translation: Vec3::new(0.0, 0.5, 4.0),
            ..NodeDesc::named("eye")
        })
        .expect("node");
    let mover = b
        .add_node(NodeDesc {
            children: vec![spinner, eye],
            ..NodeDesc::named("mover")
        })
        .expect("node");
    let lamp = b
        .add_node(NodeDesc {
            light: Some(light),
            translation: Vec3::new(0.0, 3.0, 0.0),
            ..NodeDesc::named("lamp")
        })
        .expect("node");
    let (stepper, spinner, mover, lamp) = (
        stepper.index(),
        spinner.index(),
        mover.index(),
        lamp.index(),
    );

    let step = Interpolation::Step;
    let linear = Interpolation::Linear;
    let cubic = Interpolation::CubicSpline;
    let q0 = quat(Vec3::Y, 0.0);
    let q1 = quat(Vec3::Y, 120.0);
    let q2 = quat(Vec3::new(1.0, 1.0, 0.0), 200.0);
    let zero4 = [0.0; 4];
    let channels = vec![
        channel(
            Target::Rotation(stepper),
            step,
            &[0.25, 0.75, 1.25],
            flat(&[q0, q1, q2]),
        ),
        channel(
            Target::Scale(stepper),
            step,
            &[0.5, 1.0],
            flat(&[[1.0, 1.0, 1.0], [2.0, 0.5, 1.5]]),
        ),
        channel(
            Target::Translation(mover),
            linear,
            &[0.25, 1.0, 1.5],
            flat(&[[0.0, 0.0, 0.0], [3.0, 1.0, -2.0], [1.0, 1.0, 1.0]]),
        ),
        // The second key is the negated quaternion of a 120° turn: the
        // shorter arc is still the 120° one.
        channel(
            Target::Rotation(mover),
            linear,
            &[0.0, 1.0, 2.0],
            flat(&[q0, negated(q1), q2]),
        ),
        channel(
            Target::Scale(mover),
            linear,
            &[0.5, 1.5],
            flat(&[[1.0, 1.0, 1.0], [0.5, 2.0, 1.0]]),
        ),
        channel(
            Target::Rotation(spinner),
            cubic,
            &[0.0, 0.8, 1.8],
            flat(&[
                zero4,
                q0,
                [0.0, 0.6, 0.0, 0.0],
                [0.1, 0.0, 0.2, 0.0],
                quat(Vec3::Z, 90.0),
                [0.0, 0.3, 0.0, -0.1],
                zero4,
                quat(Vec3::X, -45.0),
                zero4,
            ]),
        ),
        channel(
            Target::Translation(spinner),
            cubic,
            &[0.2, 1.2],
            flat(&[
                [0.0, 0.0, 0.0],
                [0.0, 1.0, 0.0],
                [2.0, 0.0, 1.0],
                [-1.0, 3.0, 0.0],
                [1.0, 2.0, 0.5],
                [0.0, 0.0, 0.0],
            ]),
        ),
        channel(
            Target::Translation(lamp),
            linear,
            &[0.0, 2.0],
            flat(&[[0.0, 3.0, 0.0], [4.0, 3.0, -4.0]]),
        ),
    ];
    b.add_animation(&clip("all", channels)).expect("animation");
    let path = dir.join("interpolations.gltf");
    b.write_gltf(&path).expect("write");
    path
}

/// A vertical strip of 3 × 2 vertices bound to a chain of three joints,
/// with one morph target, posed by rotations (LINEAR, CUBICSPLINE) and a
/// STEP scale. The skinned node sits at the root with no transform, where
/// three.js and the glTF spec agree.
pub fn skinned(dir: &Path) -> PathBuf {
    let mut b = GltfBuilder::new();
    let mut geometry = Geometry::default();
    let rows = [0.0f32, 0.5, 1.0, 1.5, 2.0];
    for &y in &rows {
        for x in [-0.2f32, 0.2] {
            geometry.positions.push(Vec3::new(x, y, 0.0));
            geometry.normals.push(Vec3::Z);
        }
    }
    for row in 0..rows.len() as u32 - 1 {
        let (a, c) = (2 * row, 2 * row + 2);
        geometry.indices.extend([a, a + 1, c + 1, a, c + 1, c]);
    }
    // Joint 0 at y = 0, joint 1 at y = 1, joint 2 at y = 2; each vertex
    // blends the two joints around it.
    let mut set = JointSet::default();
    for &y in &rows {
        let (joints, weights) = match y {
            y if y <= 0.0 => ([0, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
            y if y < 1.0 => ([0, 1, 0, 0], [0.5, 0.5, 0.0, 0.0]),
            y if y <= 1.0 => ([1, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
            y if y < 2.0 => ([1, 2, 0, 0], [0.3, 0.7, 0.0, 0.0]),
            _ => ([2, 1, 0, 0], [0.9, 0.1, 0.0, 0.0]),
        };
        for _ in 0..2 {
            set.joints.push(joints);
            set.weights.push(weights);
        }
    }
    geometry.joint_sets = vec![set];
    geometry.morph_targets = vec![MorphTarget {
        positions: (0..geometry.positions.len())
            .map(|i| Vec3::new(0.0, 0.0, 0.1 * i as f32))
            .collect(),
        normals: Vec::new(),
    }];
    let geometry = b.add_geometry(&geometry).expect("geometry");
    let mesh = b
        .add_mesh(
            "strip",
            &[Primitive {
                geometry,
                material: None,
            }],
        )
        .expect("mesh");
    b.set_mesh_weights(mesh, &[0.5]).expect("weights");
    let tip = b
        .add_node(NodeDesc {
            translation: Vec3::new(0.0, 1.0, 0.0),
            ..NodeDesc::named("tip")
        })
        .expect("node");
    let middle = b
        .add_node(NodeDesc {
            translation: Vec3::new(0.0, 1.0, 0.0),
            children: vec![tip],
            ..NodeDesc::named("middle")
        })
        .expect("node");
    let base = b
        .add_node(NodeDesc {
            children: vec![middle],
            ..NodeDesc::named("base")
        })
        .expect("node");
    let joints = vec![base.index(), middle.index(), tip.index()];
    let skin = b
        .add_skin(&Skin {
            name: Some("chain".into()),
            joints: joints.clone(),
            inverse_bind: [0.0, -1.0, -2.0]
                .map(|y| DMat4::from_translation(DVec3::new(0.0, y, 0.0)))
                .to_vec(),
            skeleton: Some(base.index()),
        })
        .expect("skin");
    let strip = b
        .add_node(NodeDesc {
            mesh: Some(mesh),
            skin: Some(skin),
            ..NodeDesc::named("strip")
        })
        .expect("node");
    let zero4 = [0.0; 4];
    let channels = vec![
        channel(
            Target::Rotation(joints[1]),
            Interpolation::Linear,
            &[0.0, 1.0, 2.0],
            flat(&[
                quat(Vec3::Z, 0.0),
                quat(Vec3::Z, 60.0),
                quat(Vec3::X, -30.0),
            ]),
        ),
        channel(
            Target::Rotation(joints[0]),
            Interpolation::CubicSpline,
            &[0.5, 1.5],
            flat(&[
                zero4,
                quat(Vec3::Y, 0.0),
                [0.0, 0.5, 0.0, 0.0],
                zero4,
                quat(Vec3::Y, 90.0),
                zero4,
            ]),
        ),
        channel(
            Target::Scale(joints[2]),
            Interpolation::Step,
            &[0.0, 1.0],
            flat(&[[1.0, 1.0, 1.0], [1.5, 0.5, 1.0]]),
        ),
        channel(
            Target::Weights(strip.index()),
            Interpolation::Linear,
            &[0.0, 2.0],
            vec![0.0, 1.0],
        ),
    ];
    b.add_animation(&clip("bend", channels)).expect("animation");
    let path = dir.join("skinned.gltf");
    b.write_gltf(&path).expect("write");
    path
}

/// One mesh with two morph targets (positions and normals) and default
/// weights, used by two nodes: one with weights of its own. Three clips:
/// LINEAR weights, CUBICSPLINE weights, and a STEP hop.
pub fn morph(dir: &Path) -> PathBuf {
    let mut b = GltfBuilder::new();
    let mut geometry = lmanim_authoring::shapes::plane(glam::Vec2::splat(1.0));
    let count = geometry.positions.len();
    geometry.morph_targets = vec![
        MorphTarget {
            positions: vec![Vec3::new(0.0, 1.0, 0.0); count],
            normals: vec![Vec3::new(0.5, 0.0, 0.0); count],
        },
        MorphTarget {
            positions: (0..count)
                .map(|i| Vec3::new(0.1 * i as f32, 0.0, 0.2))
                .collect(),
            normals: Vec::new(),
        },
    ];
    let geometry = b.add_geometry(&geometry).expect("geometry");
    let mesh = b
        .add_mesh(
            "sheet",
            &[Primitive {
                geometry,
                material: None,
            }],
        )
        .expect("mesh");
    b.set_mesh_weights(mesh, &[0.1, 0.2]).expect("weights");
    let own = b
        .add_node(NodeDesc {
            mesh: Some(mesh),
            weights: Some(vec![0.3, 0.0]),
            ..NodeDesc::named("own_weights")
        })
        .expect("node");
    let shared = b
        .add_node(NodeDesc {
            mesh: Some(mesh),
            translation: Vec3::new(3.0, 0.0, 0.0),
            ..NodeDesc::named("mesh_weights")
        })
        .expect("node");
    let (own, shared) = (own.index(), shared.index());
    b.add_animation(&clip(
        "wobble",
        vec![channel(
            Target::Weights(own),
            Interpolation::Linear,
            &[0.25, 0.75, 1.25],
            vec![0.0, 0.0, 1.0, 0.5, 0.2, 1.0],
        )],
    ))
    .expect("animation");
    b.add_animation(&clip(
        "pulse",
        vec![channel(
            Target::Weights(shared),
            Interpolation::CubicSpline,
            &[0.0, 1.0],
            vec![0.0, 0.0, 0.0, 0.0, 1.0, 2.0, -1.0, 0.0, 1.0, 0.5, 0.0, 0.0],
        )],
    ))
    .expect("animation");
    b.add_animation(&clip(
        "hop",
        vec![channel(
            Target::Translation(shared),
            Interpolation::Step,
            &[0.0, 0.5, 1.5],
            flat(&[[3.0, 0.0, 0.0], [3.0, 1.0, 0.0], [3.0, 0.0, 2.0]]),
        )],
    ))
    .expect("animation");
    let path = dir.join("morph.gltf");
    b.write_gltf(&path).expect("write");
    path
}

/// KHR_animation_pointer channels on a light's colour (LINEAR), intensity
/// (STEP) and range (LINEAR), a spot's outer cone (LINEAR), a camera's
/// yfov (CUBICSPLINE) and a material's base colour (LINEAR), in that
/// channel order, one sampler each. `anim_pointer.rs` checks the values
/// by hand.
pub fn pointers(dir: &Path) -> PathBuf {
    let mut b = GltfBuilder::new();
    let paint = b
        .add_material(&Material {
            name: Some("paint".into()),
            metallic: 0.0,
            ..Material::default()
        })
        .expect("material");
    let geometry = b
        .add_geometry(&lmanim_authoring::shapes::plane(glam::Vec2::ONE))
        .expect("plane");
    let mesh = b
        .add_mesh(
            "floor",
            &[Primitive {
                geometry,
                material: Some(paint),
            }],
        )
        .expect("mesh");
    let lamp = b
        .add_light(&Light {
            name: Some("lamp".into()),
            kind: LightKind::Point,
            color: Vec3::ONE,
            intensity: 10.0,
            range: Some(4.0),
            radius: Some(0.1),
            group: None,
        })
        .expect("light");
    let spot = b
        .add_light(&Light {
            name: Some("spot".into()),
            kind: LightKind::Spot {
                inner_cone: 0.25,
                outer_cone: 0.5,
            },
            color: Vec3::ONE,
            intensity: 5.0,
            range: None,
            radius: None,
            group: None,
        })
        .expect("light");
    let camera = b
        .add_camera(&Camera {
            name: Some("eye".into()),
            projection: Projection::Perspective {
                yfov: 0.8,
                aspect_ratio: None,
                znear: 0.1,
                zfar: None,
            },
        })
        .expect("camera");
    b.add_node(NodeDesc {
        mesh: Some(mesh),
        ..NodeDesc::named("floor")
    })
    .expect("node");
    for (name, light, y) in [("lamp", lamp, 2.0), ("spot", spot, 3.0)] {
        b.add_node(NodeDesc {
            light: Some(light),
            translation: Vec3::new(0.0, y, 0.0),
            ..NodeDesc::named(name)
        })
        .expect("node");
    }
    b.add_node(NodeDesc {
        camera: Some(camera),
        translation: Vec3::new(0.0, 1.0, 4.0),
        ..NodeDesc::named("eye")
    })
    .expect("node");

    let (lamp, spot, camera, paint) = (lamp.index(), spot.index(), camera.index(), paint.index());
    let channels = vec![
        channel(
            Target::Light(lamp, LightProperty::Color),
            Interpolation::Linear,
            &[1.0, 2.0],
            vec![1.0, 0.0, 0.0, 0.0, 0.5, 1.0],
        ),
        channel(
            Target::Light(lamp, LightProperty::Intensity),
            Interpolation::Step,
            &[0.5, 1.5, 2.5],
            vec![10.0, 20.0, 5.0],
        ),
        channel(
            Target::Light(lamp, LightProperty::Range),
            Interpolation::Linear,
            &[0.0, 2.0],
            vec![4.0, 8.0],
        ),
        channel(
            Target::Light(spot, LightProperty::OuterConeAngle),
            Interpolation::Linear,
            &[0.0, 2.0],
            vec![0.5, 0.75],
        ),
        // In-tangent, value, out-tangent per key.
        channel(
            Target::Camera(camera, CameraProperty::Yfov),
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            vec![0.0, 0.5, 0.25, 0.125, 1.0, 0.0],
        ),
        channel(
            Target::Material(paint, MaterialProperty::BaseColor),
            Interpolation::Linear,
            &[0.0, 1.0],
            vec![1.0, 1.0, 1.0, 1.0, 0.2, 0.4, 0.6, 0.8],
        ),
    ];
    b.add_animation(&clip("looks", channels))
        .expect("animation");
    let path = dir.join("pointers.gltf");
    b.write_gltf(&path).expect("write");
    path
}

/// Runs the `lmanim` binary with `args` in `dir`.
pub fn lmanim(args: &[&str], dir: &Path) -> std::process::Output {
    std::process::Command::new(env!("CARGO_BIN_EXE_lmanim"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run lmanim")
}

/// A test model of this module (`model`) with its JSON changed by `edit`,
/// written to `dir/name`; the buffer stays embedded, so accessors keep
/// their data.
pub fn edited(
    dir: &Path,
    name: &str,
    model: fn(&Path) -> PathBuf,
    edit: impl FnOnce(&mut serde_json::Value),
) -> PathBuf {
    let written = model(&dir.join(name).with_extension("d"));
    let mut doc: serde_json::Value =
        serde_json::from_slice(&std::fs::read(&written).expect("read")).expect("JSON");
    edit(&mut doc);
    let path = dir.join(name);
    std::fs::write(&path, doc.to_string()).expect("write");
    path
}
