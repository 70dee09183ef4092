//! Import of a scene that uses every feature import supports, written by the
//! test in all three storage forms (data URI, external .bin, .glb) and
//! checked field by field.

mod import_support;

use std::f32::consts::FRAC_1_SQRT_2;
use std::path::Path;

use glam::{DMat4, DQuat, DVec3, Vec2, Vec3, Vec4};
use lmanim::import::load;
use lmanim::scene::pose::Pose;
use lmanim::scene::{LightKind, Projection, SceneDesc, TextureRef, Wrap};
use serde_json::{json, Value};

use import_support::{base64, Bin, TRIANGLE};

/// A 2×1 PNG: an sRGB mid grey (188) and opaque red, half-transparent.
fn png() -> Vec<u8> {
    let mut image = image::RgbaImage::new(2, 1);
    image.put_pixel(0, 0, image::Rgba([188, 188, 188, 255]));
    image.put_pixel(1, 0, image::Rgba([255, 0, 0, 128]));
    let mut png = Vec::new();
    image
        .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
        .expect("encode PNG");
    png
}

fn png_data_uri() -> String {
    format!("data:image/png;base64,{}", base64(&png()))
}

/// The feature scene: its document and buffer.
fn feature_scene() -> (Value, Bin) {
    let mut bin = Bin::default();
    // Mesh 0, primitive 0: an indexed quad with normals and UVs.
    let quad = [
        [0.0, 0.0, 0.0],
        [1.0, 0.0, 0.0],
        [1.0, 1.0, 0.0],
        [0.0, 1.0, 0.0],
    ];
    let quad_positions = bin.vec3(&quad);
    let quad_normals = bin.vec3(&[[0.0, 0.0, 2.0]; 4]); // not unit: import normalizes
    let quad_uvs = bin.vec2(&[[0.0, 1.0], [1.0, 1.0], [1.0, 0.0], [0.0, 0.0]]);
    let quad_indices = bin.indices_u16(&[0, 1, 2, 0, 2, 3]);
    // Primitive 1: a non-indexed triangle in the XZ plane, no normals, no material.
    let flat = bin.vec3(&[[0.0, 0.0, 0.0], [0.0, 0.0, 1.0], [1.0, 0.0, 0.0]]);
    // Primitive 2: a strip of two triangles with u8 indices.
    let strip = [
        [0.0, 0.0, 5.0],
        [1.0, 0.0, 5.0],
        [0.0, 1.0, 5.0],
        [1.0, 1.0, 5.0],
    ];
    let strip_positions = bin.vec3(&strip);
    let strip_indices = bin.indices_u8(&[0, 1, 2, 3]);
    // Primitive 3: points, skipped.
    let points = bin.vec3(&[[9.0, 9.0, 9.0]]);
    // Mesh 1: one triangle; mesh 2: one triangle with a morph target.
    let triangle = bin.vec3(&TRIANGLE);
    let morph_offsets = bin.vec3(&[[0.0, 0.0, 1.0]; 3]);
    let times = bin.scalars(&[0.0, 1.0]);
    let translations = bin.vec3(&[[0.0; 3], [0.0, 1.0, 0.0]]);
    let weights = bin.scalars(&[0.0, 1.0]);

    let s = FRAC_1_SQRT_2;
    let doc = json!({
        "asset": { "version": "2.0" },
        "extensionsUsed": ["KHR_lights_punctual", "KHR_materials_transmission", "KHR_materials_ior"],
        "extensionsRequired": ["KHR_materials_transmission"],
        "scene": 1,
        "scenes": [
            { "name": "not the default", "nodes": [4] },
            { "name": "main", "nodes": [0, 4, 5, 6, 7, 8, 9] },
        ],
        "nodes": [
            { "name": "root", "translation": [1.0, 2.0, 3.0], "rotation": [0.0, s, 0.0, s],
              "scale": [2.0, 2.0, 2.0], "children": [1, 2] },
            { "name": "by matrix", "mesh": 0,
              "matrix": [0.5, 0.0, 0.0, 0.0,  0.0, 0.5, 0.0, 0.0,  0.0, 0.0, 0.5, 0.0,  0.0, 0.0, -5.0, 1.0] },
            { "name": "lamp", "translation": [0.0, 3.0, 0.0], "children": [3],
              "extensions": { "KHR_lights_punctual": { "light": 0 } } },
            { "name": "spot", "extensions": { "KHR_lights_punctual": { "light": 1 } } },
            { "name": "sun", "rotation": [-s, 0.0, 0.0, s],
              "extensions": { "KHR_lights_punctual": { "light": 2 } } },
            { "name": "main camera", "camera": 0, "translation": [0.0, 1.0, 10.0] },
            { "name": "plan view", "camera": 1 },
            { "name": "mover", "mesh": 1 },
            { "name": "skinned", "mesh": 1, "skin": 0 },
            { "name": "morphing", "mesh": 2 },
        ],
        "meshes": [
            { "name": "merged", "primitives": [
                { "attributes": { "POSITION": quad_positions, "NORMAL": quad_normals,
                                  "TEXCOORD_0": quad_uvs },
                  "indices": quad_indices, "material": 0 },
                { "attributes": { "POSITION": flat } },
                { "attributes": { "POSITION": strip_positions }, "indices": strip_indices,
                  "mode": 5, "material": 1 },
                { "attributes": { "POSITION": points }, "mode": 0 },
            ] },
            { "name": "triangle", "primitives": [{ "attributes": { "POSITION": triangle } }] },
            { "name": "morph", "weights": [0.0], "primitives": [{
                "attributes": { "POSITION": triangle },
                "targets": [{ "POSITION": morph_offsets }] }] },
        ],
        "skins": [{ "joints": [8] }],
        "animations": [{
            "channels": [
                { "sampler": 0, "target": { "node": 7, "path": "translation" } },
                { "sampler": 1, "target": { "node": 9, "path": "weights" } },
            ],
            "samplers": [
                { "input": times, "output": translations },
                { "input": times, "output": weights },
            ],
        }],
        "materials": [
            { "name": "glass", "doubleSided": true,
              "pbrMetallicRoughness": { "baseColorFactor": [0.9, 0.8, 0.7, 0.5],
                  "metallicFactor": 0.0, "roughnessFactor": 0.1,
                  "baseColorTexture": { "index": 0 } },
              "emissiveFactor": [0.1, 0.2, 0.3],
              "extensions": {
                  "KHR_materials_transmission": { "transmissionFactor": 0.9 },
                  "KHR_materials_ior": { "ior": 1.33 } } },
            { "name": "glow", "emissiveTexture": { "index": 0 } },
        ],
        "textures": [{ "source": 0, "sampler": 0 }],
        "samplers": [{ "wrapS": 33648, "wrapT": 33071 }],
        "images": [{ "uri": png_data_uri() }],
        "extensions": { "KHR_lights_punctual": { "lights": [
            { "name": "bulb", "type": "point", "color": [1.0, 0.5, 0.25], "intensity": 10.0,
              "range": 20.0, "extras": { "radius": 0.05 } },
            { "type": "spot", "intensity": 4.0, "range": 5.0,
              "spot": { "innerConeAngle": 0.2, "outerConeAngle": 0.5 } },
            { "name": "sun", "type": "directional", "intensity": 3.0 },
        ] } },
        "cameras": [
            { "name": "lens", "type": "perspective",
              "perspective": { "yfov": 0.8, "aspectRatio": 1.5, "znear": 0.1, "zfar": 100.0 } },
            { "type": "orthographic",
              "orthographic": { "xmag": 2.0, "ymag": 1.0, "znear": 0.01, "zfar": 50.0 } },
        ],
    });
    (doc, bin)
}

fn assert_close(a: DMat4, b: DMat4) {
    assert!(a.abs_diff_eq(b, 1e-6), "{a:?}\n!=\n{b:?}");
}

/// Everything the feature scene should import to, whatever its storage.
fn check_feature_scene(scene: &SceneDesc, stem: &str) {
    assert_eq!(scene.name, stem);

    // Node tree: the default scene's roots, the file's indices and names.
    assert_eq!(scene.roots, vec![0, 4, 5, 6, 7, 8, 9]);
    assert_eq!(scene.nodes.len(), 10);
    let names: Vec<_> = scene.nodes.iter().map(|n| n.name.as_deref()).collect();
    assert_eq!(names[0], Some("root"));
    assert_eq!(names[9], Some("morphing"));
    assert_eq!(scene.nodes[0].children, vec![1, 2]);
    assert_eq!(scene.nodes[2].children, vec![3]);
    let half = std::f64::consts::FRAC_1_SQRT_2;
    let root_local = DMat4::from_scale_rotation_translation(
        DVec3::splat(2.0),
        DQuat::from_rotation_y(std::f64::consts::FRAC_PI_2),
        DVec3::new(1.0, 2.0, 3.0),
    );
    assert!((half - f64::from(FRAC_1_SQRT_2)).abs() < 1e-7);
    assert_close(scene.nodes[0].local, root_local);
    let matrix_local = DMat4::from_scale_rotation_translation(
        DVec3::splat(0.5),
        DQuat::IDENTITY,
        DVec3::new(0.0, 0.0, -5.0),
    );
    assert_eq!(scene.nodes[1].local, matrix_local);
    // World placement composes parent before child: the matrix node's
    // origin is the root's transform of (0, 0, -5).
    let pose = Pose::rest(scene);
    let origin = pose.world[1].transform_point3(DVec3::ZERO);
    assert!(
        origin.abs_diff_eq(DVec3::new(-9.0, 2.0, 3.0), 1e-6),
        "{origin}"
    );

    // What hangs off nodes.
    assert_eq!(scene.nodes[1].mesh, Some(0));
    assert_eq!(scene.nodes[2].light, Some(0));
    assert_eq!(scene.nodes[3].light, Some(1));
    assert_eq!(scene.nodes[4].light, Some(2));
    assert_eq!(scene.nodes[5].camera, Some(0));
    assert_eq!(scene.nodes[6].camera, Some(1));
    assert_eq!(scene.camera_node(Some("main camera")), Some(5));
    assert_eq!(scene.camera_node(Some("lens")), Some(5));
    assert_eq!(scene.camera_node(None), Some(5));

    // Animation flags: translation moves node 7; a skin deforms node 8;
    // animated weights on a mesh with morph targets deform node 9.
    let flags: Vec<_> = scene
        .nodes
        .iter()
        .map(|n| (n.animated, n.deforms))
        .collect();
    let mut expected = vec![(false, false); 10];
    expected[7] = (true, false);
    expected[8] = (false, true);
    expected[9] = (false, true);
    assert_eq!(flags, expected);

    check_merged_mesh(scene);
    check_materials(scene);
    check_lights_and_cameras(scene);
}

fn check_merged_mesh(scene: &SceneDesc) {
    assert_eq!(scene.meshes.len(), 3);
    let mesh = &scene.meshes[0];
    assert_eq!(mesh.name.as_deref(), Some("merged"));
    // 4 quad + 3 flat + 4 strip vertices; the points primitive is skipped.
    assert_eq!(mesh.positions.len(), 11);
    assert_eq!(mesh.positions[4], Vec3::ZERO);
    assert_eq!(mesh.positions[10], Vec3::new(1.0, 1.0, 5.0));
    assert_eq!(
        mesh.triangles,
        vec![[0, 1, 2], [0, 2, 3], [4, 5, 6], [7, 8, 9], [8, 10, 9]]
    );
    // Material 2 is the default one appended for the primitive without one.
    assert_eq!(mesh.triangle_materials, vec![0, 0, 2, 1, 1]);
    // File normals normalized; the flat triangle's generated normal is its
    // face normal (+Y for this winding); the strip's is +Z.
    assert_eq!(&mesh.normals[..4], &[Vec3::Z; 4]);
    assert_eq!(&mesh.normals[4..7], &[Vec3::Y; 3]);
    assert_eq!(&mesh.normals[7..], &[Vec3::Z; 4]);
    // UVs are parallel to positions: zeros where a primitive had none.
    assert_eq!(mesh.uvs.len(), 11);
    assert_eq!(mesh.uvs[0], Vec2::new(0.0, 1.0));
    assert_eq!(mesh.uvs[2], Vec2::new(1.0, 0.0));
    assert!(mesh.uvs[4..].iter().all(|uv| *uv == Vec2::ZERO));

    assert_eq!(scene.meshes[1].triangles, vec![[0, 1, 2]]);
    assert!(scene.meshes[1].uvs.is_empty());
    assert_eq!(scene.meshes[1].normals, vec![Vec3::Z; 3]);
    assert_eq!(scene.meshes[1].triangle_materials, vec![2]);
}

fn check_materials(scene: &SceneDesc) {
    assert_eq!(scene.materials.len(), 3);
    let glass = &scene.materials[0];
    assert_eq!(glass.name.as_deref(), Some("glass"));
    assert_eq!(glass.base_color, Vec4::new(0.9, 0.8, 0.7, 0.5));
    assert_eq!((glass.metallic, glass.roughness), (0.0, 0.1));
    assert_eq!(glass.emissive, Vec3::new(0.1, 0.2, 0.3));
    assert!(glass.double_sided);
    assert_eq!(glass.transmission, 0.9);
    assert_eq!(glass.ior, 1.33);
    let texture = Some(TextureRef {
        texture: 0,
        tex_coord: 0,
    });
    assert_eq!(glass.base_color_texture, texture);
    assert_eq!(glass.emissive_texture, None);

    let glow = &scene.materials[1];
    assert_eq!(glow.emissive_texture, texture);
    assert_eq!((glow.metallic, glow.roughness, glow.ior), (1.0, 1.0, 1.5));
    assert_eq!(glow.transmission, 0.0);
    assert!(!glow.double_sided);

    let default = &scene.materials[2];
    assert_eq!(default.name, None);
    assert_eq!(default.base_color, Vec4::ONE);

    // One texture, decoded once for both materials, sRGB → linear.
    assert_eq!(scene.textures.len(), 1);
    let texture = &scene.textures[0];
    assert_eq!((texture.width, texture.height), (2, 1));
    assert_eq!(
        (texture.wrap_s, texture.wrap_t),
        (Wrap::MirroredRepeat, Wrap::ClampToEdge)
    );
    let grey = texture.texels[0];
    assert!(
        (grey.x - 0.5).abs() < 0.005 && grey.x == grey.y && grey.y == grey.z,
        "{grey}"
    );
    assert_eq!(grey.w, 1.0);
    assert_eq!(texture.texels[1].truncate(), Vec3::X);
    assert!(
        (texture.texels[1].w - 128.0 / 255.0).abs() < 1e-6,
        "alpha stays linear"
    );
}

fn check_lights_and_cameras(scene: &SceneDesc) {
    assert_eq!(scene.lights.len(), 3);
    let bulb = &scene.lights[0];
    assert_eq!(bulb.name.as_deref(), Some("bulb"));
    assert_eq!(bulb.kind, LightKind::Point);
    assert_eq!(bulb.color, Vec3::new(1.0, 0.5, 0.25));
    assert_eq!(bulb.intensity, 10.0);
    assert_eq!(bulb.range, Some(20.0));
    assert_eq!(bulb.radius, Some(0.05));
    let spot = &scene.lights[1];
    assert_eq!(
        spot.kind,
        LightKind::Spot {
            inner_cone: 0.2,
            outer_cone: 0.5
        }
    );
    assert_eq!(
        (spot.intensity, spot.range, spot.radius),
        (4.0, Some(5.0), None)
    );
    assert_eq!(spot.color, Vec3::ONE);
    let sun = &scene.lights[2];
    assert_eq!(sun.kind, LightKind::Directional);
    assert_eq!((sun.intensity, sun.range), (3.0, None));

    assert_eq!(scene.cameras.len(), 2);
    assert_eq!(scene.cameras[0].name.as_deref(), Some("lens"));
    assert_eq!(
        scene.cameras[0].projection,
        Projection::Perspective {
            yfov: 0.8,
            aspect_ratio: Some(1.5),
            znear: 0.1,
            zfar: Some(100.0)
        }
    );
    assert_eq!(
        scene.cameras[1].projection,
        Projection::Orthographic {
            xmag: 2.0,
            ymag: 1.0,
            znear: 0.01,
            zfar: 50.0
        }
    );
}

fn load_ok(path: &Path) -> SceneDesc {
    load(path).unwrap_or_else(|error| panic!("{error}"))
}

#[test]
fn gltf_with_embedded_buffer_imports_every_feature() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (doc, bin) = feature_scene();
    let path = bin.write_embedded(doc, dir.path(), "features.gltf");
    check_feature_scene(&load_ok(&path), "features");
}

#[test]
fn gltf_with_external_buffer_imports_the_same() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (doc, bin) = feature_scene();
    let path = bin.write_external(doc, dir.path(), "external.gltf", "feature data.bin");
    check_feature_scene(&load_ok(&path), "external");
}

#[test]
fn glb_imports_the_same() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (doc, bin) = feature_scene();
    let path = bin.write_glb(doc, dir.path(), "binary.glb");
    check_feature_scene(&load_ok(&path), "binary");
}

#[test]
fn without_a_default_scene_the_first_scene_is_used() {
    let dir = tempfile::tempdir().expect("tempdir");
    let (mut doc, bin) = feature_scene();
    doc.as_object_mut().expect("object").remove("scene");
    let path = bin.write_embedded(doc, dir.path(), "first.gltf");
    assert_eq!(load_ok(&path).roots, vec![4]);
}

#[test]
fn a_file_whose_primitives_all_have_materials_gets_no_default_material() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut bin = Bin::default();
    let positions = bin.vec3(&TRIANGLE);
    let mut doc = import_support::one_triangle_document(
        json!({ "attributes": { "POSITION": positions }, "material": 0 }),
    );
    doc["materials"] = json!([{ "name": "only" }]);
    let path = bin.write_embedded(doc, dir.path(), "no_default.gltf");
    let scene = load_ok(&path);
    assert_eq!(scene.materials.len(), 1);
    assert_eq!(scene.meshes[0].triangle_materials, vec![0]);
}

#[test]
fn glb_images_may_live_in_a_buffer_view() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut bin = Bin::default();
    let positions = bin.vec3(&TRIANGLE);
    let image_view = bin.view(&png());
    let mut doc = import_support::one_triangle_document(
        json!({ "attributes": { "POSITION": positions }, "material": 0 }),
    );
    doc["materials"] = json!([{ "pbrMetallicRoughness": { "baseColorTexture": { "index": 0 } } }]);
    doc["textures"] = json!([{ "source": 0 }]);
    doc["images"] = json!([{ "bufferView": image_view, "mimeType": "image/png" }]);
    let scene = load_ok(&bin.write_glb(doc, dir.path(), "image_in_view.glb"));
    assert_eq!(scene.textures.len(), 1);
    let texture = &scene.textures[0];
    assert_eq!((texture.width, texture.height), (2, 1));
    // A sampler-less texture repeats, as the glTF spec says.
    assert_eq!(
        (texture.wrap_s, texture.wrap_t),
        (Wrap::Repeat, Wrap::Repeat)
    );
    assert_eq!(texture.texels[1].truncate(), Vec3::X);
}

#[test]
fn sparse_accessors_replace_the_listed_elements() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut bin = Bin::default();
    let positions = bin.vec3(&TRIANGLE);
    bin.sparse(positions, &[2], &[[5.0, 5.0, 5.0]]);
    let doc =
        import_support::one_triangle_document(json!({ "attributes": { "POSITION": positions } }));
    let scene = load_ok(&bin.write_embedded(doc, dir.path(), "sparse.gltf"));
    assert_eq!(
        scene.meshes[0].positions,
        vec![Vec3::ZERO, Vec3::X, Vec3::splat(5.0)]
    );
}
