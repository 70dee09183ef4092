//! `--method lmm` and `lmm1` on the GPU: formula (2) at each level's
//! shading points where they lie (`light_mesh.wgsl`), from the masks in
//! the pool ([`MaskPool`]).
//!
//! The masks' authority stays the CPU's [`LightMesh`], so invalidation,
//! reuse across frames and the disk cache are the CPU's, unchanged. Per
//! level: a coverage pass (`light_mesh_coverage.wgsl`) makes the points'
//! reaching lights and finds those whose every node already holds valid
//! bits in the pool; only the others come back (copied out by the pass,
//! with its flags), for the CPU's demand. The bits they miss are settled
//! by the CPU fill's shafts where those are clear and its walls where
//! one hides a group; the pool takes the words of the bricks edited. The
//! bits left are traced on the GPU ([`super::fill`]), and LMM1's
//! enclosure probes run beside them ([`super::enclosure`]; on the CPU,
//! before the fill, where the adapter is a software one or does not
//! round as the CPU does); both write into the pool themselves: the
//! level's shading follows without a wait, and the answers reach the
//! CPU's store at its next wait (the next level's coverage, or the
//! band's end). So the masks the shader reads are the CPU backend's bit
//! for bit, and what runs on the GPU is the
//! per-point work: the half-ball, LMM's point-to-node segments, the
//! counts and Omega, and formula (1) where the set is empty. Before it,
//! the pool's tiles are summarised (`tile_summaries.wgsl`), so that a
//! point whose nodes all agree on its lights skips the walk of its set
//! (`agreement.wgsl`, the CPU's `lightmesh::agreement`).

use std::time::Instant;

use glam::IVec3;

use super::context::{GpuContext, GpuError};
use super::contract::{
    COUNTS, COUNT_BLOCKER_RAYS, COUNT_CANDIDATES, COUNT_FALLBACK, COUNT_INTERPOLATION_SET,
    COUNT_POINT_TO_NODE_TESTS, COUNT_SETTLED, DIRECTORY, FLAGS, GATHERED, GATHER_SOURCE, ITEMS,
    LIGHTS, LIGHT_MESH_COUNTERS, LOOPS_CUT_SHORT, POOL, REACH, TILES_PER_SLOT, TILE_SUMMARIES,
};
use super::direct::FrameLights;
use super::enclosure::{ProbeAnswers, ProbePass, ProbeSite};
use super::fill::{FillAnswers, FillPass, FillTable, SEGMENTS_PER_WAIT};
use super::layered::{LayeredPass, PointLayers};
use super::mask_pool::MaskPool;
use super::pass::{answer_buffer, Dispatch, WorldPass, WorldUse, BATCH};
use super::recording::{Downloaded, Downloads, Part, Recording};
use super::scene::{storage, GpuScene};
use super::shaders::Entry;
use super::surface::{LevelBuffers, SurfacePoint};
use crate::backend::RenderError;
use crate::lightmesh::demand::Demand;
use crate::lightmesh::enclosure::ProbeList;
use crate::lightmesh::interpolate::PointCounts;
use crate::lightmesh::segments::{SegmentFill, Shafts};
use crate::lightmesh::{LightMesh, LightMeshStats};
use crate::render::omega::LightLanes;
use crate::render::shadow_split::{FrameMethod, LightRole};
use crate::render::surface::ShadingPoint;
use crate::render::FrameJob;
use crate::stats::FrameStats;

/// Formula (2)'s counters, as u32 words: (low, high) pairs of
/// [`PointCounts`], then the points whose loops the adapter cut short
/// (`light_mesh.wgsl`).
type Counters = [u32; LIGHT_MESH_COUNTERS as usize];

/// The light mesh's pipelines, made once per run: coverage (which points
/// the pool serves), gathering the points it does not, writing the words
/// of the pool that changed, summarising its tiles (their own nodes, then
/// the nodes around them), and formula (2).
pub struct LightMeshPasses {
    pub(super) coverage: WorldPass,
    pub(super) gather: WorldPass,
    pub(super) patch: WorldPass,
    pub(super) summarise_tiles: WorldPass,
    pub(super) summarise_around: WorldPass,
    pub(super) shade: LayeredPass,
}

impl LightMeshPasses {
    pub fn new(context: &GpuContext) -> LightMeshPasses {
        LightMeshPasses {
            coverage: WorldPass::new(
                context,
                Entry::LightMeshCoverage,
                WorldUse::None,
                &[LIGHTS, DIRECTORY, POOL],
                &[FLAGS, GATHERED],
            ),
            gather: WorldPass::new(
                context,
                Entry::GatherPoints,
                WorldUse::None,
                &[GATHER_SOURCE],
                &[],
            ),
            patch: WorldPass::new(context, Entry::PatchPool, WorldUse::None, &[], &[]),
            summarise_tiles: WorldPass::new(
                context,
                Entry::SummariseTiles,
                WorldUse::None,
                &[DIRECTORY, POOL],
                &[],
            ),
            summarise_around: WorldPass::new(
                context,
                Entry::SummariseAround,
                WorldUse::None,
                &[DIRECTORY, TILE_SUMMARIES],
                &[],
            ),
            shade: LayeredPass::new(
                context,
                (Entry::LightMesh, Entry::LightMeshLayers),
                WorldUse::Traces,
                &[LIGHTS, REACH, DIRECTORY, POOL, TILE_SUMMARIES],
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
    /// Where LMM1's enclosure probes run.
    probe_site: ProbeSite,
    /// Whether the fill's segments are first grouped by shafts.
    shafts: Shafts,
    /// The frame's lights with only those the light mesh shades powered:
    /// the demand asks for their bits alone.
    lanes: LightLanes,
    /// What demand, fill and enclosure did.
    work: LightMeshStats,
    /// The shader's counters ([`PointCounts`] as (low, high) pairs, then
    /// the points whose loops the adapter cut short), added up over the
    /// frame.
    counts: wgpu::Buffer,
    /// The counters as the last band's wait brought them back.
    counted: Counters,
    /// The last level's fill, while its answers are on the GPU.
    pending: Option<PendingFill>,
    /// Seconds the CPU's store spent taking the fills' answers, the
    /// frame's `merge` stage: it runs inside the waits' callers
    /// (`coverage`, `resolve`), so it is timed where it happens.
    merge_seconds: f64,
}

/// A level's fill (and enclosure probes) whose bits the GPU has written
/// into the pool and whose answers the CPU's store has not taken yet.
struct PendingFill {
    demand: Demand,
    /// The demand's bricks, whose slots the fill wrote.
    bricks: Vec<IVec3>,
    fill: SegmentFill,
    answers: FillAnswers,
    probes: Option<(ProbeList, ProbeAnswers)>,
}

/// Where a wait's downloads hold a pending fill's answers.
#[derive(Default)]
struct FillParts {
    fill: Vec<Part<u32>>,
    probes: Vec<Part<u32>>,
}

/// Where a wait's downloads hold the light mesh's part: formula (2)'s
/// counters (at a band's end) and a fill's answers.
pub struct LightMeshParts {
    counts: Part<Counters>,
    fill: FillParts,
}

/// What formula (2) reads at a level's points besides the pool: their
/// reaching lights, as the coverage pass made them, and the summaries of
/// the nodes around each tile, made after the level's fill.
pub struct PreparedLevel {
    reach: wgpu::Buffer,
    summaries: wgpu::Buffer,
}

impl<'m> LightMeshShading<'m> {
    pub fn new(
        context: &GpuContext,
        mesh: &'m mut LightMesh,
        pool: &'m mut MaskPool,
        (method, shafts, probe_site): (FrameMethod, Shafts, ProbeSite),
        job: &FrameJob,
    ) -> Result<LightMeshShading<'m>, RenderError> {
        let lights = &job.frame.lights;
        Ok(LightMeshShading {
            mesh,
            pool,
            point_to_node_tests: method.tests_point_to_node(),
            probe_site,
            shafts,
            lanes: (job.shadows).lanes(method, lights, |role| role == LightRole::LightMesh),
            work: LightMeshStats::default(),
            counts: answer_buffer::<Counters>(context, "light-mesh counters", 1)?,
            counted: [0; LIGHT_MESH_COUNTERS as usize],
            pending: None,
            merge_seconds: 0.0,
        })
    }

    /// Makes every mask bit `level`'s points need valid and resident in
    /// the pool before their shading, recorded after this: the coverage
    /// pass finds the points the pool does not serve yet, and only those
    /// come back for the CPU's demand and shafts (as the CPU backend runs
    /// them), after the level's one wait (where the pass had too little
    /// room to copy them all, one more gathers them); the bits left are
    /// traced on the GPU, and the nodes' enclosure probed, into the pool,
    /// with no wait, and the pool's tiles summarised. Returns what formula
    /// (2) reads besides the pool.
    #[allow(clippy::too_many_arguments)]
    pub fn prepare(
        &mut self,
        passes: &LightMeshPasses,
        (fill_pass, probe_pass): (&FillPass, &ProbePass),
        context: &GpuContext,
        job: &FrameJob,
        scene: &GpuScene,
        lights: &FrameLights,
        level: &LevelBuffers,
        recording: &mut Recording,
        stats: &mut FrameStats,
    ) -> Result<PreparedLevel, RenderError> {
        let start = Instant::now();
        let p2n = self.point_to_node_tests;
        let (edits, changed) = self.pool.refresh(context, self.mesh, p2n)?;
        edits.write(context, &passes.patch, scene, recording, self.pool)?;
        self.work.bricks_uploaded += changed;
        stats.add_stage_time("upload", start.elapsed().as_secs_f64());

        let start = Instant::now();
        let (reach, records, read_slots) =
            self.cover(passes, context, scene, lights, level, recording)?;
        stats.add_stage_time("coverage", start.elapsed().as_secs_f64());

        let points: Vec<ShadingPoint> = records
            .iter()
            .filter_map(SurfacePoint::shading_point)
            .collect();

        let start = Instant::now();
        self.work.points_demanded += points.len() as u64;
        let demand = self.mesh.demand(&points, &self.lanes)?;
        stats.add_stage_time("demand", start.elapsed().as_secs_f64());

        let start = Instant::now();
        let fill = (self.mesh).fill_segments(&demand, &job.frame.lights, job.world, self.shafts)?;
        self.mesh.settle_groups(&demand, &fill);
        stats.add_stage_time("fill", start.elapsed().as_secs_f64());

        let mut probes = None;
        if !p2n {
            let start = Instant::now();
            if self.probe_site == ProbeSite::Gpu {
                let list = self.mesh.nodes_to_probe(&demand);
                self.work.enclosure_reused += list.reused;
                probes = Some(list);
            } else {
                let enclosure = self.mesh.settle_enclosure(&demand, job.world);
                self.work.nodes_probed += enclosure.probed;
                self.work.enclosure_reused += enclosure.reused;
            }
            stats.add_stage_time("enclosure", start.elapsed().as_secs_f64());
        }

        let start = Instant::now();
        let bricks: Vec<IVec3> = demand.bricks.iter().map(|brick| brick.brick).collect();
        let (edits, upload) = (self.pool).admit(context, self.mesh, &bricks, &read_slots, p2n)?;
        edits.write(context, &passes.patch, scene, recording, self.pool)?;
        self.work.bricks_uploaded += upload.bricks;
        self.work.bricks_inserted += upload.inserted;
        self.work.bricks_evicted += upload.evicted;
        stats.add_stage_time("upload", start.elapsed().as_secs_f64());

        let start = Instant::now();
        let light_words = MaskPool::light_words(self.mesh.masks().lights());
        let starts = self.pool.slot_starts(&bricks);
        let place = (&self.mesh.lattice, self.mesh.probe_reach());
        let table = FillTable::new(place, light_words, &bricks, &starts).upload(context)?;
        let (pool, _) = self.pool.buffers();
        let targets = (pool, &table);
        let answers = fill_pass.record(
            context,
            recording,
            scene,
            lights,
            targets,
            &fill,
            SEGMENTS_PER_WAIT,
        )?;
        stats.add_stage_time("fill", start.elapsed().as_secs_f64());
        let probes = match probes {
            Some(list) => {
                let start = Instant::now();
                let answers = probe_pass.record(context, recording, scene, targets, &list)?;
                stats.add_stage_time("enclosure", start.elapsed().as_secs_f64());
                Some((list, answers))
            }
            None => None,
        };
        self.pending = Some(PendingFill {
            demand,
            bricks,
            fill,
            answers,
            probes,
        });
        let summaries = self.summarise(passes, context, scene, recording)?;
        Ok(PreparedLevel { reach, summaries })
    }

    /// Records the tile summaries of every brick the pool holds, from the
    /// bits the level's shading reads (recorded after its fill and probes):
    /// each tile's own nodes', then the nodes' around each tile, which
    /// formula (2) reads. LMM's sets, which no summary knows, get an empty
    /// buffer.
    fn summarise(
        &self,
        passes: &LightMeshPasses,
        context: &GpuContext,
        scene: &GpuScene,
        recording: &mut Recording,
    ) -> Result<wgpu::Buffer, RenderError> {
        let light_words = MaskPool::light_words(self.mesh.masks().lights());
        let per_slot = TILES_PER_SLOT as usize * (2 * light_words + 1);
        let slots = match self.point_to_node_tests {
            true => 0,
            false => self.pool.capacity(),
        };
        let own = answer_buffer::<u32>(context, "tile summaries", per_slot * slots)?;
        let around = answer_buffer::<u32>(context, "summaries around tiles", per_slot * slots)?;
        if slots == 0 {
            return Ok(around);
        }
        let (pool, directory) = self.pool.buffers();
        // The passes' items are the directory's entries, read through
        // DIRECTORY; each invocation takes every BATCH-th from its own.
        let dispatch = Dispatch::new(scene, self.pool.directory_entries().min(BATCH));
        let reads = [(ITEMS, directory), (DIRECTORY, directory), (POOL, pool)];
        (passes.summarise_tiles).record(context, recording.encoder(), dispatch, &reads, &own);
        let reads = [
            (ITEMS, directory),
            (DIRECTORY, directory),
            (TILE_SUMMARIES, &own),
        ];
        (passes.summarise_around).record(context, recording.encoder(), dispatch, &reads, &around);
        Ok(around)
    }

    /// Gives the CPU's store the last fill's answers, which a wait brought
    /// back (`parts` of `downloaded`): the pool holds those bits already,
    /// so nothing goes up.
    fn settle_fill(&mut self, downloaded: &Downloaded, parts: FillParts) {
        let Some(mut pending) = self.pending.take() else {
            return;
        };
        let start = Instant::now();
        pending.answers.keep(downloaded, parts.fill);
        let PendingFill {
            demand,
            bricks,
            fill,
            answers,
            probes,
        } = pending;
        let answers = answers.answers();
        (self.mesh).merge_segments(&demand, &fill, &answers, &mut self.work);
        if let Some((list, mut answers)) = probes {
            answers.keep(downloaded, parts.probes);
            let enclosure = self.mesh.merge_probes(&demand, &list, &answers.enclosed());
            self.work.nodes_probed += enclosure.probed;
        }
        self.pool.written_on_gpu(self.mesh.masks(), &bricks);
        self.merge_seconds += start.elapsed().as_secs_f64();
    }

    /// Adds the last fill's answers (and its probes'), where they are
    /// still on the GPU, to what a wait brings back.
    fn download_fill<'s>(&'s self, downloads: &mut Downloads<'s>) -> FillParts {
        let Some(pending) = self.pending.as_ref() else {
            return FillParts::default();
        };
        FillParts {
            fill: pending.answers.download(downloads),
            probes: (pending.probes.as_ref())
                .map_or_else(Vec::new, |(_, answers)| answers.download(downloads)),
        }
    }

    /// Records `level`'s coverage pass and waits for what the CPU needs
    /// from it: the points' reaching lights (left on the GPU), the points
    /// the pool does not serve, in the level's order (gathered after a
    /// second wait where the pass had no room to copy them all), and the
    /// slots the others read, a bit each.
    fn cover(
        &mut self,
        passes: &LightMeshPasses,
        context: &GpuContext,
        scene: &GpuScene,
        lights: &FrameLights,
        level: &LevelBuffers,
        recording: &mut Recording,
    ) -> Result<(wgpu::Buffer, Vec<SurfacePoint>, Vec<u32>), RenderError> {
        let light_words = MaskPool::light_words(self.mesh.masks().lights());
        // Per point, its reaching lights, then its lamps that are not faint.
        let reach_words = level.count * 2 * light_words;
        let reach = answer_buffer::<u32>(context, "reaching lights", reach_words)?;
        let point_words = level.count.div_ceil(32);
        let slot_words = self.pool.capacity().div_ceil(32);
        // The points' flags, the slots', and the count of points unserved.
        let flag_words = point_words + slot_words + 1;
        let flags = answer_buffer::<u32>(context, "coverage flags", flag_words)?;
        let room = self.pool.gather_room().min(level.count);
        let gathered = answer_buffer::<SurfacePoint>(context, "unserved points", room)?;
        let (slots, directory) = self.pool.buffers();
        let reads = [
            (ITEMS, &level.points),
            (LIGHTS, lights.buffer()),
            (DIRECTORY, directory),
            (POOL, slots),
            (FLAGS, &flags),
            (GATHERED, &gathered),
        ];
        let dispatch = level.dispatch(scene).with_lights(lights.count());
        (passes.coverage).record(context, recording.encoder(), dispatch, &reads, &reach);
        let mut downloads = Downloads::default();
        let flags_part = downloads.add::<u32>(&flags, flag_words);
        let gathered_part = downloads.add::<SurfacePoint>(&gathered, room);
        let fill_parts = self.download_fill(&mut downloads);
        let why =
            "the coverage flags and the points the pool does not serve, for the CPU's demand \
                   (and the last level's fill answers, for its store)";
        let downloaded = recording.wait(why, downloads)?;
        self.settle_fill(&downloaded, fill_parts);
        let flags = downloaded.take(flags_part);
        let (unserved, read_slots) = flags[..flag_words - 1].split_at(point_words);
        let count = flags[flag_words - 1] as usize;
        self.pool.served(count);
        let mut records = if count <= room {
            let mut records = downloaded.take(gathered_part);
            records.truncate(count);
            records
        } else {
            let unserved: Vec<u32> = (unserved.iter().enumerate())
                .flat_map(|(word, &bits)| {
                    crate::bits::set_bits(bits.into()).map(move |bit| (32 * word + bit) as u32)
                })
                .collect();
            self.gather(passes, context, recording, scene, level, &unserved)?
        };
        // The demand takes the points in the level's order, however the
        // GPU copied them.
        records.sort_unstable_by_key(SurfacePoint::level_index);
        Ok((reach, records, read_slots.to_vec()))
    }

    /// The points of `level` at `indices`, read back: those the pool does
    /// not serve, where the coverage pass had no room to copy them all.
    fn gather(
        &self,
        passes: &LightMeshPasses,
        context: &GpuContext,
        recording: &mut Recording,
        scene: &GpuScene,
        level: &LevelBuffers,
        indices: &[u32],
    ) -> Result<Vec<SurfacePoint>, RenderError> {
        if indices.is_empty() {
            return Ok(Vec::new());
        }
        let indices_buffer = storage(context, "unserved points", indices)?;
        let gathered = answer_buffer::<SurfacePoint>(context, "gathered points", indices.len())?;
        let reads = [(ITEMS, &indices_buffer), (GATHER_SOURCE, &level.points)];
        let dispatch = Dispatch::new(scene, indices.len());
        (passes.gather).record(context, recording.encoder(), dispatch, &reads, &gathered);
        let why = "the points the pool does not serve, for the CPU's demand";
        Ok(recording.read_back(why, &gathered, indices.len())?)
    }

    /// Records formula (2) at `level`'s points into `direct` (and their
    /// terms per light layer into `layers` where given), with the masks
    /// [`LightMeshShading::prepare`] made resident for them.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        passes: &LightMeshPasses,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        lights: &FrameLights,
        level: &LevelBuffers,
        prepared: &PreparedLevel,
        (direct, layers): (&wgpu::Buffer, Option<&PointLayers>),
    ) {
        let (slots, directory) = self.pool.buffers();
        let reads = [
            (ITEMS, &level.points),
            (LIGHTS, lights.buffer()),
            (REACH, &prepared.reach),
            (DIRECTORY, directory),
            (POOL, slots),
            (TILE_SUMMARIES, &prepared.summaries),
            (COUNTS, &self.counts),
        ];
        let dispatch = level.dispatch(scene).with_lights(lights.count());
        (passes.shade).record(context, encoder, dispatch, &reads, direct, layers);
    }

    /// Adds formula (2)'s counters and the last fill's answers to what a
    /// band's wait brings back.
    pub fn download<'s>(&'s self, downloads: &mut Downloads<'s>) -> LightMeshParts {
        LightMeshParts {
            counts: downloads.add(&self.counts, 1),
            fill: self.download_fill(downloads),
        }
    }

    /// Keeps what a band's wait brought back: the frame's counters so far,
    /// and the last fill's answers, for the store.
    pub fn downloaded(&mut self, downloaded: &Downloaded, parts: LightMeshParts) {
        if let Some(&counts) = downloaded.take(parts.counts).first() {
            self.counted = counts;
        }
        self.settle_fill(downloaded, parts.fill);
    }

    /// The frame's light-mesh statistics, once its `shading_points` are
    /// shaded and its last band's counters came back; the fill's
    /// node-to-light segments go to the shadow rays.
    pub fn finish(
        mut self,
        context: &GpuContext,
        job: &FrameJob,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        if self.pending.is_some() {
            let mut downloads = Downloads::default();
            let parts = self.download_fill(&mut downloads);
            let why = "the last fill's answers, which no band's wait brought back";
            let downloaded = Recording::new(context).wait(why, downloads)?;
            self.settle_fill(&downloaded, parts);
        }
        stats.add_stage_time("merge", self.merge_seconds);
        let counts = self.counted;
        let points = counts[LOOPS_CUT_SHORT as usize];
        if points > 0 {
            return Err(GpuError::LoopsCutShort {
                adapter: context.info.name.clone(),
                points,
            }
            .into());
        }
        let pair = |at: u32| {
            let at = 2 * at as usize;
            counts[at] as u64 | (counts[at + 1] as u64) << 32
        };
        let counts = PointCounts {
            candidates: pair(COUNT_CANDIDATES),
            interp_set: pair(COUNT_INTERPOLATION_SET),
            p2n_tests: pair(COUNT_POINT_TO_NODE_TESTS),
            fallback: pair(COUNT_FALLBACK),
            settled: pair(COUNT_SETTLED),
            blocker_rays: pair(COUNT_BLOCKER_RAYS),
            blocker_rays_remembered: 0,
            shadow_rays: Default::default(),
        };
        stats.rays.shadow += self.work.fill_segments;
        crate::backend::count_class_mask_bits(job, self.mesh, stats);
        stats.lightmesh = Some(
            self.mesh
                .frame_stats(self.work, counts, stats.shading_points),
        );
        Ok(())
    }
}
