//! Formula (1) and (2) in two pipelines each: the beauty's, whose terms go
//! into their sum alone (`light_sum.wgsl`), and the `light` AOV's, which
//! also sums each point's terms per light layer into [`PointLayers`]
//! (`light_layers.wgsl`). The second binds one storage buffer more, which
//! some adapters lack, so it is made only when a run asks for it; a run
//! without `--aovs light` binds and runs just what it did before.

use std::sync::OnceLock;

use super::context::{GpuContext, GpuError};
use super::contract::POINT_LAYERS;
use super::pass::{answer_buffer, Bound, Dispatch, WorldPass, WorldUse};
use super::scene::storage;
use super::shaders::Entry;

/// A level's points' terms summed per light layer: `layers` sums per
/// point, in point order.
pub struct PointLayers {
    pub buffer: wgpu::Buffer,
    pub layers: usize,
}

impl PointLayers {
    /// All zero, for formula (1) or (2) to fill at `points` points.
    pub fn zeroed(
        context: &GpuContext,
        points: usize,
        layers: usize,
    ) -> Result<PointLayers, GpuError> {
        let buffer = answer_buffer::<[f32; 4]>(context, "points' light layers", points * layers)?;
        Ok(PointLayers { buffer, layers })
    }

    /// Sums made on the CPU (`--method area`), `layers` per point.
    pub fn upload(
        context: &GpuContext,
        sums: &[[f32; 4]],
        layers: usize,
    ) -> Result<PointLayers, GpuError> {
        let buffer = storage(context, "points' light layers", sums)?;
        Ok(PointLayers { buffer, layers })
    }
}

/// A pass by formula (1) or (2), with and without the light layers.
pub struct LayeredPass {
    plain: WorldPass,
    layered: OnceLock<WorldPass>,
    layered_entry: Entry,
    world: WorldUse,
    reads: Vec<u32>,
    writes: Vec<u32>,
}

impl LayeredPass {
    /// The pipeline of `entry` as [`WorldPass::new`] makes it, and the
    /// means to make `layered_entry`'s, which also writes [`POINT_LAYERS`].
    pub fn new(
        context: &GpuContext,
        (entry, layered_entry): (Entry, Entry),
        world: WorldUse,
        reads: &[u32],
        writes: &[u32],
    ) -> LayeredPass {
        LayeredPass {
            plain: WorldPass::new(context, entry, world, reads, writes),
            layered: OnceLock::new(),
            layered_entry,
            world,
            reads: reads.to_vec(),
            writes: writes.to_vec(),
        }
    }

    /// The beauty's pass.
    pub fn plain(&self) -> &WorldPass {
        &self.plain
    }

    /// The `light` AOV's pass, made now unless it is made (only where
    /// [`GpuContext::check_light_layers`] passes).
    pub fn layered(&self, context: &GpuContext) -> &WorldPass {
        self.layered.get_or_init(|| {
            let writes: Vec<u32> = self.writes.iter().copied().chain([POINT_LAYERS]).collect();
            WorldPass::new(
                context,
                self.layered_entry,
                self.world,
                &self.reads,
                &writes,
            )
        })
    }

    /// Records the pass as [`WorldPass::record`] does, keeping the terms
    /// in `layers` where given.
    pub fn record(
        &self,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        dispatch: Dispatch,
        reads: &[Bound],
        answers: &wgpu::Buffer,
        layers: Option<&PointLayers>,
    ) {
        let Some(layers) = layers else {
            return (self.plain).record(context, encoder, dispatch, reads, answers);
        };
        let reads: Vec<Bound> = (reads.iter().copied())
            .chain([(POINT_LAYERS, &layers.buffer)])
            .collect();
        let dispatch = dispatch.with_layers(layers.layers);
        (self.layered(context)).record(context, encoder, dispatch, &reads, answers);
    }
}
