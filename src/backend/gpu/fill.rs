//! The light mesh's fill on the GPU: the level's missing (node, light)
//! bits as one segment each (`lightmesh::segments`), traced in a compute
//! pass (`fill_segments.wgsl`) against the static structure and the
//! dynamic objects with the CPU's watertight test, so the bits are the
//! CPU fill's. The CPU's shafts and remembered walls save it segments; a
//! GPU traces them all side by side instead. What crosses is lean: 8
//! bytes a segment up (its brick, node, light and flags; the GPU places
//! the node on the lattice as the CPU does), four bits of answer down.
//!
//! The pass writes each bit into the mask pool where it belongs, so the
//! level's shading reads it without the CPU waiting for it; the answers
//! come back with the CPU's next wait ([`FillAnswers`]), for its store.

use bytemuck::{Pod, Zeroable};
use glam::IVec3;

use super::context::{GpuContext, GpuError};
use super::contract::{
    ANSWERS_PER_WORD, ANSWER_BITS, DYNAMIC_BLOCKED, DYNAMIC_TESTED, FILL_BRICKS, FILL_FLAG_BITS,
    FILL_NODE_BITS, ITEMS, KNOWN_OCCLUDED, KNOWN_VISIBLE, LIGHTS, POOL, STATIC_BLOCKED,
    TEST_DYNAMIC, TEST_STATIC,
};
use super::direct::FrameLights;
use super::mask_pool::MaskPool;
use super::pass::{answer_buffer, Dispatch, WorldPass, WorldUse, BATCH};
use super::recording::{Downloaded, Downloads, Part, PendingWords, Recording};
use super::scene::{storage, GpuScene};
use super::shaders::Entry;
use crate::lightmesh::lattice::Lattice;
use crate::lightmesh::segments::{Segment, SegmentAnswer, SegmentFill};

/// `fill_segments.wgsl`'s `FillSegment`: 8 bytes, since a steady frame
/// of a fly-through sends a million of them.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FillSegment {
    /// The brick's index in the [`FillTable`] above [`FILL_NODE_BITS`]
    /// bits of the node's slot in it.
    brick_node: u32,
    /// The light's index above [`FILL_FLAG_BITS`] bits of flags.
    light_flags: u32,
}

impl FillSegment {
    /// `segment` of the fill's brick `brick`.
    pub fn new(brick: usize, segment: &Segment) -> FillSegment {
        let flag = |on: bool, flag: u32| if on { flag } else { 0 };
        debug_assert!(segment.light < u32::MAX >> FILL_FLAG_BITS);
        FillSegment {
            brick_node: table_node(brick, segment.node),
            light_flags: segment.light << FILL_FLAG_BITS
                | flag(segment.test_static, TEST_STATIC)
                | flag(segment.known_visible, KNOWN_VISIBLE)
                | flag(segment.test_dynamic, TEST_DYNAMIC)
                | flag(segment.known_occluded, KNOWN_OCCLUDED),
        }
    }
}

/// Node `slot` of the [`FillTable`]'s brick `brick` as the level's passes
/// take it (`level_bricks.wgsl`'s `table_entry` and `table_slot`): the
/// brick's index above [`FILL_NODE_BITS`] bits of the slot.
pub fn table_node(brick: usize, slot: u16) -> u32 {
    debug_assert!(brick < (u32::MAX >> FILL_NODE_BITS) as usize);
    (brick as u32) << FILL_NODE_BITS | u32::from(slot)
}

/// `level_bricks.wgsl`'s `FillHeader`: the lattice, the u32 light words
/// of a node in the pool, and how far LMM1's enclosure probes reach
/// (`super::enclosure`).
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FillHeader {
    origin: [f32; 3],
    h: f32,
    light_words: u32,
    probe_reach: f32,
    _pad: [u32; 2],
}

/// `level_bricks.wgsl`'s `FillBrick`: a brick of the level, and the pool
/// word where its slot starts.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FillBrick {
    brick: [i32; 3],
    slot_start: u32,
}

/// Where a level's fill segments and enclosure probes lie and write: the
/// lattice and, per brick of the level's demand (in its order), its
/// coordinates and its slot in the pool. Uploaded once a level, for both.
pub struct FillTable {
    header: FillHeader,
    bricks: Vec<FillBrick>,
}

impl FillTable {
    /// The table of `bricks` on `lattice`, each with the pool word where
    /// its slot starts where it has one (a brick without one has no
    /// segment to write), in a pool of `light_words` u32 light words per
    /// node; probes reach `probe_reach`.
    pub fn new(
        (lattice, probe_reach): (&Lattice, f32),
        light_words: usize,
        bricks: &[IVec3],
        slot_starts: &[Option<usize>],
    ) -> FillTable {
        FillTable {
            header: FillHeader {
                origin: lattice.origin.to_array(),
                h: lattice.h,
                light_words: light_words as u32,
                probe_reach,
                _pad: [0; 2],
            },
            bricks: (bricks.iter().zip(slot_starts))
                .map(|(brick, start)| FillBrick {
                    brick: brick.to_array(),
                    slot_start: start.map_or(u32::MAX, |start| start as u32),
                })
                .collect(),
        }
    }

    /// `bricks` (on `place`'s lattice) in a scratch pool of their own, a
    /// slot each in order, of `light_words` light words per node: the
    /// table uploaded, and the pool, for running a level's passes outside
    /// a frame.
    pub fn scratch(
        context: &GpuContext,
        place: (&Lattice, f32),
        light_words: usize,
        bricks: &[IVec3],
    ) -> Result<(wgpu::Buffer, wgpu::Buffer), GpuError> {
        let slot_words = MaskPool::slot_bytes(light_words) / size_of::<u32>();
        let starts: Vec<Option<usize>> = (0..bricks.len())
            .map(|brick| Some(brick * slot_words))
            .collect();
        let table = FillTable::new(place, light_words, bricks, &starts).upload(context)?;
        let pool = answer_buffer::<u32>(context, "scratch pool", bricks.len() * slot_words)?;
        Ok((table, pool))
    }

    /// The header and the bricks, uploaded as the shaders read them.
    pub fn upload(&self, context: &GpuContext) -> Result<wgpu::Buffer, GpuError> {
        context.checked("the level's bricks", || {
            let mut bytes = bytemuck::bytes_of(&self.header).to_vec();
            bytes.extend_from_slice(bytemuck::cast_slice(&self.bricks));
            context.check_binding("fill bricks", bytes.len() as u64)?;
            Ok(context.upload("fill bricks", &bytes, wgpu::BufferUsages::STORAGE))
        })
    }
}

/// The segments recorded before the CPU waits for their answers where a
/// level has more: eight batches, so a steady frame's million segments
/// need no wait of their own, and a cold frame's tens of millions hold at
/// most eight batches' buffers at once.
pub const SEGMENTS_PER_WAIT: usize = 8 * BATCH;

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
                &[FILL_BRICKS, LIGHTS],
                &[POOL],
            ),
        }
    }

    /// Records the tracing of `fill`'s segments against `scene` with
    /// `lights`, each bit written into `pool`, where `table` (a
    /// [`FillTable`] uploaded) places the fill's bricks. Waits only
    /// between groups of `per_wait` segments ([`SEGMENTS_PER_WAIT`] but in
    /// tests; a whole number of answer words), where there are more; the answers left come back with the
    /// CPU's next wait.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        context: &GpuContext,
        recording: &mut Recording,
        scene: &GpuScene,
        lights: &FrameLights,
        (pool, table): (&wgpu::Buffer, &wgpu::Buffer),
        fill: &SegmentFill,
        per_wait: usize,
    ) -> Result<FillAnswers, GpuError> {
        // Each group's answers then start a word of their own.
        assert!(per_wait > 0 && per_wait.is_multiple_of(ANSWERS_PER_WORD as usize));
        let segments = fill.records(FillSegment::new);
        context.traffic.traced(segments.len() as u64);
        let mut answers = FillAnswers {
            count: segments.len(),
            ..FillAnswers::default()
        };
        let groups = segments.chunks(per_wait).count();
        for (index, group) in segments.chunks(per_wait).enumerate() {
            context.checked(Entry::FillSegments.name(), || {
                for batch in group.chunks(BATCH) {
                    let items = storage(context, "fill segments", batch)?;
                    let words = batch.len().div_ceil(ANSWERS_PER_WORD as usize);
                    let out = answer_buffer::<u32>(context, "fill answers", words)?;
                    let dispatch = Dispatch::new(scene, batch.len()).with_lights(lights.count());
                    let reads = [
                        (ITEMS, &items),
                        (FILL_BRICKS, table),
                        (LIGHTS, lights.buffer()),
                        (POOL, pool),
                    ];
                    (self.pass).record(context, recording.encoder(), dispatch, &reads, &out);
                    answers.words.push(out, words);
                }
                Ok::<_, GpuError>(())
            })?;
            if index + 1 < groups {
                let mut downloads = Downloads::default();
                let parts = answers.download(&mut downloads);
                let why = "a group of the fill's answers, before the next group's buffers";
                let downloaded = recording.wait(why, downloads)?;
                answers.keep(&downloaded, parts);
            }
        }
        Ok(answers)
    }

    /// Traces `fill`'s segments of `bricks` (the demand's, on `lattice`)
    /// on their own and waits for their answers, one per segment in order
    /// (their bits go to a scratch pool of the fill's bricks): the GPU's
    /// fill, for comparing with the CPU's, waiting every `per_wait`
    /// segments as [`FillPass::record`] does.
    pub fn trace(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        lights: &FrameLights,
        (lattice, bricks): (&Lattice, &[IVec3]),
        fill: &SegmentFill,
        per_wait: usize,
    ) -> Result<Vec<SegmentAnswer>, GpuError> {
        let light_words = MaskPool::light_words(lights.count() as usize);
        let (table, scratch) = FillTable::scratch(context, (lattice, 0.0), light_words, bricks)?;
        let mut recording = Recording::new(context);
        let mut answers = self.record(
            context,
            &mut recording,
            scene,
            lights,
            (&scratch, &table),
            fill,
            per_wait,
        )?;
        (answers.words).wait_for_all(&mut recording, "the fill's answers, for comparing")?;
        Ok(answers.answers())
    }
}

/// The answers of a level's fill, [`ANSWERS_PER_WORD`] to a word in the
/// segments' order: those a wait within the fill brought back, and those
/// the CPU's next wait brings back.
#[derive(Default)]
pub struct FillAnswers {
    words: PendingWords,
    /// Segments answered.
    count: usize,
}

impl FillAnswers {
    /// Adds the answers still on the GPU to what a wait brings back.
    pub fn download<'s>(&'s self, downloads: &mut Downloads<'s>) -> Vec<Part<u32>> {
        self.words.download(downloads)
    }

    /// Keeps what a wait brought back of `parts`.
    pub fn keep(&mut self, downloaded: &Downloaded, parts: Vec<Part<u32>>) {
        self.words.keep(downloaded, parts);
    }

    /// One answer per segment, in order, once every part is back.
    pub fn answers(&self) -> Vec<SegmentAnswer> {
        let words = self.words.words();
        (0..self.count)
            .map(|index| {
                let bits = words[index / ANSWERS_PER_WORD as usize]
                    >> (ANSWER_BITS * (index as u32 % ANSWERS_PER_WORD));
                SegmentAnswer {
                    static_blocked: bits & STATIC_BLOCKED != 0,
                    dynamic_tested: bits & DYNAMIC_TESTED != 0,
                    dynamic_blocked: bits & DYNAMIC_BLOCKED != 0,
                }
            })
            .collect()
    }
}
