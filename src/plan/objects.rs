//! Which objects are dynamic. An object is dynamic when a playing clip
//! animates it (or a node above it) at all, or when its mesh deforms
//! (skins, morph targets): the scene and the clips decide, never the
//! frames a run renders. So every run of a shot (the whole shot, a farm
//! chunk, one frame rendered again) puts the same objects in the static
//! structures, traces them the same way (static ones in render space,
//! dynamic ones through their instance transform) and renders the same
//! bits, and every chunk shares one disk cache key. (Deciding by the
//! planned frames made a car parked in one chunk static there: its frames
//! then differed from the same frames of a chunk where it drove.)

use serde::Serialize;

use super::report::frame_ranges;
use super::PlannedFrames;
use crate::anim::pose::ClipSelection;
use crate::scene::pose::dynamic_nodes_where;
use crate::scene::SceneDesc;

/// One mesh object's part in the plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectPlan {
    /// Its scene node.
    pub node: usize,
    pub name: Option<String>,
    pub dynamic: bool,
    /// Whether its mesh deforms (skin or morph targets).
    pub deforms: bool,
    /// The planned frames it arrives in a new place or shape, as ranges
    /// (`3..10`); empty for static objects, and for dynamic ones that
    /// the planned frames show still.
    pub moves_in: Vec<String>,
}

/// Every mesh object's plan, in the order frames place them.
pub fn plan(scene: &SceneDesc, clips: ClipSelection, planned: &PlannedFrames) -> Vec<ObjectPlan> {
    let Some(first) = planned.placed.first() else {
        return Vec::new();
    };
    let dynamic = animated_by(scene, clips);
    (0..first.objects.len())
        .map(|index| {
            let node = first.objects[index].node;
            let moved_from =
                |before: &crate::render::frame::FrameScene,
                 after: &crate::render::frame::FrameScene| {
                    before.objects[index].to_render != after.objects[index].to_render
                        || before.deformed[index] != after.deformed[index]
                };
            let moves: Vec<u32> = (planned.placed.windows(2).zip(&planned.numbers[1..]))
                .filter(|(pair, _)| moved_from(&pair[0], &pair[1]))
                .map(|(_, &frame)| frame)
                .collect();
            ObjectPlan {
                node,
                name: scene.nodes[node].name.clone(),
                dynamic: dynamic[node],
                deforms: scene.nodes[node].deforms,
                moves_in: frame_ranges(&moves),
            }
        })
        .collect()
}

/// Per scene node, whether `clips` can move or deform it at any time: a
/// translation, rotation or scale channel of theirs targets it or a node
/// above it, or its mesh deforms. A channel counts even where its keys
/// are equal: sampled between them, a slerp or a spline may still round
/// to a placement of its own.
fn animated_by(scene: &SceneDesc, clips: ClipSelection) -> Vec<bool> {
    let mut moved = vec![false; scene.nodes.len()];
    for channel in clips.clips(scene).flat_map(|clip| &clip.channels) {
        if let Some(node) = channel.target.placed_node() {
            moved[node] = true;
        }
    }
    dynamic_nodes_where(scene, |node| moved[node])
}
