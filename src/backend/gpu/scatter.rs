//! The Whitted recursion on the GPU: each level's mirror and glass rays
//! made from its shading points where they lie (`scatter.wgsl`), then
//! packed in point order by a prefix sum over the rays each point spawned
//! (`scan_blocks.wgsl`, `scan_sums.wgsl`, `compact.wgsl`): the next level
//! lists its rays as the CPU's `flat_map` over `secondary_rays` does. Its
//! length stays on the GPU, where the compaction writes it as the item
//! count and the indirect dispatch arguments of the next level's passes,
//! and adds it to the film's count of secondary rays. The CPU sizes the
//! next level by its bound instead: this level's rays times the most rays
//! a point of the frame's materials spawns. Only where that bound is more
//! than a batch does the CPU wait for the length, to split the level into
//! batches as long as it is (a level of a batch at most keeps every
//! dispatch within 65535 workgroups in x, and memory within a batch's).

use super::context::{GpuContext, GpuError};
use super::contract::{
    BLOCK_OFFSETS, COUNTERS, ITEMS, LEVEL_LENGTH, LEVEL_LENGTH_WORDS, LOCAL_OFFSETS, SECOND_OUTPUT,
    SLOTS, WORKGROUP,
};
use super::pass::{answer_buffer, Dispatch, WorldPass, WorldUse, BATCH};
use super::recording::Recording;
use super::scene::GpuScene;
use super::shaders::Entry;
use super::surface::{LevelBuffers, PathRay};

/// The four pipelines, made once per run.
pub struct ScatterPasses {
    pub(super) scatter: WorldPass,
    pub(super) scan_blocks: WorldPass,
    pub(super) scan_sums: WorldPass,
    pub(super) compact: WorldPass,
}

impl ScatterPasses {
    pub fn new(context: &GpuContext) -> ScatterPasses {
        let pass = |entry, reads: &[u32], writes: &[u32]| {
            WorldPass::new(context, entry, WorldUse::None, reads, writes)
        };
        ScatterPasses {
            scatter: pass(Entry::Scatter, &[], &[SECOND_OUTPUT]),
            scan_blocks: pass(Entry::ScanBlocks, &[], &[SECOND_OUTPUT]),
            scan_sums: pass(Entry::ScanSums, &[], &[LEVEL_LENGTH, COUNTERS]),
            compact: pass(Entry::Compact, &[SLOTS, LOCAL_OFFSETS, BLOCK_OFFSETS], &[]),
        }
    }

    /// Records the passes that make the next level from `level`'s shading
    /// points, whose points spawn at most `rays_per_point` rays each, and
    /// returns the next level: one level counted on the GPU, or where its
    /// bound is more than a batch, batches of at most [`BATCH`] rays
    /// after a wait for its length (none when no point spawns a ray).
    /// The level's length is added to `counters`, the film's.
    pub fn next_level(
        &self,
        context: &GpuContext,
        recording: &mut Recording,
        scene: &GpuScene,
        level: &LevelBuffers,
        rays_per_point: usize,
        counters: &wgpu::Buffer,
    ) -> Result<Vec<LevelBuffers>, GpuError> {
        let count = level.count;
        let bound = rays_per_point * count;
        if bound == 0 {
            return Ok(Vec::new());
        }
        let blocks = count.div_ceil(WORKGROUP as usize);
        let slots = answer_buffer::<PathRay>(context, "scattered rays", 2 * count)?;
        let counts = answer_buffer::<u32>(context, "rays per point", count)?;
        let local_offsets = answer_buffer::<u32>(context, "ray offsets", count)?;
        let block_totals = answer_buffer::<u32>(context, "rays per group", blocks)?;
        let block_offsets = answer_buffer::<u32>(context, "group offsets", blocks + 1)?;
        let next = answer_buffer::<PathRay>(context, "next level", bound)?;
        let length = context.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("next level's length"),
            size: (LEVEL_LENGTH_WORDS as usize * size_of::<u32>()) as u64,
            usage: wgpu::BufferUsages::STORAGE
                | wgpu::BufferUsages::INDIRECT
                | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });

        let encoder = recording.encoder();
        let reads = [(ITEMS, &level.points), (SECOND_OUTPUT, &counts)];
        (self.scatter).record(context, encoder, level.dispatch(scene), &reads, &slots);
        let reads = [(ITEMS, &counts), (SECOND_OUTPUT, &block_totals)];
        let dispatch = level.dispatch(scene);
        (self.scan_blocks).record(context, encoder, dispatch, &reads, &local_offsets);
        let reads = [
            (ITEMS, &block_totals),
            (LEVEL_LENGTH, &length),
            (COUNTERS, counters),
        ];
        let lanes = Dispatch::new(scene, WORKGROUP as usize);
        (self.scan_sums).record(context, encoder, lanes, &reads, &block_offsets);
        let reads = [
            (ITEMS, &counts),
            (SLOTS, &slots),
            (LOCAL_OFFSETS, &local_offsets),
            (BLOCK_OFFSETS, &block_offsets),
        ];
        (self.compact).record(context, encoder, level.dispatch(scene), &reads, &next);

        if bound <= BATCH {
            return Ok(vec![LevelBuffers::with_paths(
                context,
                next,
                bound,
                Some(length),
            )?]);
        }
        let why = "the length of a next level that may hold more than a batch";
        let total = recording.read_back::<u32>(why, &length, 1)?[0] as usize;
        split(context, recording, next, total)
    }
}

/// `total` rays at the start of `paths` as levels of at most [`BATCH`]
/// rays, the first in `paths` itself and the rest copied out on the GPU.
fn split(
    context: &GpuContext,
    recording: &mut Recording,
    paths: wgpu::Buffer,
    total: usize,
) -> Result<Vec<LevelBuffers>, GpuError> {
    let mut batches = batches(total).into_iter();
    let Some(first) = batches.next() else {
        return Ok(Vec::new());
    };
    let size = size_of::<PathRay>() as u64;
    let mut levels = Vec::new();
    for batch in batches {
        let part = answer_buffer::<PathRay>(context, "next level", batch.len())?;
        let bytes = batch.len() as u64 * size;
        let from = batch.start as u64 * size;
        (recording.encoder()).copy_buffer_to_buffer(&paths, from, &part, 0, bytes);
        levels.push(LevelBuffers::with_paths(context, part, batch.len(), None)?);
    }
    levels.insert(
        0,
        LevelBuffers::with_paths(context, paths, first.len(), None)?,
    );
    Ok(levels)
}

/// `0..total` in consecutive batches of at most [`BATCH`]; none for 0.
pub fn batches(total: usize) -> Vec<std::ops::Range<usize>> {
    (0..total)
        .step_by(BATCH)
        .map(|start| start..(start + BATCH).min(total))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn batches_cover_every_ray_once_in_order() {
        assert!(batches(0).is_empty());
        assert_eq!(batches(1), vec![0..1]);
        assert_eq!(batches(BATCH), vec![0..BATCH]);
        assert_eq!(batches(BATCH + 1), vec![0..BATCH, BATCH..BATCH + 1]);
        assert_eq!(
            batches(2 * BATCH),
            vec![0..BATCH, BATCH..2 * BATCH],
            "a level twice the batch (every point spawned two rays)"
        );
    }
}
