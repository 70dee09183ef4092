//! Animation clips: each channel's target and its sampler's keys, read
//! through the bounds-checked accessor reader and checked as sampling needs
//! (times finite and strictly increasing, as many values as keys, width and
//! interpolation call for). Channels of KHR_animation_pointer are not read
//! here; see `container.rs`.

use gltf::animation::{Interpolation as FileInterpolation, Property};

use super::accessor::Use;
use super::error::Fault;
use crate::scene::{AnimationClip, Channel, Interpolation, Mesh, Node, Sampler, Target};

/// Every animation of the file. `nodes` and `meshes` are the imported
/// ones: a weights channel has one value per morph target of the node's
/// mesh.
pub fn import(
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    nodes: &[Node],
    meshes: &[Mesh],
) -> Result<Vec<AnimationClip>, Fault> {
    document
        .animations()
        .map(|animation| {
            let channels = animation
                .channels()
                .enumerate()
                .map(|(c, channel)| {
                    let fault = |problem: String| Fault::Animation {
                        animation: animation.index(),
                        channel: c,
                        problem,
                    };
                    read_channel(&channel, animation.index(), buffers, (nodes, meshes), fault)
                })
                .collect::<Result<Vec<_>, _>>()?;
            Ok(AnimationClip {
                name: animation.name().map(str::to_owned),
                channels,
            })
        })
        .collect()
}

/// One channel of animation `animation`; `fault` names it in errors.
fn read_channel(
    channel: &gltf::animation::Channel,
    animation: usize,
    buffers: &[Vec<u8>],
    (nodes, meshes): (&[Node], &[Mesh]),
    fault: impl Fn(String) -> Fault,
) -> Result<Channel, Fault> {
    let node = channel.target().node().index();
    let (target, width) = match channel.target().property() {
        Property::Translation => (Target::Translation(node), 3),
        Property::Rotation => (Target::Rotation(node), 4),
        Property::Scale => (Target::Scale(node), 3),
        Property::MorphTargetWeights => {
            let targets = nodes
                .get(node)
                .and_then(|node| node.mesh)
                .and_then(|mesh| meshes.get(mesh))
                .map_or(0, |mesh| mesh.morph_targets.len());
            if targets == 0 {
                return Err(fault(format!(
                    "animates the weights of node {node}, which has no mesh with morph targets"
                )));
            }
            (Target::Weights(node), targets)
        }
    };
    let sampler = channel.sampler();
    let s = sampler.index();
    let input = sampler.input();
    let output = sampler.output();
    let input_usage = format!("input of animation {animation} sampler {s}");
    let output_usage = format!("output of animation {animation} sampler {s}");
    let times: Vec<f32> = Use {
        accessor: &input,
        usage: &input_usage,
    }
    .vectors::<1>(buffers)?
    .into_iter()
    .map(|[time]| time)
    .collect();
    let output = Use {
        accessor: &output,
        usage: &output_usage,
    };
    let values = match target {
        Target::Translation(_) | Target::Scale(_) => flatten(output.vectors::<3>(buffers)?),
        Target::Rotation(_) => flatten(output.vectors::<4>(buffers)?),
        Target::Weights(_) => flatten(output.vectors::<1>(buffers)?),
    };
    let sampler = Sampler {
        interpolation: match sampler.interpolation() {
            FileInterpolation::Step => Interpolation::Step,
            FileInterpolation::Linear => Interpolation::Linear,
            FileInterpolation::CubicSpline => Interpolation::CubicSpline,
        },
        times,
        values,
        width,
    };
    sampler
        .validate()
        .map_err(|problem| fault(format!("sampler {s} {problem}")))?;
    Ok(Channel { target, sampler })
}

fn flatten<const N: usize>(vectors: Vec<[f32; N]>) -> Vec<f32> {
    vectors.into_iter().flatten().collect()
}
