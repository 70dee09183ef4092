//! Animated files import as the authoring builder wrote them: clips,
//! skins, every JOINTS_n/WEIGHTS_n set (normalised) and morph targets with
//! default weights. (KHR_animation_pointer channels: `anim_pointer.rs`.)

mod anim_support;

use lmanim::scene::{Interpolation, JointSet, Skin, Target};
use lmanim_authoring::{shapes, GltfBuilder, NodeDesc, Primitive};

#[test]
fn clips_skins_and_morph_targets_import_as_written() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = lmanim::import::load(&anim_support::skinned(dir.path())).expect("import");
    assert_eq!(scene.animations.len(), 1);
    let clip = &scene.animations[0];
    assert_eq!(clip.name.as_deref(), Some("bend"));
    let targets: Vec<Target> = clip.channels.iter().map(|c| c.target).collect();
    assert_eq!(
        targets,
        vec![
            Target::Rotation(1),
            Target::Rotation(2),
            Target::Scale(0),
            Target::Weights(3)
        ]
    );
    let cubic = &clip.channels[1].sampler;
    assert_eq!(cubic.interpolation, Interpolation::CubicSpline);
    assert_eq!(cubic.values.len(), 2 * 3 * 4);
    assert_eq!(clip.channels[3].sampler.width, 1);

    assert_eq!(scene.skins.len(), 1);
    let skin = &scene.skins[0];
    assert_eq!(skin.joints, vec![2, 1, 0]);
    assert_eq!(skin.skeleton, Some(2));
    let strip = &scene.nodes[3];
    assert_eq!(strip.skin, Some(0));
    assert!(strip.deforms);
    let mesh = &scene.meshes[strip.mesh.expect("mesh")];
    assert_eq!(mesh.joint_sets.len(), 1);
    assert_eq!(mesh.joint_sets[0].weights[2], [0.5, 0.5, 0.0, 0.0]);
    assert_eq!(mesh.morph_targets.len(), 1);
    assert_eq!(mesh.morph_weights, vec![0.5]);

    let morph = lmanim::import::load(&anim_support::morph(dir.path())).expect("import");
    assert_eq!(morph.nodes[0].weights, Some(vec![0.3, 0.0]));
    assert_eq!(morph.meshes[0].morph_targets[0].normals.len(), 4);
    assert!(morph.meshes[0].morph_targets[1].normals.is_empty());
}

#[test]
fn joint_sets_beyond_the_first_are_read_and_weights_normalised() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut b = GltfBuilder::new();
    let mut geometry = shapes::plane(glam::Vec2::ONE);
    let count = geometry.positions.len();
    // Weights sum to 2 over both sets, except one vertex with all zeros.
    let mut second = vec![[0.5, 0.5, 0.0, 0.0]; count];
    second[3] = [0.0; 4];
    let mut first = vec![[1.0, 0.0, 0.0, 0.0]; count];
    first[3] = [0.0; 4];
    geometry.joint_sets = vec![
        JointSet {
            joints: vec![[1, 0, 0, 0]; count],
            weights: first,
        },
        JointSet {
            joints: vec![[0, 1, 0, 0]; count],
            weights: second,
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
    let a = b.add_node(NodeDesc::named("a")).expect("node");
    let c = b.add_node(NodeDesc::named("c")).expect("node");
    let skin = b
        .add_skin(&Skin {
            joints: vec![a.index(), c.index()],
            inverse_bind: vec![glam::DMat4::IDENTITY; 2],
            ..Skin::default()
        })
        .expect("skin");
    b.add_node(NodeDesc {
        mesh: Some(mesh),
        skin: Some(skin),
        ..NodeDesc::named("skinned")
    })
    .expect("node");
    let path = dir.path().join("two_sets.glb");
    b.write_glb(&path).expect("write");

    let scene = lmanim::import::load(&path).expect("import");
    let sets = &scene.meshes[0].joint_sets;
    assert_eq!(sets.len(), 2);
    assert_eq!(sets[0].weights[0], [0.5, 0.0, 0.0, 0.0]);
    assert_eq!(sets[1].weights[0], [0.25, 0.25, 0.0, 0.0]);
    // All-zero weights bind the vertex to its first JOINTS_0 slot.
    assert_eq!(sets[0].weights[3], [1.0, 0.0, 0.0, 0.0]);
    assert_eq!(sets[1].weights[3], [0.0; 4]);
    assert_eq!(sets[0].joints[3], [1, 0, 0, 0]);
}
