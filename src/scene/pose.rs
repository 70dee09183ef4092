//! Where everything is at one instant: world transforms of the nodes, the
//! joint matrices of every skin, the morph weights of every node, and the
//! light, camera and material values that KHR_animation_pointer channels
//! animate. The rest pose (the file's own values) is built here;
//! [`crate::anim`] samples clips into the same [`Pose`] (`Pose::at`), so
//! that nothing downstream knows whether a scene is animated.
//!
//! Transforms are composed in `f64`: a scene placed 100 km from the origin
//! keeps millimetre precision until the renderer subtracts its anchor.

use glam::DMat4;

use super::{Light, Material, Projection, SceneDesc};

/// A posed scene, indexed like the scene's own arrays.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// World transform of every node, indexed like `SceneDesc::nodes`.
    pub world: Vec<DMat4>,
    /// Per skin (indexed like `SceneDesc::skins`), per joint:
    /// `world(joint) · inverse_bind(joint)`, which takes bind-space vertices
    /// to world space. As the glTF spec says, the skinned node's own
    /// transform plays no part.
    pub joints: Vec<Vec<DMat4>>,
    /// Per node, the morph weights of its mesh; empty for nodes without a
    /// mesh that has morph targets.
    pub weights: Vec<Vec<f32>>,
    pub properties: Properties,
}

/// The lights, camera projections and materials at one instant, indexed
/// like the scene's arrays: the file's own at rest, with the values
/// KHR_animation_pointer channels give them when animated. Whole copies
/// rather than the animated numbers alone, so that everything downstream
/// reads a light, camera or material from one place.
#[derive(Clone, Debug, PartialEq)]
pub struct Properties {
    pub lights: Vec<Light>,
    pub cameras: Vec<Projection>,
    pub materials: Vec<Material>,
}

impl Properties {
    /// The file's own values.
    pub fn rest(scene: &SceneDesc) -> Properties {
        Properties {
            lights: scene.lights.clone(),
            cameras: scene
                .cameras
                .iter()
                .map(|camera| camera.projection)
                .collect(),
            materials: scene.materials.clone(),
        }
    }
}

impl Pose {
    /// The pose given by the nodes' own transforms and default weights,
    /// and the file's lights, cameras and materials.
    pub fn rest(scene: &SceneDesc) -> Pose {
        let locals: Vec<DMat4> = scene.nodes.iter().map(|node| node.local).collect();
        Pose::from_locals(
            scene,
            &locals,
            default_weights(scene),
            Properties::rest(scene),
        )
    }

    /// Composes local transforms (one per node) down the tree, and the skin
    /// matrices from the result. Import has already rejected node cycles,
    /// so the walk from the roots terminates.
    pub fn from_locals(
        scene: &SceneDesc,
        locals: &[DMat4],
        weights: Vec<Vec<f32>>,
        properties: Properties,
    ) -> Pose {
        let mut world = vec![DMat4::IDENTITY; scene.nodes.len()];
        let mut stack: Vec<(usize, DMat4)> = scene
            .roots
            .iter()
            .map(|&root| (root, DMat4::IDENTITY))
            .collect();
        while let Some((index, parent)) = stack.pop() {
            let placed = parent * locals[index];
            world[index] = placed;
            stack.extend(
                scene.nodes[index]
                    .children
                    .iter()
                    .map(|&child| (child, placed)),
            );
        }
        let joints = scene
            .skins
            .iter()
            .map(|skin| {
                skin.joints
                    .iter()
                    .zip(&skin.inverse_bind)
                    .map(|(&joint, inverse_bind)| world[joint] * *inverse_bind)
                    .collect()
            })
            .collect();
        Pose {
            world,
            joints,
            weights,
            properties,
        }
    }
}

/// Each node's default morph weights: the node's own, else its mesh's;
/// empty for nodes whose mesh has no morph targets. Import has checked that
/// the counts match the targets.
pub fn default_weights(scene: &SceneDesc) -> Vec<Vec<f32>> {
    scene
        .nodes
        .iter()
        .map(|node| {
            let Some(mesh) = node.mesh.and_then(|mesh| scene.meshes.get(mesh)) else {
                return Vec::new();
            };
            if mesh.morph_targets.is_empty() {
                return Vec::new();
            }
            node.weights
                .clone()
                .unwrap_or_else(|| mesh.morph_weights.clone())
        })
        .collect()
}

/// Which nodes may move or deform: a node is dynamic when it, or any node
/// above it, is animated, or when its own mesh deforms. Everything else is
/// static and goes into the structure built once per sequence.
pub fn dynamic_nodes(scene: &SceneDesc) -> Vec<bool> {
    dynamic_nodes_where(scene, |node| scene.nodes[node].animated)
}

/// [`dynamic_nodes`] with `animated` saying which nodes a channel moves:
/// a node is dynamic when it, or any node above it, is `animated`, or
/// when its own mesh deforms.
pub fn dynamic_nodes_where(scene: &SceneDesc, animated: impl Fn(usize) -> bool) -> Vec<bool> {
    let mut dynamic = vec![false; scene.nodes.len()];
    let mut stack: Vec<(usize, bool)> = scene.roots.iter().map(|&root| (root, false)).collect();
    while let Some((index, parent_moves)) = stack.pop() {
        let node = &scene.nodes[index];
        let moves = parent_moves || animated(index);
        dynamic[index] = moves || node.deforms;
        stack.extend(node.children.iter().map(|&child| (child, moves)));
    }
    dynamic
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::Node;
    use glam::DVec3;

    fn node(local: DMat4, children: Vec<usize>) -> Node {
        Node {
            local,
            children,
            ..Node::default()
        }
    }

    #[test]
    fn rest_pose_composes_parent_before_child() {
        let scene = SceneDesc {
            nodes: vec![
                node(DMat4::from_translation(DVec3::new(1e5, 0.0, 0.0)), vec![1]),
                node(DMat4::from_scale(DVec3::splat(2.0)), vec![]),
            ],
            roots: vec![0],
            ..SceneDesc::default()
        };
        let pose = Pose::rest(&scene);
        let p = pose.world[1].transform_point3(DVec3::new(0.25, 0.0, 0.0));
        assert_eq!(p, DVec3::new(100_000.5, 0.0, 0.0));
    }

    #[test]
    fn animation_makes_the_subtree_dynamic_and_deformation_only_the_node() {
        let mut scene = SceneDesc {
            nodes: vec![
                node(DMat4::IDENTITY, vec![1]),
                node(DMat4::IDENTITY, vec![2]),
                node(DMat4::IDENTITY, vec![]),
                node(DMat4::IDENTITY, vec![4]),
                node(DMat4::IDENTITY, vec![]),
            ],
            roots: vec![0, 3],
            ..SceneDesc::default()
        };
        scene.nodes[1].animated = true;
        scene.nodes[3].deforms = true;
        assert_eq!(dynamic_nodes(&scene), vec![false, true, true, true, false]);
    }
}
