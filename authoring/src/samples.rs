//! The sample scenes under `animations/`, which the README renders:
//! `cargo run --example make_animations` writes them, and
//! `tests/sample_scenes.rs` checks that they regenerate byte for byte.
//!
//! `courtyard.gltf` shows what lmanim does in one still: a floor and walls
//! to catch soft shadows, pillars and crates to cast them, a mirror sphere
//! and a glass sphere for Whitted reflection and refraction, three coloured
//! point lamps of different radii (so penumbrae of different widths) and a
//! spot light, with four seconds of animation: a rolling glass ball, a
//! drifting lamp and a camera dolly. Its settings are in the hand-written
//! `courtyard.ron`.
//!
//! `city.gltf` is the showcase: the city block of [`crate::city`] with
//! 121 windowed buildings (over 300k triangles in the scene, from three
//! instanced meshes), 24 street lamps, 8 cars lapping the streets, 12
//! skinned trees swaying along the main street and a 10 s camera
//! fly-through ("flythrough"). Its settings are in the hand-written
//! `city.ron`.
//!
//! `study-box.gltf`, `study-leaves.gltf`, `study-street.gltf` and
//! `study-wall.gltf` are the stills of `lmanim study` (STUDY.md), from
//! [`crate::study`].

use std::f32::consts::PI;

use glam::{Quat, Vec2, Vec3, Vec4};
use lmanim::scene::animation::{AnimationClip, Channel, Interpolation, Sampler, Target};
use lmanim::scene::{Camera, Light, LightKind, Material, Projection};

use crate::city::{city_block, CityParams};
use crate::study::StudyScene;
use crate::{
    look_at_rotation, matte, shapes, AuthoringError, GltfBuilder, MeshId, NodeDesc, NodeId,
    Primitive,
};

/// A sample scene: its file name under `animations/` and how to build it.
pub struct Sample {
    pub file_name: &'static str,
    pub build: fn() -> Result<GltfBuilder, AuthoringError>,
}

/// Every sample scene, in the order they are written.
pub const SAMPLES: [Sample; 6] = [
    Sample {
        file_name: "courtyard.gltf",
        build: courtyard,
    },
    Sample {
        file_name: "city.gltf",
        build: city,
    },
    Sample {
        file_name: "study-box.gltf",
        build: || StudyScene::Box.build(),
    },
    Sample {
        file_name: "study-leaves.gltf",
        build: || StudyScene::Leaves.build(),
    },
    Sample {
        file_name: "study-street.gltf",
        build: || StudyScene::Street.build(),
    },
    Sample {
        file_name: "study-wall.gltf",
        build: || StudyScene::Wall.build(),
    },
];

/// The showcase city.
pub fn city() -> Result<GltfBuilder, AuthoringError> {
    city_block(&showcase_city())
}

/// The showcase's city: 11 × 11 buildings with 6 × 6 windows per wall,
/// lamps whose range lets each point see a few of them.
fn showcase_city() -> CityParams {
    CityParams {
        blocks: 11,
        lamps: 24,
        lamp_radius: 0.25,
        lamp_range: Some(35.0),
        facade_detail: 6,
        cars: 8,
        trees: 12,
        flythrough: true,
    }
}

fn point_lamp(name: &str, colour: Vec3, intensity: f32, radius: f32) -> Light {
    Light {
        name: Some(name.into()),
        kind: LightKind::Point,
        color: colour,
        intensity,
        range: None,
        radius: Some(radius),
        group: None,
    }
}

/// The courtyard: every kind of light and material lmanim renders, in
/// one small scene with four seconds of animation.
pub fn courtyard() -> Result<GltfBuilder, AuthoringError> {
    let mut b = GltfBuilder::new();

    let stone = b.add_material(&matte("Stone", Vec3::new(0.55, 0.52, 0.48), 0.8))?;
    let plaster = b.add_material(&matte("Plaster", Vec3::new(0.75, 0.72, 0.66), 0.9))?;
    let wood = b.add_material(&matte("Wood", Vec3::new(0.45, 0.28, 0.14), 0.6))?;
    let paint = b.add_material(&matte("BluePaint", Vec3::new(0.12, 0.25, 0.6), 0.4))?;
    let mirror = b.add_material(&Material {
        name: Some("Mirror".into()),
        base_color: Vec4::new(0.95, 0.95, 0.95, 1.0),
        metallic: 1.0,
        roughness: 0.05,
        ..Material::default()
    })?;
    let glass = b.add_material(&Material {
        name: Some("Glass".into()),
        base_color: Vec4::ONE,
        metallic: 0.0,
        roughness: 0.0,
        transmission: 1.0,
        ior: 1.5,
        ..Material::default()
    })?;

    // Shared geometry: a unit cube scaled per node, a unit sphere.
    let cube = b.add_geometry(&shapes::cuboid(Vec3::splat(0.5)))?;
    let sphere = b.add_geometry(&shapes::uv_sphere(1.0, 48, 24))?;
    let floor_geometry = b.add_geometry(&shapes::plane(Vec2::new(6.0, 6.0)))?;
    let mut mesh = |name: &str, geometry, material| {
        b.add_mesh(
            name,
            &[Primitive {
                geometry,
                material: Some(material),
            }],
        )
    };
    let floor = mesh("Floor", floor_geometry, stone)?;
    let wall = mesh("Wall", cube, plaster)?;
    let pillar = mesh("Pillar", cube, stone)?;
    let crate_mesh = mesh("Crate", cube, wood)?;
    let block = mesh("Block", cube, paint)?;
    let mirror_ball = mesh("MirrorBall", sphere, mirror)?;
    let glass_ball = mesh("GlassBall", sphere, glass)?;

    let mut placed = |name: &str, mesh: MeshId, at: Vec3, size: Vec3, turn: f32| {
        b.add_node(NodeDesc {
            translation: at,
            rotation: Quat::from_rotation_y(turn),
            scale: size,
            mesh: Some(mesh),
            ..NodeDesc::named(name)
        })
    };
    placed("Floor", floor, Vec3::ZERO, Vec3::ONE, 0.0)?;
    placed(
        "BackWall",
        wall,
        Vec3::new(0.0, 1.5, -5.0),
        Vec3::new(12.0, 3.0, 0.3),
        0.0,
    )?;
    placed(
        "SideWall",
        wall,
        Vec3::new(-5.5, 1.0, -1.5),
        Vec3::new(0.3, 2.0, 7.0),
        0.0,
    )?;
    placed(
        "LowWall",
        wall,
        Vec3::new(5.5, 0.6, -1.5),
        Vec3::new(0.3, 1.2, 7.0),
        0.0,
    )?;
    for (i, (x, z)) in [(-3.0, -2.5), (3.0, -2.5), (-3.0, 1.5), (3.0, 1.5)]
        .into_iter()
        .enumerate()
    {
        let at = Vec3::new(x, 1.5, z);
        placed(
            &format!("Pillar.{i}"),
            pillar,
            at,
            Vec3::new(0.35, 3.0, 0.35),
            0.0,
        )?;
    }
    placed(
        "Crate.0",
        crate_mesh,
        Vec3::new(-1.6, 0.4, 0.2),
        Vec3::splat(0.8),
        0.35,
    )?;
    placed(
        "Crate.1",
        crate_mesh,
        Vec3::new(-1.5, 1.05, 0.1),
        Vec3::splat(0.5),
        PI / 4.0,
    )?;
    placed(
        "Block",
        block,
        Vec3::new(2.2, 0.6, -1.8),
        Vec3::new(0.6, 1.2, 0.6),
        -0.3,
    )?;
    placed(
        "MirrorBall",
        mirror_ball,
        Vec3::new(0.1, 0.7, -1.6),
        Vec3::splat(0.7),
        0.0,
    )?;
    let glass_ball_node = placed(
        "GlassBall",
        glass_ball,
        Vec3::new(1.2, 0.45, 0.9),
        Vec3::splat(0.45),
        0.0,
    )?;

    // Three lamps of different colours and sizes: wide and narrow
    // penumbrae side by side. Intensities in W/sr (see ARCHITECTURE.md, "Conventions").
    let lamps = [
        (
            "Lamp.Warm",
            Vec3::new(1.0, 0.72, 0.45),
            30.0,
            0.3,
            Vec3::new(-2.4, 2.6, 1.2),
        ),
        (
            "Lamp.Cool",
            Vec3::new(0.5, 0.7, 1.0),
            20.0,
            0.15,
            Vec3::new(2.6, 2.3, -0.6),
        ),
        (
            "Lamp.Small",
            Vec3::new(1.0, 0.95, 0.85),
            6.0,
            0.05,
            Vec3::new(0.3, 1.3, 2.2),
        ),
    ];
    let mut lamp_nodes = Vec::new();
    for (name, colour, intensity, radius, at) in lamps {
        let light = b.add_light(&point_lamp(name, colour, intensity, radius))?;
        lamp_nodes.push(b.add_node(NodeDesc {
            translation: at,
            light: Some(light),
            ..NodeDesc::named(name)
        })?);
    }
    let spot_at = Vec3::new(1.5, 5.0, 3.5);
    let spot = b.add_light(&Light {
        name: Some("Spot.Key".into()),
        kind: LightKind::Spot {
            inner_cone: 0.25,
            outer_cone: 0.4,
        },
        color: Vec3::new(1.0, 0.98, 0.92),
        intensity: 150.0,
        range: None,
        radius: Some(0.1),
        group: None,
    })?;
    b.add_node(NodeDesc {
        translation: spot_at,
        rotation: look_at_rotation(spot_at, Vec3::new(0.0, 0.0, -1.0), Vec3::Y)
            .unwrap_or(Quat::IDENTITY),
        light: Some(spot),
        ..NodeDesc::named("Spot.Key")
    })?;

    let camera = b.add_camera(&Camera {
        name: Some("main".into()),
        projection: Projection::Perspective {
            yfov: 50f32.to_radians(),
            aspect_ratio: Some(16.0 / 9.0),
            znear: 0.1,
            zfar: Some(100.0),
        },
    })?;
    let eye = Vec3::new(0.8, 2.4, 7.8);
    let camera_node = b.add_node(NodeDesc {
        translation: eye,
        rotation: look_at_rotation(eye, Vec3::new(0.0, 0.8, -1.0), Vec3::Y)
            .unwrap_or(Quat::IDENTITY),
        camera: Some(camera),
        ..NodeDesc::named("main")
    })?;

    // Four seconds of animation: the glass ball rolls towards the crates
    // (a dynamic object, so its shadow's mask bits are invalidated), the
    // small lamp drifts across the courtyard (a moving light) and the
    // camera dollies in (which invalidates nothing).
    let path = |node: NodeId, keys: &[Vec3]| Channel {
        target: Target::Translation(node.index()),
        sampler: Sampler {
            interpolation: Interpolation::Linear,
            times: (0..keys.len())
                .map(|i| 4.0 * i as f32 / (keys.len() - 1) as f32)
                .collect(),
            values: keys.iter().flat_map(|key| key.to_array()).collect(),
            width: 3,
        },
    };
    b.add_animation(&AnimationClip {
        name: Some("Courtyard".into()),
        channels: vec![
            path(
                glass_ball_node,
                &[
                    Vec3::new(1.2, 0.45, 0.9),
                    Vec3::new(0.3, 0.45, 1.3),
                    Vec3::new(-0.5, 0.45, 1.6),
                ],
            ),
            path(
                lamp_nodes[2],
                &[Vec3::new(0.3, 1.3, 2.2), Vec3::new(-1.2, 1.5, 2.4)],
            ),
            path(camera_node, &[eye, eye + Vec3::new(-0.6, -0.2, -1.2)]),
        ],
    })?;
    Ok(b)
}
