//! World placement of every node at one instant. For now this is the rest
//! pose (the nodes' own TRS); the animation module will sample clips into the
//! same [`Pose`] so that nothing downstream changes.
//!
//! Transforms are composed in `f64`: a scene placed 100 km from the origin
//! keeps millimetre precision until the renderer subtracts its anchor.

use glam::DMat4;

use super::SceneDesc;

/// World transform of every node, indexed like `SceneDesc::nodes`.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    pub world: Vec<DMat4>,
}

impl Pose {
    /// The pose given by the nodes' own transforms. Import has already
    /// rejected node cycles, so the walk from the roots terminates.
    pub fn rest(scene: &SceneDesc) -> Pose {
        let mut world = vec![DMat4::IDENTITY; scene.nodes.len()];
        let mut stack: Vec<(usize, DMat4)> = scene
            .roots
            .iter()
            .map(|&root| (root, DMat4::IDENTITY))
            .collect();
        while let Some((index, parent)) = stack.pop() {
            let node = &scene.nodes[index];
            let placed = parent * node.local;
            world[index] = placed;
            stack.extend(node.children.iter().map(|&child| (child, placed)));
        }
        Pose { world }
    }
}

/// Which nodes may move or deform: a node is dynamic when it, or any node
/// above it, is animated, or when its own mesh deforms. Everything else is
/// static and goes into the structure built once per sequence.
pub fn dynamic_nodes(scene: &SceneDesc) -> Vec<bool> {
    let mut dynamic = vec![false; scene.nodes.len()];
    let mut stack: Vec<(usize, bool)> = scene.roots.iter().map(|&root| (root, false)).collect();
    while let Some((index, parent_moves)) = stack.pop() {
        let node = &scene.nodes[index];
        let moves = parent_moves || node.animated;
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
