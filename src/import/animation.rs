//! Animation clips: each channel's target and its sampler's keys, read
//! through the bounds-checked accessor reader and checked as sampling needs
//! (times finite and strictly increasing, as many values as keys, width and
//! interpolation call for). Channels name a node and a path, or a
//! KHR_animation_pointer (taken from the JSON by `container.rs`, see
//! `pointer.rs`); both kinds are read here alike, in the file's channel
//! order. A pointer to a property lmanim does not animate, or to an object
//! the file lacks, skips its channel; the caller reports it.

use std::fmt;

use gltf::animation::{Interpolation as FileInterpolation, Property};
use gltf::json::validation::Checked;

use super::accessor::Use;
use super::error::Fault;
use super::pointer::{PointerChannel, PointerChannels};
use crate::scene::{
    AnimationClip, Camera, Channel, Interpolation, Light, Mesh, Node, Sampler, Target,
};

/// What channels can target: the scene as imported so far. A target's
/// index must exist, and a weights channel has one value per morph target
/// of the node's mesh.
pub struct Animatable<'a> {
    pub nodes: &'a [Node],
    pub meshes: &'a [Mesh],
    pub lights: &'a [Light],
    pub cameras: &'a [Camera],
    /// The file's own materials (not the default one import may append).
    pub materials: usize,
}

/// The file's animations and the channels left out of them.
pub struct Animations {
    pub clips: Vec<AnimationClip>,
    pub skipped: Vec<SkippedChannel>,
}

/// A channel that import leaves out, and why: a KHR_animation_pointer
/// to something lmanim does not animate, or a `target.path` that glTF 2.0
/// does not define (an extension's, which the spec lets a reader ignore).
#[derive(Clone, Debug, PartialEq)]
pub struct SkippedChannel {
    pub animation: usize,
    pub channel: usize,
    /// What the channel targets, as the file says it:
    /// `KHR_animation_pointer "/nodes/0/scale"`, `path "visibility"`.
    pub target: String,
    pub reason: String,
}

impl fmt::Display for SkippedChannel {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "animation {} channel {}: {} {}; the channel is skipped",
            self.animation, self.channel, self.target, self.reason
        )
    }
}

/// A channel as the file has it: through the glTF crate, or taken out
/// of the JSON before it.
enum Source<'d, 'p> {
    Node(gltf::animation::Channel<'d>),
    Pointer(&'p PointerChannel),
}

/// Every animation of the file.
pub fn import(
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    pointers: &PointerChannels,
    scene: &Animatable,
) -> Result<Animations, Fault> {
    let mut skipped = Vec::new();
    let mut clips = Vec::new();
    for animation in document.animations() {
        let a = animation.index();
        let mut channels = Vec::new();
        for (c, source) in file_order(&animation, pointers.of(a)).enumerate() {
            let fault = |problem: String| Fault::Animation {
                animation: a,
                channel: c,
                problem,
            };
            let mut skip = |target: String, reason: String| {
                skipped.push(SkippedChannel {
                    animation: a,
                    channel: c,
                    target,
                    reason,
                })
            };
            let (target, sampler, pointer) = match source {
                Source::Node(channel) => match node_target(document, &channel) {
                    Ok(target) => (target, channel.sampler(), None),
                    Err(UnknownPath) => {
                        skip(
                            "target.path".into(),
                            "is not one glTF 2.0 defines (an extension's, which lmanim does not read)"
                                .into(),
                        );
                        continue;
                    }
                },
                Source::Pointer(channel) => {
                    let target = match channel.target(scene) {
                        Ok(target) => target,
                        Err(reason) => {
                            skip(
                                format!("KHR_animation_pointer {:?}", channel.pointer),
                                reason,
                            );
                            continue;
                        }
                    };
                    // `pointer.rs` checked the index against the samplers.
                    let sampler = animation.samplers().nth(channel.sampler).ok_or_else(|| {
                        fault(format!("names missing sampler {}", channel.sampler))
                    })?;
                    (target, sampler, Some(channel.pointer.as_str()))
                }
            };
            let width = target.width(|node| morph_targets(scene, node));
            if let (Target::Weights(node), 0) = (target, width) {
                return Err(fault(format!(
                    "animates the weights of node {node}, which has no mesh with morph targets"
                )));
            }
            let reader = Reader {
                animation: a,
                sampler: sampler.index(),
                channel: c,
                pointer,
            };
            let channel = Channel {
                target,
                sampler: reader.keys(&sampler, target, width, buffers)?,
            };
            channel.validate().map_err(|problem| Fault::Rule {
                path: format!("animations[{a}].samplers[{}]", reader.sampler),
                rule: format!("{problem} (read by channel {c})"),
            })?;
            channels.push(channel);
        }
        clips.push(AnimationClip {
            name: animation.name().map(str::to_owned),
            channels,
        });
    }
    Ok(Animations { clips, skipped })
}

/// The channels of `animation` in the file's order: the pointer channels
/// at their own indices, the glTF crate's (the rest, in order) between.
fn file_order<'d, 'p>(
    animation: &gltf::Animation<'d>,
    pointers: &'p [PointerChannel],
) -> impl Iterator<Item = Source<'d, 'p>> {
    let mut nodes = animation.channels();
    let mut pointers = pointers.iter().peekable();
    (0..).map_while(
        move |index| match pointers.next_if(|p| p.channel == index) {
            Some(pointer) => Some(Source::Pointer(pointer)),
            None => nodes.next().map(Source::Node),
        },
    )
}

/// A channel's `target.path` that glTF 2.0 does not define.
struct UnknownPath;

/// The channel's node and property (`channel_targets.rs` has checked the
/// node, which the glTF crate unwraps), unless its path is unknown (the
/// crate would unwrap that too).
fn node_target(
    document: &gltf::Document,
    channel: &gltf::animation::Channel,
) -> Result<Target, UnknownPath> {
    // The crate's own indices of the channel it handed out.
    let json =
        &document.as_json().animations[channel.animation().index()].channels[channel.index()];
    if matches!(json.target.path, Checked::Invalid) {
        return Err(UnknownPath);
    }
    let node = channel.target().node().index();
    Ok(match channel.target().property() {
        Property::Translation => Target::Translation(node),
        Property::Rotation => Target::Rotation(node),
        Property::Scale => Target::Scale(node),
        Property::MorphTargetWeights => Target::Weights(node),
    })
}

/// Morph targets of `node`'s mesh (0 without a mesh or targets).
fn morph_targets(scene: &Animatable, node: usize) -> usize {
    scene
        .nodes
        .get(node)
        .and_then(|node| node.mesh)
        .and_then(|mesh| scene.meshes.get(mesh))
        .map_or(0, |mesh| mesh.morph_targets.len())
}

/// One channel's sampler, named as accessor faults name it.
struct Reader<'p> {
    animation: usize,
    sampler: usize,
    channel: usize,
    pointer: Option<&'p str>,
}

impl Reader<'_> {
    /// What `role` ("input", "output") of the sampler is read for.
    fn usage(&self, role: &str) -> String {
        let pointer = self
            .pointer
            .map_or(String::new(), |pointer| format!(", pointer {pointer}"));
        format!(
            "{role} of animation {} sampler {}, read by channel {}{pointer}",
            self.animation, self.sampler, self.channel
        )
    }

    /// The keys of `sampler` for `target`, `width` components a value.
    /// The output accessor's type must be the property's: SCALAR, VEC3 or
    /// VEC4 (morph weights are SCALARs, one per target and key).
    fn keys(
        &self,
        sampler: &gltf::animation::Sampler,
        target: Target,
        width: usize,
        buffers: &[Vec<u8>],
    ) -> Result<Sampler, Fault> {
        let times: Vec<f32> = Use {
            accessor: &sampler.input(),
            usage: &self.usage("input"),
        }
        .vectors::<1>(buffers)?
        .into_iter()
        .map(|[time]| time)
        .collect();
        let accessor = sampler.output();
        let usage = self.usage("output");
        let output = Use {
            accessor: &accessor,
            usage: &usage,
        };
        let element = match target {
            Target::Weights(_) => 1,
            _ => width,
        };
        let values = match element {
            3 => flatten(output.vectors::<3>(buffers)?),
            4 => flatten(output.vectors::<4>(buffers)?),
            _ => flatten(output.vectors::<1>(buffers)?),
        };
        Ok(Sampler {
            interpolation: match sampler.interpolation() {
                FileInterpolation::Step => Interpolation::Step,
                FileInterpolation::Linear => Interpolation::Linear,
                FileInterpolation::CubicSpline => Interpolation::CubicSpline,
            },
            times,
            values,
            width,
        })
    }
}

fn flatten<const N: usize>(vectors: Vec<[f32; N]>) -> Vec<f32> {
    vectors.into_iter().flatten().collect()
}
