//! One frame on the GPU, band by band, each band one [`Recording`]. Each
//! level of the band's camera paths is recorded and submitted without a
//! wait: level 0's rays made by the camera pass, then closest hits,
//! shading points, their direct light (formula (1) on the GPU for
//! `whitted`; lamp samples made on the CPU for `area`, their segments
//! tested on the GPU; formula (2) for the light mesh), the film's
//! accumulation, and the next level's rays with their compaction, whose
//! length stays on the GPU ([`super::scatter`]). The band waits once at
//! its end, for its resolved pixels, its counters (the secondary rays
//! among them), formula (2)'s counters and, with `--aovs`, the AOV
//! film's samples ([`AovFilm`]). The waits within a level are where the
//! CPU takes part: `area`'s lamp samples and the light mesh's demand
//! ([`LightMeshShading::prepare`]).

use std::ops::Range;
use std::time::Instant;

use glam::{Vec3, Vec4};
use rayon::prelude::*;

use super::aov_film::AovFilm;
use super::camera::CameraRecord;
use super::context::{GpuContext, GpuError};
use super::direct::{DirectLight, FrameLights};
use super::film::Film;
use super::layered::PointLayers;
use super::light_mesh::LightMeshShading;
use super::pass::{answer_buffer, BATCH};
use super::pipelines::Pipelines;
use super::recording::{Downloads, Recording};
use super::scatter::batches;
use super::scene::{storage, GpuScene};
use super::surface::{FrameSurfaces, LevelBuffers, PathRay, SceneSurfaces, SurfacePoint};
use crate::accel::Ray;
use crate::backend::aov::{AovFrame, BandSamples};
use crate::backend::sampling::lamp_sample;
use crate::backend::RenderError;
use crate::render::surface::ShadingPoint;
use crate::render::{area, FrameJob};
use crate::stats::{ClassRays, FrameStats};

/// Points whose lamp samples go to the GPU together (`--method area`): at
/// 64 lights, about a million segments.
const SHADE_CHUNK: usize = 16384;

/// How a level's points get their direct light.
pub enum DirectMethod<'m> {
    /// Formula (1), on the GPU.
    Whitted,
    /// Lamp samples made on the CPU, their segments tested on the GPU.
    Area,
    /// Formula (2), on the GPU, from masks the CPU keeps valid.
    LightMesh(Box<LightMeshShading<'m>>),
}

/// One frame's view of the backend, with the frame's uploads.
pub struct Frame<'a> {
    pub job: &'a FrameJob<'a>,
    pub context: &'a GpuContext,
    pub pipelines: &'a Pipelines,
    pub scene: &'a GpuScene,
    pub scene_surfaces: &'a SceneSurfaces,
    pub frame_surfaces: &'a FrameSurfaces,
    pub lights: FrameLights,
    /// The most secondary rays a point spawns, over the frame's materials
    /// and the default one (`most_secondary_rays`): it bounds each next
    /// level's length.
    pub rays_per_point: usize,
}

impl Frame<'_> {
    /// The pixels of `rows`, and their samples for the layers of `aovs`
    /// where the frame has AOVs; ray, point and segment counts and stage
    /// times go to `stats`. The band is one recording: each level's passes
    /// are recorded and submitted without waiting, and the band waits
    /// once, at its end, for everything it gives back (a level waits
    /// earlier only where the CPU takes part in it: `area`'s lamp
    /// samples, the light mesh's demand, a next level's length that may
    /// be more than a batch).
    pub fn render_band(
        &self,
        rows: Range<u32>,
        method: &mut DirectMethod,
        aovs: Option<&AovFrame>,
        stats: &mut FrameStats,
    ) -> Result<(Vec<Vec4>, Option<BandSamples>), RenderError> {
        let job = self.job;
        let context = self.context;
        let pixels = ((rows.end - rows.start) * job.width) as usize;
        let band_samples = pixels * job.spp as usize;
        let band_start = rows.start as u64 * job.width as u64 * job.spp as u64;
        context.checked("rendering a band", || {
            let film = Film::new(context, pixels, job.spp as usize, &job.environment)?;
            let aov_film = match aovs {
                Some(aovs) => Some(AovFilm::new(context, band_samples, aovs.light_layers())?),
                None => None,
            };
            let films = (&film, aov_film.as_ref());
            let mut recording = Recording::new(context);

            let start = Instant::now();
            let mut level = Vec::new();
            for batch in batches(band_samples) {
                let camera = CameraRecord::new(job, rows.start, batch.start as u32);
                let camera_rays = (self.pipelines.camera).rays(
                    context,
                    recording.encoder(),
                    self.scene,
                    &camera,
                    batch.len(),
                )?;
                self.shade(
                    &mut recording,
                    &camera_rays,
                    films,
                    method,
                    band_start,
                    stats,
                )?;
                if let Some(aov_film) = &aov_film {
                    let passes = &self.pipelines.aovs;
                    let encoder = recording.encoder();
                    aov_film.record_first_hits(passes, context, encoder, self.scene, &camera_rays);
                }
                level.extend(self.continue_paths(&mut recording, &camera_rays, &film, 0)?);
                recording.submit();
            }
            stats.rays.primary += band_samples as u64;
            stats.add_stage_time("primary", start.elapsed().as_secs_f64());

            let start = Instant::now();
            for depth in 1..=job.max_depth {
                let mut next = Vec::new();
                for paths in &level {
                    self.shade(&mut recording, paths, films, method, band_start, stats)?;
                    next.extend(self.continue_paths(&mut recording, paths, &film, depth)?);
                    recording.submit();
                }
                level = next;
            }
            stats.add_stage_time("secondary", start.elapsed().as_secs_f64());

            let start = Instant::now();
            let developed = self.develop(recording, films, method, stats)?;
            stats.add_stage_time("resolve", start.elapsed().as_secs_f64());
            Ok(developed)
        })
    }

    /// Records the band's resolve and waits for it, the band's one wait:
    /// its pixels, the film's counters (the secondary rays among them,
    /// which go to `stats` with the shading points and shadow rays), the
    /// AOV samples and formula (2)'s counters come back in one map.
    fn develop(
        &self,
        mut recording: Recording,
        (film, aov_film): (&Film, Option<&AovFilm>),
        method: &mut DirectMethod,
        stats: &mut FrameStats,
    ) -> Result<(Vec<Vec4>, Option<BandSamples>), GpuError> {
        let mut downloads = Downloads::default();
        let film_parts = film.develop(
            &self.pipelines.film,
            self.context,
            recording.encoder(),
            self.scene,
            &mut downloads,
        );
        let aov_parts = aov_film.map(|aov_film| aov_film.develop(&mut downloads));
        let counts = match &*method {
            DirectMethod::LightMesh(light_mesh) => Some(light_mesh.download(&mut downloads)),
            DirectMethod::Whitted | DirectMethod::Area => None,
        };
        let why = "the band's pixels and counters (and AOV samples, formula (2)'s counters)";
        let downloaded = recording.wait(why, downloads)?;
        let developed = film_parts.developed(&downloaded);
        if let (DirectMethod::LightMesh(light_mesh), Some(counts)) = (method, counts) {
            light_mesh.downloaded(&downloaded, counts);
        }
        stats.rays.secondary += developed.secondary_rays;
        stats.rays.shadow += developed.other_rays + developed.class_rays.total();
        stats.shadow_classes.add_rays(developed.class_rays);
        stats.shading_points += developed.shading_points;
        let samples = aov_parts.map(|parts| parts.samples(&downloaded));
        Ok((developed.pixels, samples))
    }

    /// Records a level's closest hits, shading points, direct light and
    /// accumulation into the film (and the AOV film's light layers, where
    /// it has them); for `area` and the light mesh, waits halfway to
    /// bring points to the CPU (lamp samples; demand and fill for the
    /// points the mask pool does not serve).
    fn shade(
        &self,
        recording: &mut Recording,
        level: &LevelBuffers,
        (film, aov_film): (&Film, Option<&AovFilm>),
        method: &mut DirectMethod,
        band_start: u64,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        let (context, pipelines, scene) = (self.context, self.pipelines, self.scene);
        self.record_points(recording.encoder(), level);
        let mut layers = match (aov_film, &method) {
            (Some(aov_film), DirectMethod::Whitted | DirectMethod::LightMesh(_)) => {
                aov_film.point_layers(context, level.count)?
            }
            _ => None,
        };
        let direct = match method {
            DirectMethod::Whitted => {
                let direct = answer_buffer::<DirectLight>(context, "direct light", level.count)?;
                (pipelines.direct).record(
                    context,
                    recording.encoder(),
                    scene,
                    &self.lights,
                    level,
                    &direct,
                    layers.as_ref(),
                );
                direct
            }
            DirectMethod::Area => {
                let points = level_points(recording, level)?;
                let layer_of = aov_film.and_then(AovFilm::layer_of);
                let (direct, sums) = self.area_light(&points, band_start, layer_of)?;
                if let (Some(sums), Some((_, count))) = (sums, layer_of) {
                    layers = Some(PointLayers::upload(context, &sums, count)?);
                }
                storage(context, "direct light", &direct)?
            }
            DirectMethod::LightMesh(light_mesh) => {
                let prepared = light_mesh.prepare(
                    &pipelines.light_mesh,
                    (&pipelines.fill, &pipelines.probes),
                    context,
                    self.job,
                    scene,
                    &self.lights,
                    level,
                    recording,
                    stats,
                )?;
                let direct = answer_buffer::<DirectLight>(context, "direct light", level.count)?;
                light_mesh.record(
                    &pipelines.light_mesh,
                    context,
                    recording.encoder(),
                    scene,
                    &self.lights,
                    level,
                    &prepared,
                    (&direct, layers.as_ref()),
                );
                direct
            }
        };
        let encoder = recording.encoder();
        film.accumulate(&pipelines.film, context, encoder, scene, level, &direct);
        if let (Some(aov_film), Some(layers)) = (aov_film, &layers) {
            let passes = &pipelines.aovs;
            aov_film.accumulate(passes, context, encoder, scene, film, level, layers);
        }
        Ok(())
    }

    /// Records the closest hits of `level`'s rays and the shading points
    /// made from them.
    fn record_points(&self, encoder: &mut wgpu::CommandEncoder, level: &LevelBuffers) {
        let (context, pipelines, scene) = (self.context, self.pipelines, self.scene);
        (pipelines.queries).record_closest(context, encoder, scene, level);
        let surfaces = (self.scene_surfaces, self.frame_surfaces);
        (pipelines.surfaces).record(context, encoder, scene, surfaces.0, surfaces.1, level);
    }

    /// Records the next level of the recursion from `level` at `depth`
    /// (none at the deepest, or where the frame's materials spawn no
    /// rays), its length added to `film`'s counters.
    fn continue_paths(
        &self,
        recording: &mut Recording,
        level: &LevelBuffers,
        film: &Film,
        depth: u32,
    ) -> Result<Vec<LevelBuffers>, GpuError> {
        if depth >= self.job.max_depth {
            return Ok(Vec::new());
        }
        (self.pipelines.scatter).next_level(
            self.context,
            recording,
            self.scene,
            level,
            self.rays_per_point,
            film.counters(),
        )
    }

    /// The shading points of `rays`' closest hits (None for a miss).
    pub fn shading_points(&self, rays: &[Ray]) -> Result<Vec<Option<ShadingPoint>>, GpuError> {
        let context = self.context;
        let mut points = Vec::with_capacity(rays.len());
        for batch in rays.chunks(BATCH) {
            let paths: Vec<PathRay> = batch.iter().map(PathRay::from).collect();
            let records: Vec<SurfacePoint> = context.checked("making shading points", || {
                let level = LevelBuffers::new(context, &paths)?;
                let mut recording = Recording::new(context);
                self.record_points(recording.encoder(), &level);
                recording.read_back("the rays' shading points", &level.points, level.count)
            })?;
            points.extend(records.iter().map(SurfacePoint::shading_point));
        }
        Ok(points)
    }

    /// `--method area` at a level's points (`records`, misses included):
    /// each point's lamp samples are made on the CPU in light order, their
    /// segments tested on the GPU, and the visible samples summed in that
    /// order, so a point gets the CPU backend's bits wherever the segments
    /// get its answers. With `layer_of` (which of `count` light layers
    /// each light adds to), also each point's visible samples summed per
    /// layer in that order, as formula (1) and (2) sum their terms on the
    /// GPU (`light_layers.wgsl`).
    fn area_light(
        &self,
        records: &[SurfacePoint],
        band_start: u64,
        layer_of: Option<(&[usize], usize)>,
    ) -> Result<(Vec<DirectLight>, Option<LayerSums>), GpuError> {
        let job = self.job;
        let mut direct = Vec::with_capacity(records.len());
        let mut layers = layer_of.map(|(_, count)| Vec::with_capacity(records.len() * count));
        for chunk in records.chunks(SHADE_CHUNK) {
            let samples: Vec<LampSamples> = chunk
                .par_iter()
                .map(|record| {
                    let mut samples = LampSamples::default();
                    if let Some(point) = record.shading_point() {
                        let sample = band_start + point.sample as u64;
                        let lamp = |light| lamp_sample(sample, job.spp, light, point.depth);
                        area::light_samples(&point, &job.frame.lights, lamp, |light, s| {
                            samples.lights.push(light);
                            samples.values.push(s.value);
                            samples.rays.push(s.shadow_ray);
                        });
                    }
                    samples
                })
                .collect();
            let rays: Vec<Ray> = samples
                .iter()
                .flat_map(|s| s.rays.iter().copied())
                .collect();
            let occluded = (self.pipelines.queries).occluded(self.context, self.scene, &rays)?;
            let mut answers = occluded.into_iter();
            for point_samples in &samples {
                let mut radiance = Vec3::ZERO;
                let mut sums = layer_of.map(|(_, count)| vec![Vec3::ZERO; count]);
                let taken = (point_samples.lights.iter()).zip(&point_samples.values);
                for ((&light, value), blocked) in taken.zip(answers.by_ref()) {
                    if !blocked {
                        radiance += *value;
                        if let (Some(sums), Some((layer_of, _))) = (&mut sums, layer_of) {
                            sums[layer_of[light]] += *value;
                        }
                    }
                }
                let mut rays = ClassRays::default();
                for &light in &point_samples.lights {
                    rays.add(job.shadows.class(light, &job.frame.lights));
                }
                direct.push(DirectLight::new(radiance, rays));
                if let (Some(layers), Some(sums)) = (&mut layers, sums) {
                    layers.extend(sums.into_iter().map(|sum| sum.extend(0.0).to_array()));
                }
            }
        }
        Ok((direct, layers))
    }
}

/// `level`'s shading points, as many as it holds (a level counted on the
/// GPU comes back with its length), for `--method area`'s lamp samples.
fn level_points(
    recording: &mut Recording,
    level: &LevelBuffers,
) -> Result<Vec<SurfacePoint>, GpuError> {
    let mut downloads = Downloads::default();
    let length = (level.length.as_ref()).map(|length| downloads.add::<u32>(length, 1));
    let points = downloads.add::<SurfacePoint>(&level.points, level.count);
    let why = "the level's points, for the CPU's lamp samples";
    let downloaded = recording.wait(why, downloads)?;
    let mut points = downloaded.take(points);
    if let Some(length) = length {
        let count = downloaded
            .take(length)
            .first()
            .map_or(0, |&count| count as usize);
        points.truncate(count);
    }
    Ok(points)
}

/// Per point, its visible terms summed per light layer, as
/// [`PointLayers`] holds them (the fourth component unused).
type LayerSums = Vec<[f32; 4]>;

/// One point's lamp samples in light order, visibility aside.
#[derive(Default)]
struct LampSamples {
    lights: Vec<usize>,
    values: Vec<Vec3>,
    rays: Vec<Ray>,
}
