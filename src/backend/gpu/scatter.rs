//! The Whitted recursion on the GPU: each level's mirror and glass rays
//! made from its shading points where they lie (`scatter.wgsl`), then
//! packed in point order by a prefix sum over the rays each point spawned
//! (`scan_blocks.wgsl`, `scan_sums.wgsl`, `compact.wgsl`): the next level
//! lists its rays as the CPU's `flat_map` over `secondary_rays` does, and
//! only its length comes back.

use super::context::{GpuContext, GpuError};
use super::contract::{BLOCK_OFFSETS, ITEMS, LOCAL_OFFSETS, SECOND_OUTPUT, SLOTS, WORKGROUP};
use super::pass::{answer_buffer, read_back, Dispatch, WorldPass, WorldUse, BATCH};
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
            scan_sums: pass(Entry::ScanSums, &[], &[]),
            compact: pass(Entry::Compact, &[SLOTS, LOCAL_OFFSETS, BLOCK_OFFSETS], &[]),
        }
    }

    /// Records the passes that make the next level from `level`'s shading
    /// points into `encoder`, submits it, and returns the next level in
    /// batches of at most [`BATCH`] rays (none when no point spawned one).
    pub fn next_level(
        &self,
        context: &GpuContext,
        mut encoder: wgpu::CommandEncoder,
        scene: &GpuScene,
        level: &LevelBuffers,
    ) -> Result<Vec<LevelBuffers>, GpuError> {
        let count = level.count;
        let blocks = count.div_ceil(WORKGROUP as usize);
        let slots = answer_buffer::<PathRay>(context, "scattered rays", 2 * count)?;
        let counts = answer_buffer::<u32>(context, "rays per point", count)?;
        let local_offsets = answer_buffer::<u32>(context, "ray offsets", count)?;
        let block_totals = answer_buffer::<u32>(context, "rays per group", blocks)?;
        let block_offsets = answer_buffer::<u32>(context, "group offsets", blocks + 1)?;
        let next = answer_buffer::<PathRay>(context, "next level", 2 * count)?;

        let reads = [(ITEMS, &level.points), (SECOND_OUTPUT, &counts)];
        (self.scatter).record(
            context,
            &mut encoder,
            Dispatch::new(scene, count),
            &reads,
            &slots,
        );
        let reads = [(ITEMS, &counts), (SECOND_OUTPUT, &block_totals)];
        (self.scan_blocks).record(
            context,
            &mut encoder,
            Dispatch::new(scene, count),
            &reads,
            &local_offsets,
        );
        let reads = [(ITEMS, &block_totals)];
        let lanes = WORKGROUP as usize;
        (self.scan_sums).record(
            context,
            &mut encoder,
            Dispatch::new(scene, lanes),
            &reads,
            &block_offsets,
        );
        let reads = [
            (ITEMS, &counts),
            (SLOTS, &slots),
            (LOCAL_OFFSETS, &local_offsets),
            (BLOCK_OFFSETS, &block_offsets),
        ];
        (self.compact).record(
            context,
            &mut encoder,
            Dispatch::new(scene, count),
            &reads,
            &next,
        );

        let total = answer_buffer::<u32>(context, "next level's length", 1)?;
        encoder.copy_buffer_to_buffer(&block_offsets, 4 * blocks as u64, &total, 0, 4);
        let total = read_back::<u32>(context, encoder, &total, 1)?[0] as usize;
        split(context, next, total)
    }
}

/// `total` rays at the start of `paths` as levels of at most [`BATCH`]
/// rays, the first in `paths` itself and the rest copied out on the GPU.
fn split(
    context: &GpuContext,
    paths: wgpu::Buffer,
    total: usize,
) -> Result<Vec<LevelBuffers>, GpuError> {
    let mut batches = batches(total).into_iter();
    let Some(first) = batches.next() else {
        return Ok(Vec::new());
    };
    let size = size_of::<PathRay>() as u64;
    let mut encoder = context.device.create_command_encoder(&Default::default());
    let mut levels = Vec::new();
    for batch in batches {
        let part = answer_buffer::<PathRay>(context, "next level", batch.len())?;
        let bytes = batch.len() as u64 * size;
        encoder.copy_buffer_to_buffer(&paths, batch.start as u64 * size, &part, 0, bytes);
        levels.push(LevelBuffers::with_paths(context, part, batch.len())?);
    }
    context.queue.submit([encoder.finish()]);
    levels.insert(0, LevelBuffers::with_paths(context, paths, first.len())?);
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
