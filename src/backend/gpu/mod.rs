//! The GPU backend (wgpu): a frame as compute passes over the uploaded
//! world, with the CPU backend's arithmetic. Band by band
//! ([`frame`]), each level of the camera paths is one submission: the
//! camera's rays ([`camera`]) or the Whitted recursion's, closest hits
//! ([`trace`]), shading points made with the scene's meshes, materials and
//! textures ([`surface`]), formula (1) whole — Omega, shadow segments and
//! their sum — where the points lie ([`direct`]), their light added to
//! their pixel samples, and the next level's mirror and glass rays packed
//! in point order ([`scatter`]). The band's pixels come back resolved
//! ([`film`]). `--method area` brings a level's points back, to sample its
//! lamps on the CPU and test their segments on the GPU; `lmm` and `lmm1`
//! shade by formula (2) from masks resident on the GPU ([`mask_pool`]),
//! bringing back only the points those masks do not serve yet, for the
//! CPU's demand, whose missing bits the GPU fills ([`fill`],
//! [`light_mesh`]). With `--aovs`, the camera level's hits and, for the
//! `light` AOV, each level's terms summed per light layer where formula
//! (1) or (2) makes them ([`layered`]) go to an AOV film beside the
//! pixels' ([`aov_film`]), whose samples come back for the resolve the
//! CPU backend uses too.
//!
//! The passes round as the CPU does, so a frame differs from the CPU
//! backend's only where a query answers differently, and tests compare
//! exactly that: ray by ray, point by point and frame by frame.

mod aov_film;
mod camera;
mod context;
mod contract;
pub(crate) mod direct;
pub mod enclosure;
pub mod fill;
mod film;
mod frame;
mod layered;
mod light_mesh;
pub mod mask_pool;
mod pass;
pub mod pass_timer;
mod pipeline_cache;
mod pipeline_file;
mod pipelines;
mod recording;
mod scatter;
pub(crate) mod scene;
mod shaders;
mod spirv;
pub(crate) mod surface;
pub(crate) mod trace;
pub mod traffic;

use std::path::Path;
use std::time::Instant;

pub use context::{GpuContext, GpuError};
pub use direct::{DirectLightPass, FrameLights};
pub use scene::GpuScene;
pub use trace::RayQueries;

use super::aov::{AovFrame, LightLayers};
use super::band::bands;
use super::{thread_pool, BackendError, RenderError};
use crate::accel::{Ray, World};
use crate::lightmesh::segments::Shafts;
use crate::lightmesh::LightMesh;
use crate::output::{Image, RenderedFrame};
use crate::render::scatter::most_secondary_rays;
use crate::render::shadow_split::FrameMethod;
use crate::render::surface::ShadingPoint;
use crate::render::FrameJob;
use crate::scene::Material;
use crate::settings::{Aov, LightMeshSettings};
use crate::stats::FrameStats;
use enclosure::{ProbePass, ProbeSite};
use fill::FillPass;
use frame::{DirectMethod, Frame};
use light_mesh::LightMeshShading;
use mask_pool::MaskPool;
use pass_timer::PassTimer;
pub use pipeline_cache::PipelineMade;
use pipelines::Pipelines;
use surface::{FrameSurfaces, SceneSurfaces};
use traffic::GpuFrameStats;

pub struct GpuBackend {
    pool: rayon::ThreadPool,
    context: GpuContext,
    pipelines: Pipelines,
    /// The last world rendered, as uploaded.
    scene: Option<GpuScene>,
    /// Its scene's meshes and textures, and the world they were uploaded
    /// with.
    scene_surfaces: Option<(u64, SceneSurfaces)>,
    /// The last frame's placement, as uploaded.
    frame_surfaces: Option<FrameSurfaces>,
    /// The light mesh's masks, resident across frames; made by the first
    /// light-mesh frame.
    mask_pool: Option<MaskPool>,
    /// Bytes the mask pool may take.
    mask_memory: usize,
    /// Whether the light mesh's fill groups its segments by shafts first
    /// (`lightmesh::segments`; [`Shafts::Test`] unless set).
    fill_shafts: Shafts,
    /// Where LMM1's enclosure probes run ([`ProbeSite::for_adapter`]
    /// unless set).
    probe_site: ProbeSite,
}

impl GpuBackend {
    /// Finds the adapter; `threads` CPU workers make rays and shade. No
    /// pipeline is compiled yet: see [`GpuBackend::prepare_pipelines`].
    pub fn new(threads: Option<usize>) -> Result<GpuBackend, BackendError> {
        let context = GpuContext::new()?;
        let probe_site = ProbeSite::for_adapter(&context);
        Ok(GpuBackend {
            pool: thread_pool(threads)?,
            pipelines: Pipelines::new(&context),
            context,
            scene: None,
            scene_surfaces: None,
            frame_surfaces: None,
            mask_pool: None,
            mask_memory: LightMeshSettings::default().gpu_memory_mib << 20,
            fill_shafts: Shafts::Test,
            probe_site,
        })
    }

    /// Bounds the GPU memory the light mesh's masks may take (bricks no
    /// level reads are evicted first; a level that reads more is refused).
    pub fn limit_mask_memory(&mut self, bytes: usize) {
        self.mask_memory = bytes;
        self.mask_pool = None;
    }

    /// Sets whether the fill groups segments by shafts: for measuring both
    /// on one adapter (the bits are the same either way).
    pub fn set_fill_shafts(&mut self, shafts: Shafts) {
        self.fill_shafts = shafts;
    }

    /// Sets where LMM1's enclosure probes run: for comparing both on one
    /// adapter. [`ProbeSite::Gpu`] gives the CPU's flags only where the
    /// adapter rounds as the CPU does ([`GpuBackend::rounds_as_the_cpu`]).
    pub fn set_probe_site(&mut self, site: ProbeSite) {
        self.probe_site = site;
    }

    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// Keeps the driver's compiled pipelines in `dir` across runs: loads
    /// them now, and saves what a run adds (see `pipeline_cache`).
    pub fn keep_pipelines_in(&mut self, dir: &Path) {
        self.context.keep_pipelines_in(dir);
    }

    /// Compiles the pipelines frames by `method` with `aovs` need, side by
    /// side, reporting (compiled, of) to `progress`, and saves them to
    /// the pipeline cache. The times go to the next frame's stats.
    pub fn prepare_pipelines(
        &self,
        method: FrameMethod,
        aovs: &[Aov],
        progress: impl FnMut(usize, usize),
    ) {
        let context = &self.context;
        let passes = self
            .pipelines
            .needed(context, (method, self.probe_site), aovs);
        // As many threads as the run's workers (`--threads`); a software
        // adapter compiles on its one queue thread, at a pipeline's first
        // dispatch: more threads would only wait there, and each
        // pipeline's time would include the others'.
        let threads = match context.is_software() {
            true => 1,
            false => self.threads(),
        };
        Pipelines::prepare(context, &passes, threads, progress);
        self.save_pipelines();
    }

    /// Writes the pipeline cache if the run made a pipeline it lacks; a
    /// failure costs only the next run's compile, so it is a warning.
    fn save_pipelines(&self) {
        if let Err(error) = self.context.pipelines.save() {
            log::warn!("the GPU pipeline cache was not saved: {error}");
        }
    }

    /// Whether the adapter rounds as the CPU does (it has f64 and takes
    /// our own SPIR-V: `shaders::Arithmetic::ExactUncontracted`): then
    /// every answer and frame is the CPU backend's to the bit.
    pub fn rounds_as_the_cpu(&self) -> bool {
        self.context.exact
    }

    /// Whether the adapter has timestamp queries: then each frame's stats
    /// say how long its passes ran on the GPU ([`pass_timer`]).
    pub fn times_passes(&self) -> bool {
        self.context.pass_timer.is_some()
    }

    /// Whether the adapter is a CPU (lavapipe, WARP, SwiftShader): its
    /// timings say nothing of a GPU's, and lavapipe cuts long shader loops
    /// short ([`GpuError::LoopsCutShort`]).
    pub fn is_software(&self) -> bool {
        self.context.is_software()
    }

    /// The adapter's name, backend and driver, for the user.
    pub fn adapter(&self) -> String {
        self.context.to_string()
    }

    /// The passes and `world` as uploaded, for running them outside a
    /// frame (tests, benchmarks).
    pub fn passes_for(&mut self, world: &World) -> Result<GpuPasses<'_>, GpuError> {
        let scene = Self::upload(&mut self.scene, &self.context, world)?;
        Ok(GpuPasses {
            context: &self.context,
            queries: &self.pipelines.queries,
            direct: &self.pipelines.direct,
            fill: &self.pipelines.fill,
            probes: &self.pipelines.probes,
            scene,
        })
    }

    /// Brings `scene` up to `world` (see [`GpuScene::update`]), uploading
    /// it whole the first time.
    fn upload<'s>(
        scene: &'s mut Option<GpuScene>,
        context: &GpuContext,
        world: &World,
    ) -> Result<&'s GpuScene, GpuError> {
        match scene {
            Some(scene) => {
                scene.update(context, world)?;
                Ok(scene)
            }
            None => Ok(scene.insert(GpuScene::upload(context, world)?)),
        }
    }

    /// Uploads what `job`'s frame needs that the GPU does not hold yet:
    /// the world as it moved, the scene's meshes and textures for a new
    /// world, the frame's placement where it changed, and its lights
    /// (with how `method` shades each, and their layers where the `light`
    /// AOV asks for them).
    fn upload_frame(
        &mut self,
        job: &FrameJob,
        method: FrameMethod,
    ) -> Result<FrameLights, GpuError> {
        let context = &self.context;
        Self::upload(&mut self.scene, context, job.world)?;
        let world = job.world.id();
        if self.scene_surfaces.as_ref().map(|(id, _)| *id) != Some(world) {
            self.scene_surfaces = Some((world, SceneSurfaces::upload(context, job.scene)?));
            self.frame_surfaces = None;
        }
        FrameSurfaces::update(&mut self.frame_surfaces, context, job.frame)?;
        let layer_of = match job.aovs.contains(&Aov::Light) {
            true => LightLayers::of(job.scene).layer_of,
            false => Vec::new(),
        };
        let shading = direct::shading_flags(job, method);
        FrameLights::upload_shaded(context, &job.frame.lights, &shading, &layer_of)
    }

    /// `job`'s frame, whose uploads [`GpuBackend::upload_frame`] made.
    fn frame<'a>(&'a self, job: &'a FrameJob<'a>, lights: FrameLights) -> Frame<'a> {
        let (Some(scene), Some((_, scene_surfaces)), Some(frame_surfaces)) =
            (&self.scene, &self.scene_surfaces, &self.frame_surfaces)
        else {
            unreachable!("the world, its scene and the frame are uploaded with the frame");
        };
        Frame {
            job,
            context: &self.context,
            pipelines: &self.pipelines,
            scene,
            scene_surfaces,
            frame_surfaces,
            lights,
            rays_per_point: most_secondary_rays(
                (job.frame.materials.iter()).chain([&Material::default()]),
            ),
        }
    }

    /// Renders one frame by `method`, with the AOV layers `job` asks for;
    /// stage times, ray and point counts go to `stats`. A light-mesh frame
    /// shades from `light_mesh` (an error without one), whose masks the
    /// backend keeps resident; its passes also add the terms of the
    /// lights it shades by formula (1) first, as the CPU does. Each
    /// light's `shading` bits ([`direct::shading_flags`]) tell the passes
    /// which integrator is its.
    pub fn render(
        &mut self,
        job: &FrameJob,
        method: FrameMethod,
        light_mesh: Option<&mut LightMesh>,
        stats: &mut FrameStats,
    ) -> Result<RenderedFrame, RenderError> {
        let start = Instant::now();
        let traffic = self.context.traffic.snapshot();
        let mut aovs = AovFrame::new(job);
        if AovFrame::wants_light_terms(job) {
            self.context.check_light_layers()?;
        }
        let lights = self.upload_frame(job, method)?;
        let mut pool = match self.mask_pool.take() {
            Some(pool) => pool,
            None => MaskPool::new(&self.context, self.mask_memory)?,
        };
        let mut direct = match (method, light_mesh) {
            (FrameMethod::FormulaOne, _) => DirectMethod::Whitted,
            (FrameMethod::Lamps, _) => DirectMethod::Area,
            (FrameMethod::LightMesh { .. }, Some(mesh)) => {
                DirectMethod::LightMesh(Box::new(LightMeshShading::new(
                    &self.context,
                    mesh,
                    &mut pool,
                    (method, self.fill_shafts, self.probe_site),
                    job,
                )?))
            }
            (FrameMethod::LightMesh { .. }, None) => return Err(RenderError::NoLightMesh),
        };
        let frame = self.frame(job, lights);
        stats.add_stage_time("upload", start.elapsed().as_secs_f64());
        let pixels = self.pool.install(|| {
            let mut pixels = Vec::with_capacity((job.width * job.height) as usize);
            for rows in bands(job) {
                let (band, samples) = frame.render_band(rows, &mut direct, aovs.as_ref(), stats)?;
                pixels.extend(band);
                if let (Some(aovs), Some(samples)) = (&mut aovs, samples) {
                    aovs.add_band(job, &samples);
                }
            }
            Ok::<_, RenderError>(pixels)
        })?;
        if let DirectMethod::LightMesh(light_mesh) = direct {
            light_mesh.finish(&self.context, job, stats)?;
        }
        self.mask_pool = Some(pool);
        self.save_pipelines();
        let pipelines = self.context.pipelines.take_made();
        let timer = self.context.pass_timer.as_ref();
        stats.gpu = Some(GpuFrameStats {
            traffic: self.context.traffic.since(traffic),
            passes: timer.map(PassTimer::take).unwrap_or_default(),
            pipelines,
        });
        let image = Image {
            width: job.width,
            height: job.height,
            pixels,
        };
        Ok(RenderedFrame {
            image,
            aovs: aovs.map_or_else(Vec::new, AovFrame::into_layers),
        })
    }

    /// Computes the masks `job`'s frame will need without shading it, on
    /// the CPU workers (the CPU backend's stages): warming a farm's disk
    /// cache needs no GPU.
    pub fn warm(
        &self,
        job: &FrameJob,
        mesh: &mut LightMesh,
        probe_enclosure: bool,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        (self.pool).install(|| super::cpu::warm_light_mesh(job, mesh, probe_enclosure, stats))
    }

    /// The bricks of `mesh` whose slots in the mask pool do not hold
    /// what the store folds them to, read back from the GPU: none after a
    /// frame, for a test to check brick for brick.
    pub fn stale_mask_bricks(&self, mesh: &LightMesh) -> Result<Vec<glam::IVec3>, GpuError> {
        match &self.mask_pool {
            Some(pool) => pool.stale_bricks(&self.context, mesh.masks()),
            None => Ok(Vec::new()),
        }
    }

    /// The shading points of `rays`' closest hits as the GPU makes them
    /// for `job`'s frame (None where a ray hits nothing), for comparing
    /// with the CPU's.
    pub fn shading_points(
        &mut self,
        job: &FrameJob,
        rays: &[Ray],
    ) -> Result<Vec<Option<ShadingPoint>>, GpuError> {
        let lights = self.upload_frame(job, FrameMethod::FormulaOne)?;
        self.frame(job, lights).shading_points(rays)
    }
}

/// The backend's passes over one uploaded world.
pub struct GpuPasses<'a> {
    pub context: &'a GpuContext,
    pub queries: &'a RayQueries,
    pub direct: &'a DirectLightPass,
    pub fill: &'a FillPass,
    pub probes: &'a ProbePass,
    pub scene: &'a GpuScene,
}
