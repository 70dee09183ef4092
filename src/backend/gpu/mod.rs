//! The GPU backend (wgpu): the frame's stages as the CPU backend runs
//! them, with the work per sample, per ray and per point as compute passes
//! over the uploaded world. Each level of the Whitted recursion (the
//! camera's samples, then the reflected and refracted rays level by level)
//! is one submission: the camera's rays for level 0 ([`camera`]), closest
//! hits ([`trace`]), shading points made from them with the scene's
//! meshes, materials and textures ([`surface`]), and, for `--method
//! whitted`, formula (1) whole — Omega, shadow segments and their sum —
//! over those points where they lie ([`direct`]). The points and their
//! direct light come back once. The recursion's rays, the lamp samples of
//! `--method area` (whose shadow segments go back to the GPU) and resolve
//! stay the CPU's code.
//!
//! The passes round as the CPU does, so a frame differs from the CPU
//! backend's only where a query answers differently, and tests compare
//! exactly that: ray by ray, point by point and frame by frame.

mod camera;
mod context;
pub(crate) mod direct;
mod pass;
pub(crate) mod scene;
mod shaders;
pub(crate) mod surface;
pub(crate) mod trace;

use std::time::Instant;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

pub use context::{GpuContext, GpuError};
pub use direct::{DirectLightPass, FrameLights};
pub use scene::GpuScene;
pub use trace::RayQueries;

use super::band::{bands, resolve, shaded_value};
use super::sampling::lamp_sample;
use super::{thread_pool, BackendError, RenderError};
use crate::accel::{Ray, World};
use crate::output::Image;
use crate::render::scatter::secondary_rays;
use crate::render::surface::ShadingPoint;
use crate::render::{area, FrameJob};
use crate::settings::Method;
use crate::stats::FrameStats;
use camera::{CameraPass, CameraRecord};
use direct::DirectLight;
use pass::{answer_buffer, read_back, BATCH};
use surface::{FrameSurfaces, LevelBuffers, PathRay, SceneSurfaces, SurfacePass, SurfacePoint};

/// Points whose lamp samples go to the GPU together (`--method area`): at
/// 64 lights, about a million segments.
const SHADE_CHUNK: usize = 16384;

pub struct GpuBackend {
    pool: rayon::ThreadPool,
    context: GpuContext,
    camera: CameraPass,
    queries: RayQueries,
    surfaces: SurfacePass,
    direct: DirectLightPass,
    /// The last world rendered, as uploaded.
    scene: Option<GpuScene>,
    /// Its scene's meshes and textures, and the world they were uploaded
    /// with.
    scene_surfaces: Option<(u64, SceneSurfaces)>,
}

impl GpuBackend {
    /// Finds the adapter and builds the pipelines; `threads` CPU workers
    /// make rays and shade.
    pub fn new(threads: Option<usize>) -> Result<GpuBackend, BackendError> {
        let context = GpuContext::new()?;
        Ok(GpuBackend {
            pool: thread_pool(threads)?,
            camera: CameraPass::new(&context),
            queries: RayQueries::new(&context),
            surfaces: SurfacePass::new(&context),
            direct: DirectLightPass::new(&context),
            context,
            scene: None,
            scene_surfaces: None,
        })
    }

    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
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
            queries: &self.queries,
            direct: &self.direct,
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
    /// world, and the frame's lights and placement; then the frame's view
    /// of the backend.
    fn frame<'a>(&'a mut self, job: &'a FrameJob<'a>) -> Result<Frame<'a>, GpuError> {
        let context = &self.context;
        Self::upload(&mut self.scene, context, job.world)?;
        let world = job.world.id();
        if self.scene_surfaces.as_ref().map(|(id, _)| *id) != Some(world) {
            self.scene_surfaces = Some((world, SceneSurfaces::upload(context, job.scene)?));
        }
        let frame_surfaces = FrameSurfaces::upload(context, job.frame)?;
        let lights = FrameLights::upload(context, &job.frame.lights)?;
        let (Some(scene), Some((_, scene_surfaces))) = (&self.scene, &self.scene_surfaces) else {
            unreachable!("both were uploaded above");
        };
        Ok(Frame {
            job,
            pool: &self.pool,
            context,
            camera: &self.camera,
            queries: &self.queries,
            surfaces: &self.surfaces,
            direct: &self.direct,
            scene,
            scene_surfaces,
            frame_surfaces,
            lights,
        })
    }

    /// Renders one frame; stage times, ray and point counts go to `stats`.
    /// The light-mesh methods are the CPU backend's: refused before any
    /// upload (settings refuse them before a run starts).
    pub fn render(
        &mut self,
        job: &FrameJob,
        method: Method,
        stats: &mut FrameStats,
    ) -> Result<Image, RenderError> {
        if method.uses_light_mesh() {
            return Err(GpuError::LightMeshOnGpu.into());
        }
        let start = Instant::now();
        let frame = self.frame(job)?;
        stats.add_stage_time("upload", start.elapsed().as_secs_f64());
        frame.pool.install(|| {
            let mut pixels = Vec::with_capacity((job.width * job.height) as usize);
            for rows in bands(job) {
                pixels.extend(frame.render_band(rows, method, stats)?);
            }
            Ok(Image {
                width: job.width,
                height: job.height,
                pixels,
            })
        })
    }

    /// The shading points of `rays`' closest hits as the GPU makes them
    /// for `job`'s frame (None where a ray hits nothing), for comparing
    /// with the CPU's.
    pub fn shading_points(
        &mut self,
        job: &FrameJob,
        rays: &[Ray],
    ) -> Result<Vec<Option<ShadingPoint>>, GpuError> {
        let paths: Vec<PathRay> = (rays.iter())
            .map(|ray| PathRay::new(ray, 0, Vec3::ONE, 0))
            .collect();
        let frame = self.frame(job)?;
        let mut points = Vec::with_capacity(rays.len());
        for batch in paths.chunks(BATCH) {
            let (records, _) = frame.trace_batch(Paths::Uploaded(batch), false)?;
            points.extend(records.iter().map(SurfacePoint::shading_point));
        }
        Ok(points)
    }
}

/// The backend's passes over one uploaded world.
pub struct GpuPasses<'a> {
    pub context: &'a GpuContext,
    pub queries: &'a RayQueries,
    pub direct: &'a DirectLightPass,
    pub scene: &'a GpuScene,
}

/// One frame's view of the backend, with the frame's uploads.
struct Frame<'a> {
    job: &'a FrameJob<'a>,
    pool: &'a rayon::ThreadPool,
    context: &'a GpuContext,
    camera: &'a CameraPass,
    queries: &'a RayQueries,
    surfaces: &'a SurfacePass,
    direct: &'a DirectLightPass,
    scene: &'a GpuScene,
    scene_surfaces: &'a SceneSurfaces,
    frame_surfaces: FrameSurfaces,
    lights: FrameLights,
}

/// The path rays of a level: made by the CPU (the Whitted recursion's),
/// or the camera's samples of the band from a row on (made on the GPU),
/// by their range in the band.
#[derive(Clone)]
enum Paths<'a> {
    Uploaded(&'a [PathRay]),
    Camera(u32, std::ops::Range<usize>),
}

impl Paths<'_> {
    /// The level in batches of at most [`BATCH`] rays.
    fn batches(&self) -> Vec<Paths<'_>> {
        match self {
            Paths::Uploaded(paths) => paths.chunks(BATCH).map(Paths::Uploaded).collect(),
            Paths::Camera(first_row, samples) => (samples.clone().step_by(BATCH))
                .map(|start| Paths::Camera(*first_row, start..(start + BATCH).min(samples.end)))
                .collect(),
        }
    }
}

/// A level's shading points and, for `--method whitted`, their direct
/// light and the shadow segments it took.
#[derive(Default)]
struct Level {
    points: Vec<ShadingPoint>,
    direct: Vec<Vec3>,
    shadow_rays: u64,
}

impl Level {
    fn extend(&mut self, other: Level) {
        self.points.extend(other.points);
        self.direct.extend(other.direct);
        self.shadow_rays += other.shadow_rays;
    }
}

impl Frame<'_> {
    fn render_band(
        &self,
        rows: std::ops::Range<u32>,
        method: Method,
        stats: &mut FrameStats,
    ) -> Result<Vec<Vec4>, GpuError> {
        let job = self.job;
        let band_samples = ((rows.end - rows.start) * job.width * job.spp) as usize;
        let whitted = method == Method::Whitted;

        let start = Instant::now();
        let mut shaded = self.trace(Paths::Camera(rows.start, 0..band_samples), whitted)?;
        let primary = shaded.points.len();
        stats.rays.primary += band_samples as u64;
        stats.add_stage_time("primary", start.elapsed().as_secs_f64());

        let start = Instant::now();
        let mut frontier = 0..primary;
        for _ in 0..job.max_depth {
            let paths: Vec<PathRay> = shaded.points[frontier.clone()]
                .iter()
                .flat_map(|point| {
                    secondary_rays(point).map(|secondary| {
                        let depth = point.depth + 1;
                        PathRay::new(&secondary.ray, point.sample, secondary.weight, depth)
                    })
                })
                .collect();
            stats.rays.secondary += paths.len() as u64;
            let next = self.trace(Paths::Uploaded(&paths), whitted)?;
            if next.points.is_empty() {
                break;
            }
            frontier = shaded.points.len()..shaded.points.len() + next.points.len();
            shaded.extend(next);
        }
        stats.add_stage_time("secondary", start.elapsed().as_secs_f64());

        let start = Instant::now();
        if !whitted {
            let band_start = rows.start as u64 * job.width as u64 * job.spp as u64;
            (shaded.direct, shaded.shadow_rays) = self.area_light(&shaded.points, band_start)?;
        }
        let points = &shaded.points;
        let values: Vec<Vec3> = (points.par_iter().zip(&shaded.direct))
            .map(|(point, &light)| shaded_value(point, light))
            .collect();
        stats.rays.shadow += shaded.shadow_rays;
        stats.shading_points += points.len() as u64;
        stats.add_stage_time("shade", start.elapsed().as_secs_f64());

        let start = Instant::now();
        let pixels = resolve(job, band_samples, points, primary, &values);
        stats.add_stage_time("resolve", start.elapsed().as_secs_f64());
        Ok(pixels)
    }

    /// One level of paths on the GPU: their shading points in ray order
    /// (misses dropped) and, `with_direct`, formula (1) at each.
    fn trace(&self, paths: Paths, with_direct: bool) -> Result<Level, GpuError> {
        let mut level = Level::default();
        for batch in paths.batches() {
            let (records, direct) = self.trace_batch(batch, with_direct)?;
            for (index, record) in records.iter().enumerate() {
                let Some(point) = record.shading_point() else {
                    continue;
                };
                level.points.push(point);
                if let Some(answer) = direct.get(index) {
                    level.direct.push(answer.radiance());
                    level.shadow_rays += answer.shadow_rays();
                }
            }
        }
        Ok(level)
    }

    /// Closest hits, shading points and (`with_direct`) formula (1) for at
    /// most [`BATCH`] paths in one submission; the points and the direct
    /// light come back.
    fn trace_batch(
        &self,
        paths: Paths,
        with_direct: bool,
    ) -> Result<(Vec<SurfacePoint>, Vec<DirectLight>), GpuError> {
        let context = self.context;
        context.checked("tracing a level of paths", || {
            let mut encoder = context.device.create_command_encoder(&Default::default());
            let level = match paths {
                Paths::Uploaded(paths) => LevelBuffers::new(context, paths)?,
                Paths::Camera(first_row, batch) => {
                    let camera = CameraRecord::new(self.job, first_row, batch.start as u32);
                    let count = batch.len();
                    (self.camera).rays(context, &mut encoder, self.scene, &camera, count)?
                }
            };
            let count = level.count;
            (self.queries).record_closest(context, &mut encoder, self.scene, &level);
            self.surfaces.record(
                context,
                &mut encoder,
                self.scene,
                self.scene_surfaces,
                &self.frame_surfaces,
                &level,
            );
            let direct = match with_direct {
                true => {
                    let direct = answer_buffer::<DirectLight>(context, "direct light", count)?;
                    (self.direct).record(
                        context,
                        &mut encoder,
                        self.scene,
                        &self.lights,
                        &level,
                        &direct,
                    );
                    Some(direct)
                }
                false => None,
            };
            let points = read_back(context, encoder, &level.points, count)?;
            let direct = match direct {
                Some(direct) => {
                    let encoder = context.device.create_command_encoder(&Default::default());
                    read_back(context, encoder, &direct, count)?
                }
                None => Vec::new(),
            };
            Ok((points, direct))
        })
    }

    /// `--method area`: each point's lamp samples are made on the CPU in
    /// light order, their segments tested on the GPU, and the visible
    /// samples summed in that order, so a point gets the CPU backend's
    /// bits wherever the segments get its answers.
    fn area_light(
        &self,
        points: &[ShadingPoint],
        band_start: u64,
    ) -> Result<(Vec<Vec3>, u64), GpuError> {
        let job = self.job;
        let mut direct = Vec::with_capacity(points.len());
        let mut shadow_rays = 0;
        for chunk in points.chunks(SHADE_CHUNK) {
            let samples: Vec<LampSamples> = chunk
                .par_iter()
                .map(|point| {
                    let mut samples = LampSamples::default();
                    let sample = band_start + point.sample as u64;
                    let lamp = |light| lamp_sample(sample, job.spp, light, point.depth);
                    area::light_samples(point, &job.frame.lights, lamp, |s| {
                        samples.values.push(s.value);
                        samples.rays.push(s.shadow_ray);
                    });
                    samples
                })
                .collect();
            let rays: Vec<Ray> = samples
                .iter()
                .flat_map(|s| s.rays.iter().copied())
                .collect();
            shadow_rays += rays.len() as u64;
            let occluded = self.queries.occluded(self.context, self.scene, &rays)?;
            let mut answers = occluded.into_iter();
            for point_samples in &samples {
                let mut radiance = Vec3::ZERO;
                for (value, blocked) in point_samples.values.iter().zip(answers.by_ref()) {
                    if !blocked {
                        radiance += *value;
                    }
                }
                direct.push(radiance);
            }
        }
        Ok((direct, shadow_rays))
    }
}

/// One point's lamp samples in light order, visibility aside.
#[derive(Default)]
struct LampSamples {
    values: Vec<Vec3>,
    rays: Vec<Ray>,
}
