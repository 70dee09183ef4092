//! The light mesh's fill on the GPU: the frame's missing (node, light)
//! bits as one segment each (`lightmesh::segments`), traced in a compute
//! pass (`fill_segments.wgsl`) against the static structure and the
//! dynamic objects with the CPU's watertight test, so the bits are the
//! CPU fill's. The CPU's shafts and remembered walls save it segments; a
//! GPU traces them all side by side instead.

use bytemuck::{Pod, Zeroable};

use super::context::{GpuContext, GpuError};
use super::contract::{
    DYNAMIC_BLOCKED, DYNAMIC_TESTED, FILL_FLAG_BITS, KNOWN_VISIBLE, LIGHTS, STATIC_BLOCKED,
    TEST_DYNAMIC, TEST_STATIC,
};
use super::direct::FrameLights;
use super::pass::{WorldPass, WorldUse, BATCH};
use super::scene::GpuScene;
use super::shaders::Entry;
use crate::lightmesh::segments::{Segment, SegmentAnswer};

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

    /// Traces `segments` against `scene` with `lights`, in batches; one
    /// answer per segment, in order.
    pub fn trace(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        lights: &FrameLights,
        segments: &[Segment],
    ) -> Result<Vec<SegmentAnswer>, GpuError> {
        let mut answers = Vec::with_capacity(segments.len());
        for batch in segments.chunks(BATCH) {
            let items: Vec<FillSegment> = batch.iter().map(FillSegment::from).collect();
            let bits: Vec<u32> = self.pass.run(
                "the fill's segments traced, which the CPU merges into its masks",
                context,
                scene,
                &items,
                &[(LIGHTS, lights.buffer())],
                lights.count(),
            )?;
            context.traffic.traced(batch.len() as u64);
            answers.extend(bits.into_iter().map(|bits| SegmentAnswer {
                static_blocked: bits & STATIC_BLOCKED != 0,
                dynamic_tested: bits & DYNAMIC_TESTED != 0,
                dynamic_blocked: bits & DYNAMIC_BLOCKED != 0,
            }));
        }
        Ok(answers)
    }
}
