//! The node tree: local transforms in `f64`, the tree's shape checked (one
//! parent per node, no cycles, roots without parents), the scene's roots, and
//! which nodes animation will move or deform (once the clips are read).
//!
//! Node indices stay the file's, so that animation channels, skins and
//! error messages can name nodes as the file does.

use glam::{DMat4, DQuat, DVec3};
use gltf::scene::Transform;

use super::error::Fault;
use crate::scene::{AnimationClip, Node, Target};

/// All nodes of the file and the roots of the scene to render (the default
/// scene, or the first one). Skinned nodes deform; what the clips move or
/// deform is marked by [`mark_motion`].
pub fn import(document: &gltf::Document) -> Result<(Vec<Node>, Vec<usize>), Fault> {
    let parents = parents(document)?;
    check_acyclic(&parents)?;
    let roots = roots(document, &parents)?;
    let nodes = document
        .nodes()
        .map(|node| {
            Ok(Node {
                name: node.name().map(str::to_owned),
                local: local_transform(&node)?,
                children: node.children().map(|child| child.index()).collect(),
                mesh: node.mesh().map(|mesh| mesh.index()),
                light: node.light().map(|light| light.index()),
                camera: node.camera().map(|camera| camera.index()),
                animated: false,
                deforms: node.skin().is_some(),
                skin: node.skin().map(|skin| skin.index()),
                weights: node.weights().map(<[f32]>::to_vec),
            })
        })
        .collect::<Result<Vec<_>, Fault>>()?;
    Ok((nodes, roots))
}

/// The node's matrix, or its TRS composed as T·R·S. The rotation is
/// normalized: exporters write quaternions a few ULPs off unit length.
fn local_transform(node: &gltf::Node) -> Result<DMat4, Fault> {
    let fault = |problem| Fault::NodeTransform {
        node: node.index(),
        problem,
    };
    let wide = |values: &[f32]| values.iter().map(|&v| f64::from(v)).collect::<Vec<_>>();
    match node.transform() {
        Transform::Matrix { matrix } => {
            let local = DMat4::from_cols_slice(&wide(matrix.as_flattened()));
            if local.is_finite() {
                Ok(local)
            } else {
                Err(fault("matrix"))
            }
        }
        Transform::Decomposed {
            translation,
            rotation,
            scale,
        } => {
            let translation = DVec3::from_slice(&wide(&translation));
            let scale = DVec3::from_slice(&wide(&scale));
            let rotation = DQuat::from_slice(&wide(&rotation));
            if !translation.is_finite() {
                return Err(fault("translation"));
            }
            if !scale.is_finite() {
                return Err(fault("scale"));
            }
            let length = rotation.length();
            if !length.is_finite() || length < 1e-6 {
                return Err(fault("rotation"));
            }
            Ok(DMat4::from_scale_rotation_translation(
                scale,
                rotation / length,
                translation,
            ))
        }
    }
}

/// Each node's parent, after checking that no node has two.
fn parents(document: &gltf::Document) -> Result<Vec<Option<usize>>, Fault> {
    let mut parents = vec![None; document.nodes().len()];
    for node in document.nodes() {
        for child in node.children() {
            let (parent, child) = (node.index(), child.index());
            if parent == child {
                return Err(Fault::NodeCycle { node: child });
            }
            match parents[child] {
                None => parents[child] = Some(parent),
                Some(first) if first == parent => {
                    return Err(Fault::Invalid(format!(
                        "node {parent} lists child {child} twice"
                    )))
                }
                Some(first) => {
                    return Err(Fault::TwoParents {
                        node: child,
                        first,
                        second: parent,
                    })
                }
            }
        }
    }
    Ok(parents)
}

/// With at most one parent per node, the tree has a cycle exactly when
/// walking up from some node comes back to a node of the same walk.
fn check_acyclic(parents: &[Option<usize>]) -> Result<(), Fault> {
    #[derive(Clone, Copy, PartialEq)]
    enum Walk {
        Unseen,
        OnPath,
        Done,
    }
    let mut state = vec![Walk::Unseen; parents.len()];
    for start in 0..parents.len() {
        let mut path = Vec::new();
        let mut at = Some(start);
        while let Some(node) = at {
            match state[node] {
                Walk::Done => break,
                Walk::OnPath => return Err(Fault::NodeCycle { node }),
                Walk::Unseen => {
                    state[node] = Walk::OnPath;
                    path.push(node);
                    at = parents[node];
                }
            }
        }
        for node in path {
            state[node] = Walk::Done;
        }
    }
    Ok(())
}

fn roots(document: &gltf::Document, parents: &[Option<usize>]) -> Result<Vec<usize>, Fault> {
    let scene = document
        .default_scene()
        .or_else(|| document.scenes().next())
        .ok_or(Fault::NoScene)?;
    let mut roots = Vec::new();
    for node in scene.nodes().map(|node| node.index()) {
        if let Some(parent) = parents[node] {
            return Err(Fault::RootWithParent {
                scene: scene.index(),
                node,
                parent,
            });
        }
        if roots.contains(&node) {
            return Err(Fault::RootTwice {
                scene: scene.index(),
                node,
            });
        }
        roots.push(node);
    }
    Ok(roots)
}

/// Marks the nodes whose translation, rotation or scale some clip animates
/// (they and their subtrees move) and those whose morph weights it
/// animates (their meshes deform; import has refused weights channels on
/// nodes without morph targets). Channels of lights, cameras and materials
/// move nothing.
pub fn mark_motion(nodes: &mut [Node], clips: &[AnimationClip]) {
    for channel in clips.iter().flat_map(|clip| &clip.channels) {
        if let Some(node) = channel.target.placed_node().and_then(|n| nodes.get_mut(n)) {
            node.animated = true;
        }
        if let Target::Weights(node) = channel.target {
            if let Some(node) = nodes.get_mut(node) {
                node.deforms = true;
            }
        }
    }
}
