//! `--method lmm` and `lmm1` on the GPU: formula (2) at each level's
//! shading points where they lie (`light_mesh.wgsl`), from the masks in
//! the pool ([`MaskPool`]).
//!
//! The masks' authority stays the CPU's [`LightMesh`]: a level's points
//! come back once, the CPU runs demand, fill and (for LMM1) enclosure on
//! them exactly as the CPU backend does, and the pool takes the bricks
//! the level reads that it lacks or holds stale. So invalidation, reuse
//! across frames and the disk cache are the CPU's, unchanged, and the
//! masks the shader reads are the CPU backend's bit for bit. What runs on
//! the GPU is the per-point work: the half-ball, LMM's point-to-node
//! segments, the counts and Omega, and formula (1) where the set is empty.

use std::time::Instant;

use glam::IVec3;

use super::context::GpuContext;
use super::direct::FrameLights;
use super::mask_pool::MaskPool;
use super::pass::{answer_buffer, read_back, Dispatch, WorldPass, WorldUse, ITEMS};
use super::scene::{storage, GpuScene};
use super::shaders::Entry;
use super::surface::{LevelBuffers, SurfacePoint};
use crate::backend::RenderError;
use crate::lightmesh::interpolate::PointCounts;
use crate::lightmesh::{LightMesh, LightMeshStats};
use crate::render::omega::LightLanes;
use crate::render::surface::ShadingPoint;
use crate::render::FrameJob;
use crate::stats::FrameStats;

/// Bindings of `light_mesh.wgsl` beyond the points, answers and world.
const LIGHTS: u32 = 10;
const REACH: u32 = 11;
const DIRECTORY: u32 = 12;
const POOL: u32 = 13;
const COUNTS: u32 = 14;

/// The formula (2) pipeline, made once per run.
pub struct LightMeshPass {
    pass: WorldPass,
}

impl LightMeshPass {
    pub fn new(context: &GpuContext) -> LightMeshPass {
        LightMeshPass {
            pass: WorldPass::new(
                context,
                Entry::LightMesh,
                WorldUse::Traces,
                &[LIGHTS, REACH, DIRECTORY, POOL],
                &[COUNTS],
            ),
        }
    }
}

/// One frame's light-mesh shading: the CPU's light mesh, the GPU's pool,
/// and what they did, summed over the frame's levels.
pub struct LightMeshShading<'m> {
    mesh: &'m mut LightMesh,
    pool: &'m mut MaskPool,
    point_to_node_tests: bool,
    lanes: LightLanes,
    /// What demand, fill and enclosure did.
    work: LightMeshStats,
    /// The shader's counters ([`PointCounts`] as (low, high) pairs).
    counts: wgpu::Buffer,
}

/// The reaching lights of a level's points, uploaded for the shader.
pub struct LevelReach {
    reach: wgpu::Buffer,
}

impl<'m> LightMeshShading<'m> {
    pub fn new(
        context: &GpuContext,
        mesh: &'m mut LightMesh,
        pool: &'m mut MaskPool,
        point_to_node_tests: bool,
        job: &FrameJob,
    ) -> Result<LightMeshShading<'m>, RenderError> {
        Ok(LightMeshShading {
            mesh,
            pool,
            point_to_node_tests,
            lanes: LightLanes::new(&job.frame.lights),
            work: LightMeshStats::default(),
            counts: answer_buffer::<[u32; 8]>(context, "light-mesh counters", 1)?,
        })
    }

    /// Makes every mask bit `records` (a level's points, misses included)
    /// need valid in the light mesh and resident in the pool, as the CPU
    /// backend's demand, fill and enclosure stages would; returns the
    /// points' reaching lights for [`LightMeshShading::record`].
    pub fn prepare(
        &mut self,
        context: &GpuContext,
        job: &FrameJob,
        records: &[SurfacePoint],
        stats: &mut FrameStats,
    ) -> Result<LevelReach, RenderError> {
        let (index, points): (Vec<usize>, Vec<ShadingPoint>) = (records.iter().enumerate())
            .filter_map(|(index, record)| Some((index, record.shading_point()?)))
            .unzip();

        let start = Instant::now();
        let demand = self.mesh.demand(&points, &self.lanes)?;
        stats.add_stage_time("demand", start.elapsed().as_secs_f64());

        let start = Instant::now();
        let lights = &job.frame.lights;
        self.mesh.fill(&demand, lights, job.world, &mut self.work)?;
        stats.add_stage_time("fill", start.elapsed().as_secs_f64());

        if !self.point_to_node_tests {
            let start = Instant::now();
            self.work.nodes_probed += self.mesh.settle_enclosure(&demand, job.world);
            stats.add_stage_time("enclosure", start.elapsed().as_secs_f64());
        }

        let start = Instant::now();
        let bricks: Vec<IVec3> = demand.bricks.iter().map(|brick| brick.brick).collect();
        let upload = (self.pool).update(context, self.mesh, &bricks, self.point_to_node_tests)?;
        self.work.bricks_uploaded += upload.bricks;
        self.work.bricks_evicted += upload.evicted;
        let words = demand.words;
        let mut reach = vec![0u64; records.len() * words];
        for (point, &record) in index.iter().enumerate() {
            reach[record * words..(record + 1) * words].copy_from_slice(demand.reach_of(point));
        }
        let reach = storage(context, "reaching lights", &reach)?;
        stats.add_stage_time("upload", start.elapsed().as_secs_f64());
        Ok(LevelReach { reach })
    }

    /// Records formula (2) at `level`'s points into `direct`, with the
    /// masks [`LightMeshShading::prepare`] made resident for them.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        pass: &LightMeshPass,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        lights: &FrameLights,
        level: &LevelBuffers,
        reach: &LevelReach,
        direct: &wgpu::Buffer,
    ) {
        let (slots, directory) = self.pool.buffers();
        let reads = [
            (ITEMS, &level.points),
            (LIGHTS, lights.buffer()),
            (REACH, &reach.reach),
            (DIRECTORY, directory),
            (POOL, slots),
            (COUNTS, &self.counts),
        ];
        let dispatch = Dispatch::new(scene, level.count).with_lights(lights.count());
        (pass.pass).record(context, encoder, dispatch, &reads, direct);
    }

    /// The frame's light-mesh statistics, once its `shading_points` are
    /// shaded; the fill's node-to-light segments go to the shadow rays.
    pub fn finish(self, context: &GpuContext, stats: &mut FrameStats) -> Result<(), RenderError> {
        let encoder = context.device.create_command_encoder(&Default::default());
        let [counts]: [[u32; 8]; 1] = read_back(context, encoder, &self.counts, 1)?
            .try_into()
            .expect("one counter record was read");
        let pair = |at: usize| counts[2 * at] as u64 | (counts[2 * at + 1] as u64) << 32;
        let counts = PointCounts {
            candidates: pair(0),
            interp_set: pair(1),
            p2n_tests: pair(2),
            fallback: pair(3),
            shadow_rays: 0,
        };
        stats.rays.shadow += self.work.fill_segments;
        stats.lightmesh = Some(
            self.mesh
                .frame_stats(self.work, counts, stats.shading_points),
        );
        Ok(())
    }
}
