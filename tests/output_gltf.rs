//! The glTF builder's files parse with the `gltf` crate in all three forms
//! and hold what was put in: bounds, materials with their extensions,
//! lights with their radius, cameras and the node tree.

use std::path::Path;

use glam::{Quat, Vec2, Vec3, Vec4};
use lmanim::scene::{Camera, Light, LightKind, Material, Projection};
use lmanim_authoring::{look_at_rotation, shapes, GltfBuilder, NodeDesc, Primitive};

fn sample() -> GltfBuilder {
    let mut builder = GltfBuilder::new();
    let glass = builder
        .add_material(&Material {
            name: Some("Glass".into()),
            metallic: 0.0,
            roughness: 0.0,
            transmission: 1.0,
            ior: 1.33,
            ..Material::default()
        })
        .unwrap();
    let red = builder
        .add_material(&Material {
            name: Some("Red".into()),
            base_color: Vec4::new(0.8, 0.1, 0.1, 1.0),
            metallic: 0.0,
            emissive: Vec3::new(0.0, 4.0, 0.0),
            double_sided: true,
            ..Material::default()
        })
        .unwrap();
    let sphere = builder
        .add_geometry(&shapes::uv_sphere(0.5, 12, 6))
        .unwrap();
    let cuboid = builder
        .add_geometry(&shapes::cuboid(Vec3::new(1.0, 2.0, 3.0)))
        .unwrap();
    let mesh = builder
        .add_mesh(
            "Both",
            &[
                Primitive {
                    geometry: sphere,
                    material: Some(glass),
                },
                Primitive {
                    geometry: cuboid,
                    material: Some(red),
                },
            ],
        )
        .unwrap();
    let lamp = builder
        .add_light(&Light {
            name: Some("Lamp".into()),
            kind: LightKind::Point,
            color: Vec3::new(1.0, 0.5, 0.25),
            intensity: 12.0,
            range: Some(20.0),
            radius: Some(0.1),
            group: None,
        })
        .unwrap();
    let spot = builder
        .add_light(&Light {
            name: Some("Spot".into()),
            kind: LightKind::Spot {
                inner_cone: 0.2,
                outer_cone: 0.4,
            },
            color: Vec3::ONE,
            intensity: 30.0,
            range: None,
            radius: None,
            group: None,
        })
        .unwrap();
    let camera = builder
        .add_camera(&Camera {
            name: Some("main".into()),
            projection: Projection::Perspective {
                yfov: 0.8,
                aspect_ratio: Some(16.0 / 9.0),
                znear: 0.1,
                zfar: None,
            },
        })
        .unwrap();
    let child = builder
        .add_node(NodeDesc {
            translation: Vec3::new(0.0, 2.0, 0.0),
            light: Some(lamp),
            ..NodeDesc::named("LampNode")
        })
        .unwrap();
    builder
        .add_node(NodeDesc {
            rotation: Quat::from_rotation_y(0.5),
            scale: Vec3::splat(2.0),
            mesh: Some(mesh),
            children: vec![child],
            ..NodeDesc::named("Thing")
        })
        .unwrap();
    builder
        .add_node(NodeDesc {
            translation: Vec3::new(0.0, 4.0, 0.0),
            rotation: look_at_rotation(Vec3::new(0.0, 4.0, 0.0), Vec3::ZERO, Vec3::Z).unwrap(),
            light: Some(spot),
            ..NodeDesc::named("SpotNode")
        })
        .unwrap();
    builder
        .add_node(NodeDesc {
            translation: Vec3::new(0.0, 1.0, 5.0),
            camera: Some(camera),
            ..NodeDesc::named("CameraNode")
        })
        .unwrap();
    builder
}

/// Checks the imported document against [`sample`].
fn check(document: &gltf::Document, buffers: &[gltf::buffer::Data]) {
    let scene = document.default_scene().unwrap();
    let roots: Vec<_> = scene
        .nodes()
        .map(|n| n.name().unwrap().to_owned())
        .collect();
    assert_eq!(roots, ["Thing", "SpotNode", "CameraNode"]);

    let thing = document
        .nodes()
        .find(|n| n.name() == Some("Thing"))
        .unwrap();
    let (_, rotation, scale) = thing.transform().decomposed();
    assert!(Quat::from_array(rotation).abs_diff_eq(Quat::from_rotation_y(0.5), 1e-6));
    assert_eq!(scale, [2.0; 3]);
    let child = thing.children().next().unwrap();
    assert_eq!(child.light().unwrap().name(), Some("Lamp"));

    let mesh = thing.mesh().unwrap();
    let primitives: Vec<_> = mesh.primitives().collect();
    assert_eq!(primitives.len(), 2);
    let bounds = primitives[1].bounding_box();
    assert_eq!(
        (bounds.min, bounds.max),
        ([-1.0, -2.0, -3.0], [1.0, 2.0, 3.0])
    );
    let reader = primitives[0].reader(|buffer| Some(&buffers[buffer.index()]));
    let positions: Vec<[f32; 3]> = reader.read_positions().unwrap().collect();
    assert_eq!(
        positions,
        shapes::uv_sphere(0.5, 12, 6)
            .positions
            .iter()
            .map(|p| p.to_array())
            .collect::<Vec<_>>()
    );
    let indices: Vec<u32> = reader.read_indices().unwrap().into_u32().collect();
    assert_eq!(indices, shapes::uv_sphere(0.5, 12, 6).indices);
    assert_eq!(
        reader.read_tex_coords(0).unwrap().into_f32().count(),
        positions.len()
    );

    let glass = primitives[0].material();
    assert_eq!(glass.name(), Some("Glass"));
    assert_eq!(glass.transmission().unwrap().transmission_factor(), 1.0);
    assert_eq!(glass.ior(), Some(1.33));
    let red = primitives[1].material();
    assert!(red.double_sided());
    assert_eq!(
        red.pbr_metallic_roughness().base_color_factor(),
        [0.8, 0.1, 0.1, 1.0]
    );
    assert_eq!(red.emissive_factor(), [0.0, 1.0, 0.0]);

    let lights: Vec<_> = document.lights().unwrap().collect();
    assert_eq!(lights[0].intensity(), 12.0);
    assert_eq!(lights[0].range(), Some(20.0));
    assert_eq!(lights[0].color(), [1.0, 0.5, 0.25]);
    let extras = lights[0].extras().as_ref().unwrap().get();
    let extras: serde_json::Value = serde_json::from_str(extras).unwrap();
    assert_eq!(extras["radius"], 0.1f32 as f64);
    match lights[1].kind() {
        gltf::khr_lights_punctual::Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => assert_eq!((inner_cone_angle, outer_cone_angle), (0.2, 0.4)),
        _ => panic!("expected a spot light"),
    }
    assert!(lights[1].extras().is_none());

    let camera = document.cameras().next().unwrap();
    assert_eq!(camera.name(), Some("main"));
    match camera.projection() {
        gltf::camera::Projection::Perspective(p) => {
            assert_eq!((p.yfov(), p.znear(), p.zfar()), (0.8, 0.1, None));
        }
        gltf::camera::Projection::Orthographic(_) => panic!("expected perspective"),
    }
}

#[test]
fn embedded_gltf_imports() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.gltf");
    sample().write_gltf(&path).unwrap();
    let (document, buffers, _) = gltf::import(&path).unwrap();
    check(&document, &buffers);
    assert_eq!(std::fs::read_dir(dir.path()).unwrap().count(), 1);
}

#[test]
fn gltf_with_external_bin_imports() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("sub dir/my scene.gltf");
    sample().write_gltf_with_bin(&path).unwrap();
    assert!(dir.path().join("sub dir/my scene.bin").exists());
    let (document, buffers, _) = gltf::import(&path).unwrap();
    check(&document, &buffers);
}

#[test]
fn glb_imports() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.glb");
    sample().write_glb(&path).unwrap();
    let (document, buffers, _) = gltf::import(&path).unwrap();
    check(&document, &buffers);
    let glb = sample().to_glb();
    assert_eq!(glb.len() % 4, 0);
    assert!(gltf::Gltf::from_slice(&glb).is_ok());
}

#[test]
fn extensions_are_declared() {
    let json = sample().to_embedded_json();
    let used: Vec<&str> = json["extensionsUsed"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_str().unwrap())
        .collect();
    assert_eq!(
        used,
        [
            "KHR_lights_punctual",
            "KHR_materials_emissive_strength",
            "KHR_materials_ior",
            "KHR_materials_transmission"
        ]
    );
    let red = &json["materials"][1];
    assert_eq!(
        red["extensions"]["KHR_materials_emissive_strength"]["emissiveStrength"],
        4.0
    );
}

#[test]
fn bad_input_is_refused_with_a_name() {
    let mut builder = GltfBuilder::new();
    let mut geometry = shapes::plane(Vec2::ONE);
    geometry.indices.push(99);
    let message = builder.add_geometry(&geometry).unwrap_err().to_string();
    assert!(message.contains("geometry #0"), "{message}");
    geometry.indices.truncate(6);
    geometry.positions[0].x = f32::NAN;
    assert!(builder.add_geometry(&geometry).is_err());

    let message = builder
        .add_light(&Light {
            name: Some("Bad".into()),
            kind: LightKind::Spot {
                inner_cone: 0.5,
                outer_cone: 0.4,
            },
            color: Vec3::ONE,
            intensity: 1.0,
            range: None,
            radius: None,
            group: None,
        })
        .unwrap_err()
        .to_string();
    assert!(message.contains("light `Bad`"), "{message}");

    let leaf = builder.add_node(NodeDesc::named("Leaf")).unwrap();
    builder
        .add_node(NodeDesc {
            children: vec![leaf],
            ..NodeDesc::named("Parent")
        })
        .unwrap();
    let message = builder
        .add_node(NodeDesc {
            children: vec![leaf],
            ..NodeDesc::named("Second")
        })
        .unwrap_err()
        .to_string();
    assert!(
        message.contains("node `Second`") && message.contains("parent"),
        "{message}"
    );
    let unnormalised = NodeDesc {
        rotation: Quat::from_xyzw(0.0, 0.0, 0.0, 2.0),
        ..NodeDesc::named("Skewed")
    };
    assert!(builder.add_node(unnormalised).is_err());
}

#[test]
fn the_sample_animation_imports() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("animations/courtyard.gltf");
    let size = std::fs::metadata(&path).unwrap().len();
    assert!(size < 200_000, "courtyard.gltf is {size} bytes");
    let (document, _, _) = gltf::import(&path).unwrap();
    let camera = document.nodes().find(|n| n.camera().is_some()).unwrap();
    assert_eq!(camera.name(), Some("main"));
    let lights: Vec<_> = document.lights().unwrap().collect();
    let points = lights
        .iter()
        .filter(|l| matches!(l.kind(), gltf::khr_lights_punctual::Kind::Point))
        .count();
    assert_eq!(points, 3);
    assert!(document.materials().any(|m| m.transmission().is_some()));
}
