//! The light mesh's fill on the GPU: the frame's missing (node, light)
//! bits as one segment each (`lightmesh::segments`), traced in a compute
//! pass (`fill_segments.wgsl`) against the static structure and the
//! dynamic objects with the CPU's watertight test, so the bits are the
//! CPU fill's. The CPU's shafts and remembered walls save it segments; a
//! GPU traces them all side by side instead. What crosses is lean: 16
//! bytes a segment up, four bits of answer down.

use bytemuck::{Pod, Zeroable};

use super::context::{GpuContext, GpuError};
use super::contract::{
    ANSWERS_PER_WORD, ANSWER_BITS, DYNAMIC_BLOCKED, DYNAMIC_TESTED, FILL_FLAG_BITS, ITEMS,
    KNOWN_VISIBLE, LIGHTS, STATIC_BLOCKED, TEST_DYNAMIC, TEST_STATIC,
};
use super::direct::FrameLights;
use super::pass::{answer_buffer, Dispatch, WorldPass, WorldUse, BATCH};
use super::recording::{Downloads, Part, Recording};
use super::scene::{storage, GpuScene};
use super::shaders::Entry;
use crate::lightmesh::segments::{Segment, SegmentAnswer, SegmentFill};

/// `fill_segments.wgsl`'s `FillSegment`: 16 bytes, since a steady frame
/// of a fly-through sends a million of them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FillSegment {
    origin: [f32; 3],
    /// The light's index above [`FILL_FLAG_BITS`] bits of flags.
    light_flags: u32,
}

impl From<&Segment> for FillSegment {
    fn from(segment: &Segment) -> FillSegment {
        let flag = |on: bool, flag: u32| if on { flag } else { 0 };
        debug_assert!(segment.light < u32::MAX >> FILL_FLAG_BITS);
        FillSegment {
            origin: segment.origin.to_array(),
            light_flags: segment.light << FILL_FLAG_BITS
                | flag(segment.test_static, TEST_STATIC)
                | flag(segment.known_visible, KNOWN_VISIBLE)
                | flag(segment.test_dynamic, TEST_DYNAMIC),
        }
    }
}

/// The batches of segments recorded before the CPU waits for their
/// answers: one wait for a steady frame's million segments, and at most
/// this many batches' buffers held at once on a cold frame's tens of
/// millions.
const BATCHES_PER_WAIT: usize = 8;

/// The fill's pipeline, made once per run.
pub struct FillPass {
    pub(super) pass: WorldPass,
}

impl FillPass {
    pub fn new(context: &GpuContext) -> FillPass {
        FillPass {
            pass: WorldPass::new(
                context,
                Entry::FillSegments,
                WorldUse::Traces,
                &[LIGHTS],
                &[],
            ),
        }
    }

    /// Traces `fill`'s segments against `scene` with `lights`, in batches
    /// recorded [`BATCHES_PER_WAIT`] at a time and waited for together;
    /// one answer per segment, in order.
    pub fn trace(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        lights: &FrameLights,
        fill: &SegmentFill,
    ) -> Result<Vec<SegmentAnswer>, GpuError> {
        let segments = fill.records(|segment| FillSegment::from(segment));
        let mut answers = Vec::with_capacity(segments.len());
        for group in segments.chunks(BATCH * BATCHES_PER_WAIT) {
            let words = context.checked(Entry::FillSegments.name(), || {
                self.trace_group(context, scene, lights, group)
            })?;
            context.traffic.traced(group.len() as u64);
            answers.extend((0..group.len()).map(|index| {
                let bits = words[index / ANSWERS_PER_WORD as usize]
                    >> (ANSWER_BITS * (index as u32 % ANSWERS_PER_WORD));
                SegmentAnswer {
                    static_blocked: bits & STATIC_BLOCKED != 0,
                    dynamic_tested: bits & DYNAMIC_TESTED != 0,
                    dynamic_blocked: bits & DYNAMIC_BLOCKED != 0,
                }
            }));
        }
        Ok(answers)
    }

    /// Records `group`'s batches and waits once for their answers,
    /// [`ANSWERS_PER_WORD`] to a word.
    fn trace_group(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        lights: &FrameLights,
        group: &[FillSegment],
    ) -> Result<Vec<u32>, GpuError> {
        let mut recording = Recording::new(context);
        let mut batches = Vec::new();
        for batch in group.chunks(BATCH) {
            let items = storage(context, "fill segments", batch)?;
            let words = batch.len().div_ceil(ANSWERS_PER_WORD as usize);
            let answers = answer_buffer::<u32>(context, "fill answers", words)?;
            let dispatch = Dispatch::new(scene, batch.len()).with_lights(lights.count());
            let reads = [(ITEMS, &items), (LIGHTS, lights.buffer())];
            (self.pass).record(context, recording.encoder(), dispatch, &reads, &answers);
            batches.push((answers, words));
        }
        let mut downloads = Downloads::default();
        let parts: Vec<Part<u32>> = (batches.iter())
            .map(|(answers, words)| downloads.add(answers, *words))
            .collect();
        let why = "the fill's segments traced, which the CPU merges into its masks";
        let downloaded = recording.wait(why, downloads)?;
        Ok(parts
            .into_iter()
            .flat_map(|part| downloaded.take(part))
            .collect())
    }
}
