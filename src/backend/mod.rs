//! Backends run a frame's stages on some hardware, behind one seam:
//! [`Backend`]. The CPU backend (rayon) is the reference; the GPU backend
//! (wgpu compute) runs hits, shading points, formula (1), the lamps'
//! segments, the light mesh's fill and formula (2) as compute passes that
//! round as the CPU does, and keeps on the CPU what it cannot do as well
//! (lamp sampling, the light mesh's demand and bookkeeping), so its frames
//! match the CPU's. Both run every method. The core (scene, accel,
//! render) never knows which one runs it.

mod aov;
mod band;
pub mod cpu;
pub mod gpu;
mod sampling;

use std::path::Path;

pub use cpu::CpuBackend;
pub use gpu::{GpuBackend, GpuError};

use crate::lightmesh::segments::Shafts;
use crate::lightmesh::{LightMesh, LightMeshError};
use crate::output::RenderedFrame;
use crate::plan::Shadows;
use crate::render::shadow_split::FrameMethod;
use crate::render::FrameJob;
use crate::settings::{Aov, BackendKind};
use crate::stats::FrameStats;

/// Sets `stats`' mask bits per shadow class: the (node, light) bits
/// `mesh` holds after `job`'s frame for the lights of each class, so a
/// run can show that the plan's `none` and formula-(1) lights cost no
/// mask bit. Both backends count them the same way.
fn count_class_mask_bits(job: &FrameJob, mesh: &LightMesh, stats: &mut FrameStats) {
    for class in Shadows::ALL {
        let words = job.shadows.class_words(class, &job.frame.lights);
        stats.shadow_classes.get_mut(class).mask_bits = mesh.masks().known_bits_of(&words);
    }
}

/// Why a backend could not start.
#[derive(Debug, thiserror::Error)]
pub enum BackendError {
    #[error("cannot start {threads} render threads: {source}")]
    Threads {
        threads: usize,
        source: rayon::ThreadPoolBuildError,
    },
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// Why a frame could not be rendered.
#[derive(Debug, thiserror::Error)]
pub enum RenderError {
    /// The light mesh refused the frame (a setting the scene cannot meet).
    #[error(transparent)]
    LightMesh(#[from] LightMeshError),
    /// A frame that shades lights from the light mesh came without one:
    /// the caller's mistake, never the scene's.
    #[error("the frame shades lights from a light mesh, and came without one")]
    NoLightMesh,
    #[error(transparent)]
    Gpu(#[from] GpuError),
}

/// The backend a run renders on.
pub enum Backend {
    Cpu(CpuBackend),
    Gpu(Box<GpuBackend>),
}

impl Backend {
    /// Starts the backend of `kind` with `threads` CPU workers (one per
    /// core when None); a GPU backend also finds its adapter.
    pub fn new(kind: BackendKind, threads: Option<usize>) -> Result<Backend, BackendError> {
        Ok(match kind {
            BackendKind::Cpu => Backend::Cpu(CpuBackend::new(threads)?),
            BackendKind::Gpu => Backend::Gpu(Box::new(GpuBackend::new(threads)?)),
        })
    }

    /// CPU worker threads (the GPU backend shades on them).
    pub fn threads(&self) -> usize {
        match self {
            Backend::Cpu(cpu) => cpu.threads(),
            Backend::Gpu(gpu) => gpu.threads(),
        }
    }

    /// Bounds the GPU memory the light mesh's resident masks may take; the
    /// CPU backend keeps its masks in the light mesh alone.
    pub fn limit_mask_memory(&mut self, bytes: usize) {
        if let Backend::Gpu(gpu) = self {
            gpu.limit_mask_memory(bytes);
        }
    }

    /// Sets whether the GPU's light-mesh fill groups its segments by
    /// shafts first (it does unless told; the CPU backend's fill always
    /// does): for measuring both on one adapter.
    pub fn set_fill_shafts(&mut self, shafts: Shafts) {
        if let Backend::Gpu(gpu) = self {
            gpu.set_fill_shafts(shafts);
        }
    }

    /// Keeps the GPU's compiled pipelines in `dir` across runs; the CPU
    /// backend compiles nothing.
    pub fn keep_pipelines_in(&mut self, dir: &Path) {
        if let Backend::Gpu(gpu) = self {
            gpu.keep_pipelines_in(dir);
        }
    }

    /// Compiles the GPU pipelines frames by `method` with `aovs` need,
    /// reporting (compiled, of) to `progress` (see
    /// [`GpuBackend::prepare_pipelines`]); nothing on the CPU.
    pub fn prepare_pipelines(
        &self,
        method: FrameMethod,
        aovs: &[Aov],
        progress: impl FnMut(usize, usize),
    ) {
        if let Backend::Gpu(gpu) = self {
            gpu.prepare_pipelines(method, aovs, progress);
        }
    }

    /// The adapter a GPU backend runs on, for the user; None on the CPU.
    pub fn adapter(&self) -> Option<String> {
        match self {
            Backend::Cpu(_) => None,
            Backend::Gpu(gpu) => Some(gpu.adapter()),
        }
    }

    /// Computes the light-mesh masks `job`'s frame will need, and LMM1's
    /// enclosure flags where `probe_enclosure`, without shading it
    /// (`lmanim warm`); the light-mesh stats go to `stats`.
    pub fn warm(
        &mut self,
        job: &FrameJob,
        mesh: &mut LightMesh,
        probe_enclosure: bool,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        match self {
            Backend::Cpu(cpu) => cpu.warm(job, mesh, probe_enclosure, stats),
            Backend::Gpu(gpu) => gpu.warm(job, mesh, probe_enclosure, stats),
        }
    }

    /// Renders one frame by `method` (the run's method resolved for the
    /// frame: [`ShadowSplit::resolve`]), with the AOV layers `job` asks
    /// for; stage times, ray and point counts go to `stats`. A light-mesh
    /// frame shades from `light_mesh`, which the caller keeps across
    /// frames so that its masks are reused; the others ignore it.
    ///
    /// [`ShadowSplit::resolve`]: crate::render::shadow_split::ShadowSplit::resolve
    pub fn render(
        &mut self,
        job: &FrameJob,
        method: FrameMethod,
        light_mesh: Option<&mut LightMesh>,
        stats: &mut FrameStats,
    ) -> Result<RenderedFrame, RenderError> {
        match self {
            Backend::Cpu(cpu) => cpu.render(job, method, light_mesh, stats),
            Backend::Gpu(gpu) => gpu.render(job, method, light_mesh, stats),
        }
    }
}

/// A rayon pool of `threads` workers, or one per core when None.
fn thread_pool(threads: Option<usize>) -> Result<rayon::ThreadPool, BackendError> {
    let threads = threads.unwrap_or(0);
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|source| BackendError::Threads { threads, source })
}
