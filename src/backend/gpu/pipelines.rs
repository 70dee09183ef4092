//! Every pass of the backend, and which of them a run needs: those are
//! compiled before its first frame, side by side, with the progress
//! reported ([`Pipelines::prepare`]); any other compiles where it is
//! first recorded. A Whitted run never waits for the light mesh's
//! pipelines, nor a run without AOVs for the AOV film's.

use std::cmp::Reverse;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::mpsc;

use super::aov_film::AovPasses;
use super::camera::CameraPass;
use super::context::GpuContext;
use super::direct::DirectLightPass;
use super::enclosure::{ProbePass, ProbeSite};
use super::fill::FillPass;
use super::film::FilmPasses;
use super::light_mesh::LightMeshPasses;
use super::pass::WorldPass;
use super::scatter::ScatterPasses;
use super::surface::SurfacePass;
use super::trace::RayQueries;
use crate::render::shadow_split::FrameMethod;
use crate::settings::Aov;

pub struct Pipelines {
    pub camera: CameraPass,
    pub queries: RayQueries,
    pub surfaces: SurfacePass,
    pub direct: DirectLightPass,
    pub fill: FillPass,
    pub probes: ProbePass,
    pub light_mesh: LightMeshPasses,
    pub scatter: ScatterPasses,
    pub film: FilmPasses,
    pub aovs: AovPasses,
}

impl Pipelines {
    /// The passes with their bind group layouts; no pipeline is compiled.
    pub fn new(context: &GpuContext) -> Pipelines {
        Pipelines {
            camera: CameraPass::new(context),
            queries: RayQueries::new(context),
            surfaces: SurfacePass::new(context),
            direct: DirectLightPass::new(context),
            fill: FillPass::new(context),
            probes: ProbePass::new(context),
            light_mesh: LightMeshPasses::new(context),
            scatter: ScatterPasses::new(context),
            film: FilmPasses::new(context),
            aovs: AovPasses::new(context),
        }
    }

    /// The passes frames by `method` record with `aovs`, LMM1's enclosure
    /// probes running at `probe_site`.
    pub fn needed(
        &self,
        context: &GpuContext,
        (method, probe_site): (FrameMethod, ProbeSite),
        aovs: &[Aov],
    ) -> Vec<&WorldPass> {
        let light_layers = aovs.contains(&Aov::Light);
        let scatter = &self.scatter;
        let mut passes = vec![
            &self.camera.pass,
            &self.queries.closest,
            &self.surfaces.pass,
            &scatter.scatter,
            &scatter.scan_blocks,
            &scatter.scan_sums,
            &scatter.compact,
            &self.film.accumulate,
            &self.film.resolve,
        ];
        // Formula (2)'s shader also adds the terms of the lights formula
        // (1) shades; the lamps' samples are the CPU's.
        let direct = match method {
            FrameMethod::FormulaOne => Some(&self.direct.pass),
            FrameMethod::LightMesh { .. } => Some(&self.light_mesh.shade),
            FrameMethod::Lamps => None,
        };
        if let Some(direct) = direct {
            passes.push(direct.plain());
            if light_layers {
                passes.push(direct.layered(context));
            }
        }
        match method {
            FrameMethod::LightMesh { .. } => {
                let mesh = &self.light_mesh;
                passes.extend([&mesh.coverage, &mesh.gather, &mesh.patch, &self.fill.pass]);
                if !method.tests_point_to_node() {
                    passes.extend([&mesh.summarise_tiles, &mesh.summarise_around]);
                }
                if !method.tests_point_to_node() && probe_site == ProbeSite::Gpu {
                    passes.push(&self.probes.pass);
                }
            }
            FrameMethod::Lamps => passes.push(&self.queries.any),
            FrameMethod::FormulaOne => {}
        }
        if !aovs.is_empty() {
            passes.push(&self.aovs.first_hits);
        }
        if light_layers {
            passes.push(&self.aovs.layers);
        }
        passes
    }

    /// Compiles `passes` on up to `threads` threads (drivers that compile
    /// at creation do so on the calling thread), calling `progress` with
    /// (compiled, of) as each is done; the largest go first, so that the
    /// last to finish is not one started late.
    pub fn prepare(
        context: &GpuContext,
        passes: &[&WorldPass],
        threads: usize,
        mut progress: impl FnMut(usize, usize),
    ) {
        let mut passes = passes.to_vec();
        passes.sort_by_cached_key(|pass| Reverse(pass.source_bytes(context)));
        let passes = &passes;
        let next = AtomicUsize::new(0);
        let (done, compiled) = mpsc::channel();
        progress(0, passes.len());
        std::thread::scope(|scope| {
            for _ in 0..threads.clamp(1, passes.len().max(1)) {
                let done = done.clone();
                let next = &next;
                scope.spawn(move || {
                    while let Some(pass) = passes.get(next.fetch_add(1, Ordering::Relaxed)) {
                        pass.prepare(context);
                        let _ = done.send(());
                    }
                });
            }
            drop(done);
            for count in 1..=passes.len() {
                if compiled.recv().is_err() {
                    break;
                }
                progress(count, passes.len());
            }
        });
    }
}
