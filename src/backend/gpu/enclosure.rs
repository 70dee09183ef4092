//! LMM1's enclosure probes on the GPU (`enclosure_probes.wgsl`): the
//! nodes the CPU's demand names whose flag is not settled
//! ([`LightMesh::nodes_to_probe`](crate::lightmesh::LightMesh::nodes_to_probe)),
//! probed in a compute pass beside the level's fill, with the CPU's
//! directions, traversal and normals, so each flag is the CPU's. What
//! crosses is 4 bytes a node up (its brick and slot) and a bit down.
//!
//! Like the fill, the pass writes each flag into the node's brick in the
//! mask pool, so the level's shading reads it without the CPU waiting,
//! and its answers come back with the CPU's next wait, for its store.
//! Only hardware adapters that round as the CPU does run it
//! ([`ProbeSite::for_adapter`]): a normal a few ULPs off could turn a
//! probe that grazes a triangle from back to front, and a software
//! adapter traces on the CPU's own cores, several times slower than the
//! CPU's probes (BENCHMARKS.md, "Enclosure probes on the GPU").

use glam::IVec3;

use super::context::{GpuContext, GpuError};
use super::contract::{FILL_BRICKS, ITEMS, POOL};
use super::fill::{table_node, FillTable};
use super::pass::{answer_buffer, Dispatch, WorldPass, WorldUse, BATCH};
use super::recording::{Downloaded, Downloads, Part, PendingWords, Recording};
use super::scene::{storage, GpuScene};
use super::shaders::Entry;
use crate::lightmesh::enclosure::ProbeList;
use crate::lightmesh::lattice::Lattice;

/// Where the GPU backend runs LMM1's enclosure probes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ProbeSite {
    /// On the CPU, into its store, before the pool takes the flags.
    Cpu,
    /// Beside the level's fill, into the pool ([`ProbePass`]).
    Gpu,
}

impl ProbeSite {
    /// The GPU where it is one and rounds as the CPU does; else the CPU.
    pub fn for_adapter(context: &GpuContext) -> ProbeSite {
        if context.exact && !context.is_software() {
            ProbeSite::Gpu
        } else {
            ProbeSite::Cpu
        }
    }
}

/// The probes' pipeline, made once per run.
pub struct ProbePass {
    pub(super) pass: WorldPass,
}

impl ProbePass {
    pub fn new(context: &GpuContext) -> ProbePass {
        ProbePass {
            pass: WorldPass::new(
                context,
                Entry::EnclosureProbes,
                WorldUse::Traces,
                &[FILL_BRICKS],
                &[POOL],
            ),
        }
    }

    /// Records the probes of `probes`' nodes against `scene`'s static
    /// structure, each flag written into `pool`, where `table` (the
    /// level's [`FillTable`](super::fill::FillTable), uploaded) places
    /// their bricks. The answers come back with the CPU's next wait.
    pub fn record(
        &self,
        context: &GpuContext,
        recording: &mut Recording,
        scene: &GpuScene,
        (pool, table): (&wgpu::Buffer, &wgpu::Buffer),
        probes: &ProbeList,
    ) -> Result<ProbeAnswers, GpuError> {
        let nodes: Vec<u32> = (probes.nodes())
            .map(|(brick, slot)| table_node(brick, slot))
            .collect();
        let mut answers = ProbeAnswers {
            count: nodes.len(),
            ..ProbeAnswers::default()
        };
        context.checked(Entry::EnclosureProbes.name(), || {
            // Each batch's answers start a word of their own.
            for batch in nodes.chunks(BATCH) {
                let items = storage(context, "probed nodes", batch)?;
                let words = batch.len().div_ceil(32);
                let out = answer_buffer::<u32>(context, "enclosure flags", words)?;
                let reads = [(ITEMS, &items), (FILL_BRICKS, table), (POOL, pool)];
                let dispatch = Dispatch::new(scene, batch.len());
                (self.pass).record(context, recording.encoder(), dispatch, &reads, &out);
                answers.words.push(out, words);
            }
            Ok::<_, GpuError>(())
        })?;
        Ok(answers)
    }
    /// Probes `probes`' nodes of `bricks` (on `lattice`, reaching
    /// `reach`) on their own and waits for their flags, one per node in
    /// order (they also go to a scratch pool of the bricks): the GPU's
    /// probes, for comparing with the CPU's.
    pub fn trace(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        place: (&Lattice, f32),
        bricks: &[IVec3],
        probes: &ProbeList,
    ) -> Result<Vec<bool>, GpuError> {
        let (table, scratch) = FillTable::scratch(context, place, 1, bricks)?;
        let mut recording = Recording::new(context);
        let mut answers =
            self.record(context, &mut recording, scene, (&scratch, &table), probes)?;
        (answers.words).wait_for_all(&mut recording, "the probes' flags, for comparing")?;
        Ok(answers.enclosed())
    }
}

/// The flags of a level's probes, a bit per node in the list's order,
/// until the CPU's next wait brings them back.
#[derive(Default)]
pub struct ProbeAnswers {
    words: PendingWords,
    /// Nodes probed.
    count: usize,
}

impl ProbeAnswers {
    /// Adds the flags still on the GPU to what a wait brings back.
    pub fn download<'s>(&'s self, downloads: &mut Downloads<'s>) -> Vec<Part<u32>> {
        self.words.download(downloads)
    }

    /// Keeps what a wait brought back of `parts`.
    pub fn keep(&mut self, downloaded: &Downloaded, parts: Vec<Part<u32>>) {
        self.words.keep(downloaded, parts);
    }

    /// Whether each node is enclosed, in order, once every part is back.
    pub fn enclosed(&self) -> Vec<bool> {
        let words = self.words.words();
        (0..self.count)
            .map(|index| words[index / 32] >> (index % 32) & 1 == 1)
            .collect()
    }
}
