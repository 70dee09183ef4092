//! A [`Pose`] at time `t`: each node's local TRS with the selected clips'
//! channels applied over the file's own, composed down the tree; skin joint
//! matrices, morph weights and the lights, cameras and materials that
//! KHR_animation_pointer channels animate come with it. This is the step
//! the frame loop takes once per frame, before anything is compared or
//! rendered.

use glam::{DMat4, DQuat, DVec3};

use super::property;
use super::sample::{sample, Values};
use crate::scene::pose::{default_weights, Pose, Properties};
use crate::scene::{AnimationClip, SceneDesc, Target};

/// Which clips play. glTF files often hold one clip per character or
/// object, meant to play together, so all do by default.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum ClipSelection {
    #[default]
    All,
    /// One clip, by its index in `SceneDesc::animations`.
    One(usize),
}

impl ClipSelection {
    /// The clip a user means by `text`: a clip's name, or else its index.
    /// The error lists the clips there are.
    pub fn parse(scene: &SceneDesc, text: &str) -> Result<ClipSelection, String> {
        let clips = &scene.animations;
        let by_name = clips
            .iter()
            .position(|clip| clip.name.as_deref() == Some(text));
        let by_index = text
            .parse::<usize>()
            .ok()
            .filter(|&index| index < clips.len());
        match by_name.or(by_index) {
            Some(index) => Ok(ClipSelection::One(index)),
            None => {
                let names: Vec<String> = clips
                    .iter()
                    .enumerate()
                    .map(|(index, clip)| match &clip.name {
                        Some(name) => format!("{index} ({name})"),
                        None => index.to_string(),
                    })
                    .collect();
                let known = if names.is_empty() {
                    "the scene has no animations".to_owned()
                } else {
                    format!("the scene's clips are {}", names.join(", "))
                };
                Err(format!("no clip named or numbered '{text}'; {known}"))
            }
        }
    }

    /// The selected clips, in file order.
    pub fn clips(self, scene: &SceneDesc) -> impl Iterator<Item = &AnimationClip> {
        scene
            .animations
            .iter()
            .enumerate()
            .filter(move |&(index, _)| match self {
                ClipSelection::All => true,
                ClipSelection::One(one) => index == one,
            })
            .map(|(_, clip)| clip)
    }

    /// When the selected clips come to rest: the latest key time.
    pub fn duration(self, scene: &SceneDesc) -> f64 {
        self.clips(scene)
            .flat_map(|clip| &clip.channels)
            .map(|channel| f64::from(channel.sampler.end()))
            .fold(0.0, f64::max)
    }
}

/// A node's placement relative to its parent, as glTF splits it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Trs {
    pub translation: DVec3,
    /// A unit quaternion.
    pub rotation: DQuat,
    pub scale: DVec3,
}

impl Trs {
    /// T · R · S, the glTF order.
    pub fn matrix(&self) -> DMat4 {
        DMat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }

    /// The TRS of a local matrix. Exact for matrices built from TRS, which
    /// are the only ones animation may target (the glTF spec forbids
    /// animating a node given by a matrix).
    pub fn of(matrix: &DMat4) -> Trs {
        let (scale, rotation, translation) = matrix.to_scale_rotation_translation();
        Trs {
            translation,
            rotation,
            scale,
        }
    }
}

/// Every node's local state at one time, before composing down the tree,
/// and the animated properties, which need no composing.
#[derive(Clone, Debug, PartialEq)]
pub struct LocalPose {
    /// Per node: the TRS, animated or the file's own.
    pub trs: Vec<Trs>,
    /// Per node: the local matrix. A node no channel touches keeps the
    /// file's matrix exactly (shear included).
    pub matrices: Vec<DMat4>,
    /// Per node: morph weights, as in [`Pose::weights`].
    pub weights: Vec<Vec<f32>>,
    pub properties: Properties,
}

impl LocalPose {
    /// Samples the selected clips at `t` seconds. Where several channels
    /// drive the same property, the later one (in file order) wins.
    pub fn at(scene: &SceneDesc, clips: ClipSelection, t: f64) -> LocalPose {
        let mut trs: Vec<Trs> = scene
            .nodes
            .iter()
            .map(|node| Trs::of(&node.local))
            .collect();
        let mut animated = vec![false; scene.nodes.len()];
        let mut weights = default_weights(scene);
        let mut properties = Properties::rest(scene);
        for channel in clips.clips(scene).flat_map(|clip| &clip.channels) {
            // Only a node's rotation is a quaternion; everything else,
            // light colours and material factors included, is a vector.
            let values = match channel.target {
                Target::Rotation(_) => Values::Rotation,
                _ => Values::Vector,
            };
            let Some(value) = sample(&channel.sampler, values, t) else {
                continue;
            };
            let Some(node) = channel.target.node() else {
                property::apply(&mut properties, channel.target, &value);
                continue;
            };
            let Some(local) = trs.get_mut(node) else {
                continue;
            };
            match (channel.target, value.as_slice()) {
                (Target::Translation(_), &[x, y, z]) => local.translation = DVec3::new(x, y, z),
                (Target::Scale(_), &[x, y, z]) => local.scale = DVec3::new(x, y, z),
                (Target::Rotation(_), &[x, y, z, w]) => {
                    local.rotation = DQuat::from_xyzw(x, y, z, w)
                }
                (Target::Weights(_), sampled) => {
                    if weights[node].len() == sampled.len() {
                        weights[node] = sampled.iter().map(|&w| w as f32).collect();
                    }
                    continue;
                }
                // A width that does not fit the property: import refuses it.
                _ => continue,
            }
            animated[node] = true;
        }
        let matrices = scene
            .nodes
            .iter()
            .zip(&trs)
            .zip(&animated)
            .map(|((node, trs), &animated)| if animated { trs.matrix() } else { node.local })
            .collect();
        LocalPose {
            trs,
            matrices,
            weights,
            properties,
        }
    }
}

impl Pose {
    /// The scene posed at `t` seconds by the selected clips.
    pub fn at(scene: &SceneDesc, clips: ClipSelection, t: f64) -> Pose {
        Pose::of_locals(scene, LocalPose::at(scene, clips, t))
    }

    /// Composes a sampled [`LocalPose`] down the tree.
    pub fn of_locals(scene: &SceneDesc, local: LocalPose) -> Pose {
        Pose::from_locals(scene, &local.matrices, local.weights, local.properties)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Channel, Interpolation, Mesh, MorphTarget, Node, Sampler, Skin};
    use glam::Vec3;

    fn linear(target: Target, times: &[f32], values: &[f32], width: usize) -> Channel {
        Channel {
            target,
            sampler: Sampler {
                interpolation: Interpolation::Linear,
                times: times.to_vec(),
                values: values.to_vec(),
                width,
            },
        }
    }

    /// Node 0 (root, animated translation) → node 1 (scaled child with a
    /// two-target morph mesh); a skin whose one joint is node 0.
    fn scene() -> SceneDesc {
        let mesh = Mesh {
            positions: vec![Vec3::ZERO],
            normals: vec![Vec3::Z],
            morph_targets: vec![MorphTarget::default(), MorphTarget::default()],
            morph_weights: vec![0.25, 0.5],
            ..Mesh::default()
        };
        SceneDesc {
            nodes: vec![
                Node {
                    name: Some("root".into()),
                    children: vec![1],
                    ..Node::default()
                },
                Node {
                    local: DMat4::from_scale(DVec3::splat(2.0)),
                    mesh: Some(0),
                    ..Node::default()
                },
            ],
            roots: vec![0],
            meshes: vec![mesh],
            skins: vec![Skin {
                joints: vec![0],
                inverse_bind: vec![DMat4::from_translation(DVec3::new(0.0, -1.0, 0.0))],
                ..Skin::default()
            }],
            animations: vec![
                AnimationClip {
                    name: Some("slide".into()),
                    channels: vec![linear(
                        Target::Translation(0),
                        &[0.0, 1.0],
                        &[0.0, 0.0, 0.0, 4.0, 0.0, 0.0],
                        3,
                    )],
                },
                AnimationClip {
                    name: Some("blend".into()),
                    channels: vec![linear(
                        Target::Weights(1),
                        &[0.0, 2.0],
                        &[0.0, 0.0, 1.0, 0.5],
                        2,
                    )],
                },
            ],
            ..SceneDesc::default()
        }
    }

    #[test]
    fn channels_override_the_local_transform_and_compose_down_the_tree() {
        let scene = scene();
        let pose = Pose::at(&scene, ClipSelection::All, 0.5);
        let child = pose.world[1].transform_point3(DVec3::new(1.0, 0.0, 0.0));
        assert_eq!(child, DVec3::new(4.0, 0.0, 0.0));
        assert_eq!(pose.weights[1], vec![0.25, 0.125]);
        assert!(pose.weights[0].is_empty());
        // The joint matrix is world(joint) · inverse_bind.
        let bound = pose.joints[0][0].transform_point3(DVec3::new(0.0, 1.0, 0.0));
        assert_eq!(bound, DVec3::new(2.0, 0.0, 0.0));
    }

    #[test]
    fn a_selected_clip_plays_alone() {
        let scene = scene();
        let blend = ClipSelection::parse(&scene, "blend").expect("by name");
        assert_eq!(blend, ClipSelection::One(1));
        assert_eq!(ClipSelection::parse(&scene, "0"), Ok(ClipSelection::One(0)));
        let pose = Pose::at(&scene, blend, 0.5);
        assert_eq!(pose.world[0], DMat4::IDENTITY);
        assert_eq!(pose.weights[1], vec![0.25, 0.125]);
        let message = ClipSelection::parse(&scene, "7").expect_err("no clip 7");
        assert!(message.contains("0 (slide), 1 (blend)"), "{message}");
        assert_eq!(ClipSelection::All.duration(&scene), 2.0);
    }

    #[test]
    fn without_channels_the_pose_is_the_rest_pose() {
        let mut scene = scene();
        scene.animations.clear();
        assert_eq!(
            Pose::at(&scene, ClipSelection::All, 3.0),
            Pose::rest(&scene)
        );
        assert_eq!(Pose::rest(&scene).weights[1], vec![0.25, 0.5]);
    }
}
