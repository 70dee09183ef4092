//! The CPU backend: a frame as a wavefront of stages, each a parallel rayon
//! loop over independent items, run band by band so memory stays bounded
//! at any resolution and sample count.
//!
//! Stages (ARCHITECTURE.md, "A frame as stages"): `primary` (camera rays over
//! 16×16 tiles), `secondary` (the Whitted recursion, level by level), for
//! the light-mesh methods `demand` and `fill` (node masks), then `shade`
//! (formula (1), formula (2) or the spherical-lamp reference per shading
//! point) and `resolve` (samples to pixels).
//! Every stage collects in a fixed order and sums sequentially, so the image
//! is the same for any thread count.

use std::convert::Infallible;
use std::time::Instant;

use glam::{UVec2, Vec3};
use rayon::prelude::*;

use super::aov::{AovFrame, BandSamples};
use super::band::{bands, resolve, TILE};
use super::sampling::{film_position, lamp_sample};
use super::{thread_pool, BackendError, RenderError};
use crate::accel::Ray;
use crate::lightmesh::demand::Demand;
use crate::lightmesh::interpolate::{PointCounts, Scratch};
use crate::lightmesh::{LightMesh, LightMeshStats};
use crate::output::{Image, RenderedFrame};
use crate::render::environment::Environment;
use crate::render::light_terms::{PointTerms, TermLog};
use crate::render::omega::LightLanes;
use crate::render::scatter::secondary_rays;
use crate::render::shadow_split::{FrameMethod, LightRole};
use crate::render::surface::ShadingPoint;
use crate::render::{area, whitted, FrameJob};
use crate::stats::FrameStats;

/// Renders frames on a rayon pool of its own.
pub struct CpuBackend {
    pool: rayon::ThreadPool,
}

impl CpuBackend {
    /// A backend with `threads` workers, or one per core when None.
    pub fn new(threads: Option<usize>) -> Result<CpuBackend, BackendError> {
        Ok(CpuBackend {
            pool: thread_pool(threads)?,
        })
    }

    pub fn threads(&self) -> usize {
        self.pool.current_num_threads()
    }

    /// Renders one frame by `method`, with the AOV layers `job` asks for;
    /// stage times, ray and point counts go to `stats`. A light-mesh frame
    /// shades from `light_mesh` (an error without one); the others ignore
    /// it.
    pub fn render(
        &self,
        job: &FrameJob,
        method: FrameMethod,
        light_mesh: Option<&mut LightMesh>,
        stats: &mut FrameStats,
    ) -> Result<RenderedFrame, RenderError> {
        if AovFrame::wants_light_terms(job) {
            self.render_keeping::<TermLog>(job, method, light_mesh, stats)
        } else {
            self.render_keeping::<Vec3>(job, method, light_mesh, stats)
        }
    }

    /// [`CpuBackend::render`] with the shade stage keeping each point's
    /// light terms as `T` does (their sum, or each term for the `light`
    /// AOV).
    fn render_keeping<T: PointTerms>(
        &self,
        job: &FrameJob,
        method: FrameMethod,
        mut light_mesh: Option<&mut LightMesh>,
        stats: &mut FrameStats,
    ) -> Result<RenderedFrame, RenderError> {
        let mut counts = PointCounts::default();
        let mut lightmesh = LightMeshStats::default();
        let aovs = AovFrame::new(job);
        let frame = self.render_bands(job, aovs, stats, |rows, points, stats| {
            let (shaded, terms, band_counts) = shade_by_method::<T>(
                job,
                rows,
                points,
                method,
                light_mesh.as_deref_mut(),
                stats,
                &mut lightmesh,
            )?;
            counts += band_counts;
            Ok::<_, RenderError>((shaded, terms))
        })?;
        let lights = &job.frame.lights;
        if let (true, Some(mesh)) = (job.shadows.uses_light_mesh(method, lights), light_mesh) {
            super::count_class_mask_bits(job, mesh, stats);
            stats.lightmesh = Some(mesh.frame_stats(lightmesh, counts, stats.shading_points));
        }
        Ok(frame)
    }

    /// Computes the masks `job`'s frame will need (hits, demand and fill,
    /// band by band, and LMM1's enclosure flags where `probe_enclosure`)
    /// without shading it; the light-mesh stats go to `stats`.
    pub fn warm(
        &self,
        job: &FrameJob,
        mesh: &mut LightMesh,
        probe_enclosure: bool,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        self.pool
            .install(|| warm_light_mesh(job, mesh, probe_enclosure, stats))
    }

    /// Renders one frame with every light visible from every point
    /// (formula (1) with V = 1): the light each pixel would get without
    /// shadows, against which the study measures how shadowed a pixel is.
    pub fn render_unshadowed(&self, job: &FrameJob, stats: &mut FrameStats) -> Image {
        let lanes = LightLanes::new(&job.frame.lights);
        let unshadowed = self.render_bands(job, None, stats, |_, points, stats| {
            let shade = |_: &mut (), _, point: &ShadingPoint, sum: &mut Vec3| {
                *sum = whitted::unshadowed_light(point, &lanes);
                PointCounts::default()
            };
            let (shaded, sums, _) = shade_stage(points, &job.environment, stats, || (), shade);
            Ok::<_, Infallible>((shaded, sums))
        });
        match unshadowed {
            Ok(frame) => frame.image,
            Err(never) => match never {},
        }
    }

    /// The frame band by band: hits (stages 1–2), then `shade` gives each
    /// shading point its value (and the terms it kept, one `T` per
    /// [`SHADE_CHUNK`] points), then samples are resolved to pixels and,
    /// where the job asks for them, to the `aovs` layers.
    fn render_bands<E: Send, T: PointTerms>(
        &self,
        job: &FrameJob,
        mut aovs: Option<AovFrame>,
        stats: &mut FrameStats,
        mut shade: impl FnMut(
                std::ops::Range<u32>,
                &[ShadingPoint],
                &mut FrameStats,
            ) -> Result<(Vec<Vec3>, Vec<T>), E>
            + Send,
    ) -> Result<RenderedFrame, E> {
        self.pool.install(|| {
            let mut pixels = Vec::with_capacity((job.width * job.height) as usize);
            for rows in bands(job) {
                let band_samples = ((rows.end - rows.start) * job.width * job.spp) as usize;
                let (points, primary_count) = hits(job, rows.clone(), stats);
                let (shaded, terms) = shade(rows.clone(), &points, stats)?;
                stats.shading_points += points.len() as u64;
                let start = Instant::now();
                pixels.extend(resolve(job, band_samples, &points, primary_count, &shaded));
                if let Some(aovs) = &mut aovs {
                    let terms = (&terms[..], SHADE_CHUNK);
                    let lights = aovs.light_layers();
                    let band =
                        BandSamples::from_points(job, rows, &points, primary_count, terms, lights);
                    aovs.add_band(job, &band);
                }
                stats.add_stage_time("resolve", start.elapsed().as_secs_f64());
            }
            let image = Image {
                width: job.width,
                height: job.height,
                pixels,
            };
            Ok(RenderedFrame {
                image,
                aovs: aovs.map_or_else(Vec::new, AovFrame::into_layers),
            })
        })
    }
}

/// The stages of a light-mesh frame that fill masks (hits, demand, fill,
/// and LMM1's enclosure where `probe_enclosure`), band by band on the
/// current rayon pool, without shading: what a farm's first task runs to
/// fill the disk cache (`lmanim warm`), which keeps the static bits and
/// the enclosure flags.
pub(super) fn warm_light_mesh(
    job: &FrameJob,
    mesh: &mut LightMesh,
    probe_enclosure: bool,
    stats: &mut FrameStats,
) -> Result<(), RenderError> {
    let lanes = LightLanes::new(&job.frame.lights);
    let mut work = LightMeshStats::default();
    for rows in bands(job) {
        let (points, _) = hits(job, rows, stats);
        let start = Instant::now();
        work.points_demanded += points.len() as u64;
        let demand = mesh.demand(&points, &lanes)?;
        stats.add_stage_time("demand", start.elapsed().as_secs_f64());
        let start = Instant::now();
        mesh.fill(&demand, &job.frame.lights, job.world, &mut work)?;
        stats.add_stage_time("fill", start.elapsed().as_secs_f64());
        if probe_enclosure {
            settle_enclosure(job, mesh, &demand, stats, &mut work);
        }
        stats.shading_points += points.len() as u64;
    }
    stats.rays.shadow += work.fill_segments;
    stats.lightmesh = Some(mesh.frame_stats(work, PointCounts::default(), stats.shading_points));
    Ok(())
}

/// LMM1's enclosure stage after the fill: the flags of the nodes `demand`
/// names that need one, probed on the CPU.
fn settle_enclosure(
    job: &FrameJob,
    mesh: &mut LightMesh,
    demand: &Demand,
    stats: &mut FrameStats,
    work: &mut LightMeshStats,
) {
    let start = Instant::now();
    let enclosure = mesh.settle_enclosure(demand, job.world);
    work.nodes_probed += enclosure.probed;
    work.enclosure_reused += enclosure.reused;
    stats.add_stage_time("enclosure", start.elapsed().as_secs_f64());
}

/// Stages 1–2 for one band of rows: the camera rays' hits, then the
/// Whitted recursion's, level by level; also how many hits are primary.
fn hits(
    job: &FrameJob,
    rows: std::ops::Range<u32>,
    stats: &mut FrameStats,
) -> (Vec<ShadingPoint>, usize) {
    let band_samples = ((rows.end - rows.start) * job.width * job.spp) as usize;
    let start = Instant::now();
    let primary = primary_hits(job, rows);
    stats.rays.primary += band_samples as u64;
    stats.add_stage_time("primary", start.elapsed().as_secs_f64());

    let start = Instant::now();
    let primary_count = primary.len();
    let mut points = primary;
    let mut frontier = 0..points.len();
    for _ in 0..job.max_depth {
        let (next, rays) = secondary_hits(job, &points[frontier.clone()]);
        stats.rays.secondary += rays;
        if next.is_empty() {
            break;
        }
        frontier = points.len()..points.len() + next.len();
        points.extend(next);
    }
    stats.add_stage_time("secondary", start.elapsed().as_secs_f64());
    (points, primary_count)
}

/// The shading stages of one band by `method` and the plan's shadow
/// classes (for the lights shaded from the light mesh, demand and fill
/// first): each point's value, the light terms kept as `T` keeps them,
/// and what shading cost.
fn shade_by_method<T: PointTerms>(
    job: &FrameJob,
    rows: std::ops::Range<u32>,
    points: &[ShadingPoint],
    method: FrameMethod,
    light_mesh: Option<&mut LightMesh>,
    stats: &mut FrameStats,
    lightmesh: &mut LightMeshStats,
) -> Result<(Vec<Vec3>, Vec<T>, PointCounts), RenderError> {
    let lights = &job.frame.lights;
    let shadows = job.shadows;
    let segments_before = lightmesh.fill_segments;
    let formula_one = || {
        shadows.lanes(method, lights, |role| {
            matches!(role, LightRole::FormulaOne { .. })
        })
    };
    let (shaded, terms, band_counts) = match (method, light_mesh) {
        (FrameMethod::FormulaOne, _) => formula_one_stage(job, points, &formula_one(), stats),
        (FrameMethod::Lamps, _) => {
            // Lamp samples are seeded by the sample's index in the whole
            // image; `point.sample` counts from the band's first row.
            let band_start = rows.start as u64 * job.width as u64 * job.spp as u64;
            shade_stage(
                points,
                &job.environment,
                stats,
                || (),
                |_, _, point, terms: &mut T| {
                    let sample = band_start + point.sample as u64;
                    let lamp = |light| lamp_sample(sample, job.spp, light, point.depth);
                    let rays = area::direct_light(point, lights, job.world, lamp, shadows, terms);
                    PointCounts::shadow_rays(rays)
                },
            )
        }
        (FrameMethod::LightMesh { .. }, Some(mesh)) => {
            let formula_one = shadows.uses_formula_one(method, lights).then(formula_one);
            let mesh_lanes = shadows.lanes(method, lights, |role| role == LightRole::LightMesh);
            let mesh_stage = MeshStage {
                lanes: &mesh_lanes,
                point_to_node_tests: method.tests_point_to_node(),
                formula_one_first: formula_one.as_ref(),
            };
            mesh_stage.shade(job, points, mesh, stats, lightmesh)?
        }
        (FrameMethod::LightMesh { .. }, None) => return Err(RenderError::NoLightMesh),
    };
    stats.shadow_classes.add_rays(band_counts.shadow_rays);
    // Every occlusion segment is a shadow ray: formula (1)'s, the fill's
    // node-to-light ones, LMM's point-to-node tests, and the rays that
    // found a penumbra's blocker.
    stats.rays.shadow += band_counts.shadow_rays.total()
        + band_counts.p2n_tests
        + band_counts.blocker_rays
        + lightmesh.fill_segments
        - segments_before;
    Ok((shaded, terms, band_counts))
}

/// Formula (1) at every point, for the lights `lanes` hold powered.
fn formula_one_stage<T: PointTerms>(
    job: &FrameJob,
    points: &[ShadingPoint],
    lanes: &LightLanes,
    stats: &mut FrameStats,
) -> (Vec<Vec3>, Vec<T>, PointCounts) {
    shade_stage(
        points,
        &job.environment,
        stats,
        || (),
        |_, _, point, terms: &mut T| {
            let rays = whitted::direct_light_terms(point, lanes, job.world, job.shadows, terms);
            PointCounts::shadow_rays(rays)
        },
    )
}

/// The light-mesh stages (demand, fill, LMM1's enclosure, formula (2))
/// for the lights `lanes` hold powered; with `formula_one_first`, each
/// point first gets formula (1)'s terms of the lights those lanes hold
/// (the hard and unshadowed lights of [`MeshLights::Soft`]), so a
/// point's terms are summed in one fixed order.
///
/// [`MeshLights::Soft`]: crate::render::shadow_split::MeshLights::Soft
struct MeshStage<'l> {
    lanes: &'l LightLanes,
    point_to_node_tests: bool,
    formula_one_first: Option<&'l LightLanes>,
}

impl MeshStage<'_> {
    fn shade<T: PointTerms>(
        &self,
        job: &FrameJob,
        points: &[ShadingPoint],
        mesh: &mut LightMesh,
        stats: &mut FrameStats,
        lightmesh: &mut LightMeshStats,
    ) -> Result<(Vec<Vec3>, Vec<T>, PointCounts), RenderError> {
        let lights = &job.frame.lights;
        let start = Instant::now();
        lightmesh.points_demanded += points.len() as u64;
        let demand = mesh.demand(points, self.lanes)?;
        stats.add_stage_time("demand", start.elapsed().as_secs_f64());

        let start = Instant::now();
        mesh.fill(&demand, lights, job.world, lightmesh)?;
        stats.add_stage_time("fill", start.elapsed().as_secs_f64());

        if !self.point_to_node_tests {
            settle_enclosure(job, mesh, &demand, stats, lightmesh);
        }

        let mesh = &*mesh;
        let scratch = || Scratch::new(mesh, lights);
        Ok(shade_stage(
            points,
            &job.environment,
            stats,
            scratch,
            |scratch, index, point, terms: &mut T| {
                let mut counts = PointCounts::default();
                if let Some(lanes) = self.formula_one_first {
                    counts.shadow_rays =
                        whitted::direct_light_terms(point, lanes, job.world, job.shadows, terms);
                }
                counts += mesh.shade(
                    point,
                    demand.of_point(index),
                    self.lanes,
                    job.world,
                    self.point_to_node_tests,
                    job.shadows,
                    scratch,
                    terms,
                );
                counts
            },
        ))
    }
}

/// Shading points per work item of the shade stage, and per `T` of the
/// terms it keeps.
const SHADE_CHUNK: usize = 1024;

/// The last stage before resolve: every point's emission (and the
/// `environment`'s ambient sky) plus its direct light, which `direct`
/// (formula (1), (2) or the lamp estimate) hands light by light to a `T`,
/// weighted by its path throughput; the `T` of each [`SHADE_CHUNK`]
/// points, in order; and what shading them cost. `init` makes per-thread
/// scratch space. Counts are integers, so summing them in any order gives
/// the same totals.
fn shade_stage<S, T: PointTerms>(
    points: &[ShadingPoint],
    environment: &Environment,
    stats: &mut FrameStats,
    init: impl Fn() -> S + Send + Sync,
    direct: impl Fn(&mut S, usize, &ShadingPoint, &mut T) -> PointCounts + Send + Sync,
) -> (Vec<Vec3>, Vec<T>, PointCounts) {
    let start = Instant::now();
    let mut shaded = vec![Vec3::ZERO; points.len()];
    let chunks: Vec<(T, PointCounts)> = shaded
        .par_chunks_mut(SHADE_CHUNK)
        .zip(points.par_chunks(SHADE_CHUNK))
        .enumerate()
        .map_init(init, |scratch, (chunk, (out, points))| {
            let mut counts = PointCounts::default();
            let mut terms = T::default();
            for (offset, (value, point)) in out.iter_mut().zip(points).enumerate() {
                terms.begin_point();
                counts += direct(scratch, chunk * SHADE_CHUNK + offset, point, &mut terms);
                *value = environment.shaded_value(point, terms.sum());
            }
            (terms, counts)
        })
        .collect();
    let mut counts = PointCounts::default();
    let terms = (chunks.into_iter())
        .map(|(terms, chunk_counts)| {
            counts += chunk_counts;
            terms
        })
        .collect();
    stats.add_stage_time("shade", start.elapsed().as_secs_f64());
    (shaded, terms, counts)
}

/// Stage 1: camera rays of every sample in the band, tile by tile.
fn primary_hits(job: &FrameJob, rows: std::ops::Range<u32>) -> Vec<ShadingPoint> {
    let tiles: Vec<UVec2> = (rows.start..rows.end)
        .step_by(TILE as usize)
        .flat_map(|y| {
            (0..job.width)
                .step_by(TILE as usize)
                .map(move |x| UVec2::new(x, y))
        })
        .collect();
    let rays = job.frame.camera.film(job.width, job.height);
    let per_tile: Vec<Vec<ShadingPoint>> = tiles
        .par_iter()
        .map(|&corner| {
            let mut points = Vec::new();
            for y in corner.y..(corner.y + TILE).min(rows.end) {
                for x in corner.x..(corner.x + TILE).min(job.width) {
                    for s in 0..job.spp {
                        let film = film_position(UVec2::new(x, y), job.width, s, job.spp);
                        let ray = rays.through(film);
                        let sample = ((y - rows.start) * job.width + x) * job.spp + s;
                        points.extend(trace(job, &ray, sample, Vec3::ONE, 0));
                    }
                }
            }
            points
        })
        .collect();
    per_tile.into_iter().flatten().collect()
}

/// Stage 2, one level: rays that mirrors and glass spawn from `points`.
fn secondary_hits(job: &FrameJob, points: &[ShadingPoint]) -> (Vec<ShadingPoint>, u64) {
    let spawned: Vec<(Vec<ShadingPoint>, u64)> = points
        .par_iter()
        .map(|point| {
            let mut hits = Vec::new();
            let mut rays = 0;
            for secondary in secondary_rays(point) {
                rays += 1;
                hits.extend(trace(
                    job,
                    &secondary.ray,
                    point.sample,
                    secondary.weight,
                    point.depth + 1,
                ));
            }
            (hits, rays)
        })
        .collect();
    let rays = spawned.iter().map(|(_, rays)| rays).sum();
    (
        spawned.into_iter().flat_map(|(hits, _)| hits).collect(),
        rays,
    )
}

fn trace(job: &FrameJob, ray: &Ray, sample: u32, weight: Vec3, depth: u32) -> Option<ShadingPoint> {
    let hit = job.world.closest_hit(ray)?;
    Some(ShadingPoint::from_hit(
        job.scene, job.frame, ray, &hit, sample, weight, depth,
    ))
}
