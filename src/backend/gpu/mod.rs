//! The GPU backend (wgpu): the frame's stages as the CPU backend runs
//! them, with the ray tracing as compute passes over the uploaded world:
//! closest hits for the camera's samples and the Whitted recursion level
//! by level ([`trace`]), formula (1) whole — Omega, shadow segments and
//! their sum — in one pass ([`direct`]), and the shadow segments of
//! `--method area`. Making rays, completing hits into shading points,
//! sampling lamps and resolve stay the CPU's code on the CPU's threads.
//! The passes round as the CPU does, so a frame differs from the CPU
//! backend's only where a query answers differently, and tests compare
//! exactly that, ray by ray and frame by frame.
//!
//! Stages wait for their pass's answers (a readback per batch). Making
//! shading points on the GPU too is what a real GPU needs next for speed
//! (see BENCHMARKS.md).

mod context;
pub(crate) mod direct;
mod pass;
pub(crate) mod scene;
mod shaders;
pub(crate) mod trace;

use std::time::Instant;

use glam::{UVec2, Vec3, Vec4};
use rayon::prelude::*;

pub use context::{GpuContext, GpuError};
pub use direct::{DirectLightPass, FrameLights};
pub use scene::GpuScene;
pub use trace::RayQueries;

use super::band::{bands, resolve, shaded_value};
use super::sampling::{film_position, lamp_sample};
use super::{thread_pool, BackendError, RenderError};
use crate::accel::{Hit, Ray};
use crate::output::Image;
use crate::render::scatter::secondary_rays;
use crate::render::surface::ShadingPoint;
use crate::render::{area, FrameJob};
use crate::settings::Method;
use crate::stats::FrameStats;

/// Points whose lamp samples go to the GPU together (`--method area`): at
/// 64 lights, about a million segments.
const SHADE_CHUNK: usize = 16384;

pub struct GpuBackend {
    pool: rayon::ThreadPool,
    context: GpuContext,
    queries: RayQueries,
    direct: DirectLightPass,
    /// The last world rendered, as uploaded.
    scene: Option<GpuScene>,
}

impl GpuBackend {
    /// Finds the adapter and builds the pipelines; `threads` CPU workers
    /// make rays and shade.
    pub fn new(threads: Option<usize>) -> Result<GpuBackend, BackendError> {
        let context = GpuContext::new()?;
        let queries = RayQueries::new(&context);
        let direct = DirectLightPass::new(&context);
        Ok(GpuBackend {
            pool: thread_pool(threads)?,
            context,
            queries,
            direct,
            scene: None,
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
    pub fn passes_for(&mut self, world: &crate::accel::World) -> Result<GpuPasses<'_>, GpuError> {
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
        world: &crate::accel::World,
    ) -> Result<&'s GpuScene, GpuError> {
        match scene {
            Some(scene) => {
                scene.update(context, world)?;
                Ok(scene)
            }
            None => Ok(scene.insert(GpuScene::upload(context, world)?)),
        }
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
        let scene = Self::upload(&mut self.scene, &self.context, job.world)?;
        let lights = FrameLights::upload(&self.context, &job.frame.lights)?;
        stats.add_stage_time("upload", start.elapsed().as_secs_f64());
        let frame = Frame {
            job,
            context: &self.context,
            queries: &self.queries,
            direct: &self.direct,
            scene,
            lights,
        };
        self.pool.install(|| {
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
}

/// The backend's passes over one uploaded world.
pub struct GpuPasses<'a> {
    pub context: &'a GpuContext,
    pub queries: &'a RayQueries,
    pub direct: &'a DirectLightPass,
    pub scene: &'a GpuScene,
}

/// One frame's view of the backend.
struct Frame<'a> {
    job: &'a FrameJob<'a>,
    context: &'a GpuContext,
    queries: &'a RayQueries,
    direct: &'a DirectLightPass,
    scene: &'a GpuScene,
    lights: FrameLights,
}

/// Where a ray's hit goes: the sample it belongs to, its path weight, its
/// recursion depth.
#[derive(Clone, Copy)]
struct PathVertex {
    sample: u32,
    weight: Vec3,
    depth: u32,
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

        let start = Instant::now();
        let (rays, vertices) = self.camera_rays(rows.clone());
        let mut points = self.trace(&rays, &vertices)?;
        let primary = points.len();
        stats.rays.primary += rays.len() as u64;
        stats.add_stage_time("primary", start.elapsed().as_secs_f64());

        let start = Instant::now();
        let mut frontier = 0..points.len();
        for _ in 0..job.max_depth {
            let (rays, vertices): (Vec<Ray>, Vec<PathVertex>) = points[frontier.clone()]
                .iter()
                .flat_map(|point| {
                    secondary_rays(point).map(|secondary| {
                        let vertex = PathVertex {
                            sample: point.sample,
                            weight: secondary.weight,
                            depth: point.depth + 1,
                        };
                        (secondary.ray, vertex)
                    })
                })
                .unzip();
            stats.rays.secondary += rays.len() as u64;
            let next = self.trace(&rays, &vertices)?;
            if next.is_empty() {
                break;
            }
            frontier = points.len()..points.len() + next.len();
            points.extend(next);
        }
        stats.add_stage_time("secondary", start.elapsed().as_secs_f64());

        let start = Instant::now();
        let band_start = rows.start as u64 * job.width as u64 * job.spp as u64;
        let (direct, shadow_rays) = self.direct_light(&points, method, band_start)?;
        let shaded: Vec<Vec3> = (points.par_iter().zip(&direct))
            .map(|(point, &light)| shaded_value(point, light))
            .collect();
        stats.rays.shadow += shadow_rays;
        stats.shading_points += points.len() as u64;
        stats.add_stage_time("shade", start.elapsed().as_secs_f64());

        let start = Instant::now();
        let pixels = resolve(job, band_samples, &points, primary, &shaded);
        stats.add_stage_time("resolve", start.elapsed().as_secs_f64());
        Ok(pixels)
    }

    /// The camera rays of every sample in the band, in sample order, made
    /// exactly as the CPU backend makes them.
    fn camera_rays(&self, rows: std::ops::Range<u32>) -> (Vec<Ray>, Vec<PathVertex>) {
        let job = self.job;
        let (width, spp) = (job.width, job.spp);
        (rows.start..rows.end)
            .into_par_iter()
            .flat_map_iter(|y| {
                (0..width).flat_map(move |x| {
                    (0..spp).map(move |s| {
                        let film = film_position(UVec2::new(x, y), width, s, spp);
                        let ray = job.frame.camera.primary_ray(film, width, job.height);
                        let vertex = PathVertex {
                            sample: ((y - rows.start) * width + x) * spp + s,
                            weight: Vec3::ONE,
                            depth: 0,
                        };
                        (ray, vertex)
                    })
                })
            })
            .unzip()
    }

    /// Closest hits of `rays` on the GPU, made into shading points in ray
    /// order (misses dropped).
    fn trace(&self, rays: &[Ray], vertices: &[PathVertex]) -> Result<Vec<ShadingPoint>, GpuError> {
        let job = self.job;
        let hits: Vec<Option<Hit>> =
            self.queries
                .closest_hits(self.context, self.scene, job.world, rays)?;
        Ok((hits.par_iter().zip(rays).zip(vertices))
            .filter_map(|((hit, ray), vertex)| {
                let hit = hit.as_ref()?;
                Some(ShadingPoint::from_hit(
                    job.scene,
                    job.frame,
                    ray,
                    hit,
                    vertex.sample,
                    vertex.weight,
                    vertex.depth,
                ))
            })
            .collect())
    }

    /// Every point's direct light by `method`, and the shadow segments
    /// traced.
    fn direct_light(
        &self,
        points: &[ShadingPoint],
        method: Method,
        band_start: u64,
    ) -> Result<(Vec<Vec3>, u64), GpuError> {
        match method {
            Method::Whitted => self
                .direct
                .run(self.context, self.scene, &self.lights, points),
            Method::Area => self.area_light(points, band_start),
            Method::Lmm | Method::Lmm1 => Err(GpuError::LightMeshOnGpu),
        }
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
