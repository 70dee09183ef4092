//! The effect plan: made once per run, before the first frame, from the
//! scene, the settings and the frames the run plans over, it says which
//! effects those frames call for, so that later stages simulate nothing
//! else. Per light a shadow class ([`Shadows`]: `none`, `unshadowed`,
//! `hard`, `soft`), per object whether the playing clips move it at all
//! (not only within the planned frames: see [`objects`]),
//! per material whether it spawns secondary rays where the camera sees it,
//! and the frames that change nothing.
//!
//! Every decision is conservative: a plan that could change an image is a
//! bug. The tests are evaluated on every planned frame's placement (only
//! those frames are ever rendered), with margins for rounding, so a light
//! is `none` only where it provably sends nothing to any point a camera
//! path can reach, and `unshadowed` only where provably nothing can stand
//! between it and what it lights.
//!
//! In the frame loop: `sequence.rs` makes the plan in `open`, places every
//! frame with its static set ([`Plan::dynamic_nodes`]) and its `none`
//! lights switched off ([`Plan::apply`]), and hands the backends the
//! per-light classes ([`Plan::shadow_split`]).

mod lights;
mod materials;
mod objects;
mod reach;
pub mod report;
pub mod shadows;
mod view;

use glam::DVec3;
use serde::Serialize;

use crate::anim::pose::ClipSelection;
use crate::render::frame::{CameraChoice, FrameScene, PlaceError, SceneBounds};
use crate::render::shadow_split::ShadowSplit;
use crate::scene::pose::{dynamic_nodes, Pose};
use crate::scene::SceneDesc;
use crate::schedule::{FrameSet, Timeline};
use crate::settings::{Method, Settings};

pub use lights::{LightPlan, Reason};
pub use materials::MaterialPlan;
pub use objects::ObjectPlan;
pub use report::WorkEstimate;
pub use shadows::Shadows;

/// The plan of one run.
#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    /// The frames planned over (`--plan-frames`, else the run's).
    #[serde(serialize_with = "report::frame_list")]
    pub frames: FrameSet,
    pub method: Method,
    pub lights: Vec<LightPlan>,
    pub objects: Vec<ObjectPlan>,
    pub materials: Vec<MaterialPlan>,
    /// Planned frames that change nothing from the planned frame before
    /// them: their image is a copy.
    #[serde(serialize_with = "report::numbers")]
    pub copied_frames: Vec<u32>,
    pub work: WorkEstimate,
    /// Per scene node, whether its object may move or deform.
    #[serde(skip)]
    dynamic_nodes: Vec<bool>,
}

impl Plan {
    /// The plan of `scene` played by `clips` over `frames`, with
    /// `settings`; `anchor` is the sequence's render-space origin (see
    /// [`Plan::anchor`]).
    pub fn make(
        scene: &SceneDesc,
        settings: &Settings,
        clips: ClipSelection,
        frames: &FrameSet,
    ) -> Result<Plan, PlaceError> {
        let anchor = Plan::anchor(scene);
        let timeline = Timeline { fps: settings.fps };
        let every_mover = dynamic_nodes(scene);
        let placed = (frames.frames().iter())
            .map(|&frame| {
                let time = timeline.time_of(frame);
                let pose = Pose::at(scene, clips, time);
                let camera = CameraChoice::for_frame(settings, time);
                FrameScene::place(scene, &pose, anchor, camera, &settings.lamps, &every_mover)
            })
            .collect::<Result<Vec<_>, _>>()?;
        let planned = PlannedFrames {
            numbers: frames.frames(),
            placed: &placed,
        };

        let objects = objects::plan(scene, clips, &planned);
        let views = view::views(scene, &planned, settings);
        let materials = materials::plan(scene, &planned, &views);
        let lights = lights::plan(scene, &planned, &views);
        let mut dynamic_nodes = vec![false; scene.nodes.len()];
        for object in objects.iter().filter(|object| object.dynamic) {
            dynamic_nodes[object.node] = true;
        }
        let copied_frames = (placed.windows(2).zip(&frames.frames()[1..]))
            .filter(|(pair, _)| pair[0] == pair[1])
            .map(|(_, &frame)| frame)
            .collect();
        let work = WorkEstimate::of(settings, &lights);
        Ok(Plan {
            frames: frames.clone(),
            method: settings.method,
            lights,
            objects,
            materials,
            copied_frames,
            work,
            dynamic_nodes,
        })
    }

    /// The render-space origin every frame of a sequence is placed around:
    /// the centre of the scene's bounds at rest, so it is the same for
    /// every chunk of a shot.
    pub fn anchor(scene: &SceneDesc) -> DVec3 {
        SceneBounds::of(scene, &Pose::rest(scene)).map_or(DVec3::ZERO, |b| b.centre())
    }

    /// Per scene node, whether the playing clips may move or deform its
    /// object (in any frame, planned or not): everything else goes into
    /// the static structures
    /// (the world's static BVH, the light mesh's static layer and its disk
    /// cache).
    pub fn dynamic_nodes(&self) -> &[bool] {
        &self.dynamic_nodes
    }

    /// Switches off the lights the plan found to send nothing (`none`):
    /// with no power they reach no point, so no stage of either backend
    /// spends a shadow ray or a mask bit on them. Their term was zero at
    /// every point a camera path meets, so the image keeps its bits.
    pub fn apply(&self, placed: &mut FrameScene) {
        for light in self.lights.iter().filter(|l| l.shadows == Shadows::None) {
            if let Some(render) = placed.lights.get_mut(light.index) {
                render.power = glam::Vec3::ZERO;
            }
        }
    }

    /// The per-light classes the backends shade by.
    pub fn shadow_split(&self) -> ShadowSplit {
        ShadowSplit::new(self.lights.iter().map(|light| light.shadows).collect())
    }
}

/// The planned frames' numbers and placements, side by side.
#[derive(Clone, Copy)]
struct PlannedFrames<'a> {
    numbers: &'a [u32],
    placed: &'a [FrameScene],
}

impl PlannedFrames<'_> {
    fn iter(&self) -> impl Iterator<Item = (u32, &FrameScene)> + '_ {
        self.numbers.iter().copied().zip(self.placed)
    }
}
