//! Which objects move within the planned frames. An object is dynamic
//! when its placement (or, for skinned and morphed meshes, its shape)
//! differs between two planned frames; one whose animation lies outside
//! them is static there, and goes into the static structures at the place
//! the planned frames have it. Meshes that skins or morph targets can
//! deform stay dynamic whatever the frames: the static structures hold
//! undeformed triangles.

use serde::Serialize;

use super::report::frame_ranges;
use super::PlannedFrames;
use crate::scene::SceneDesc;

/// One mesh object's part in the plan.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectPlan {
    /// Its scene node.
    pub node: usize,
    pub name: Option<String>,
    pub dynamic: bool,
    /// The planned frames it arrives in a new place or shape, as ranges
    /// (`3..10`); empty for static objects.
    pub moves_in: Vec<String>,
}

/// Every mesh object's plan, in the order frames place them.
pub fn plan(scene: &SceneDesc, planned: &PlannedFrames) -> Vec<ObjectPlan> {
    let Some(first) = planned.placed.first() else {
        return Vec::new();
    };
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
                dynamic: scene.nodes[node].deforms || !moves.is_empty(),
                moves_in: frame_ranges(&moves),
            }
        })
        .collect()
}
