//! A band's film on the GPU: each level's shading points add what they
//! send to their pixel samples (`accumulate.wgsl`), in point order, and
//! the samples resolve into pixels (`resolve.wgsl`), as the CPU's
//! `Environment::shaded_value` and `resolve` do, with the frame's
//! background and ambient sky; only the pixels and two counters come back.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use super::context::{GpuContext, GpuError};
use super::contract::{
    COUNTERS, COUNTER_CLASS_RAYS, COUNTER_OTHER_RAYS, COUNTER_SHADING_POINTS, DIRECT, ENVIRONMENT,
    FILM_COUNTERS, ITEMS,
};
use super::pass::{answer_buffer, read_back, Dispatch, WorldPass, WorldUse};
use super::scene::{storage, GpuScene};
use super::shaders::Entry;
use super::surface::LevelBuffers;
use crate::render::environment::Environment;
use crate::stats::ClassRays;

/// `environment.wgsl`'s `Environment`: an [`Environment`] with flags for
/// the parts that are on.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct EnvironmentRecord {
    background: [f32; 3],
    opaque: u32,
    ambient: [f32; 3],
    sky: u32,
}

impl From<&Environment> for EnvironmentRecord {
    fn from(environment: &Environment) -> EnvironmentRecord {
        EnvironmentRecord {
            background: environment.background.unwrap_or_default().to_array(),
            opaque: environment.background.is_some() as u32,
            ambient: environment.ambient.unwrap_or_default().to_array(),
            sky: environment.ambient.is_some() as u32,
        }
    }
}

/// The two pipelines, made once per run.
pub struct FilmPasses {
    pub(super) accumulate: WorldPass,
    pub(super) resolve: WorldPass,
}

impl FilmPasses {
    pub fn new(context: &GpuContext) -> FilmPasses {
        FilmPasses {
            accumulate: WorldPass::new(
                context,
                Entry::Accumulate,
                WorldUse::None,
                &[DIRECT, ENVIRONMENT],
                &[COUNTERS],
            ),
            resolve: WorldPass::new(context, Entry::Resolve, WorldUse::None, &[ENVIRONMENT], &[]),
        }
    }
}

/// One band's samples and counters, and the frame's environment.
pub struct Film {
    samples: wgpu::Buffer,
    counters: wgpu::Buffer,
    environment: wgpu::Buffer,
    pixels: usize,
}

/// What a band's film gives back.
pub struct Developed {
    pub pixels: Vec<Vec4>,
    pub shading_points: u64,
    /// Segments of no light's class (LMM's point-to-node tests, the
    /// blockers' rays).
    pub other_rays: u64,
    /// Formula (1)'s shadow rays and lamp samples by class.
    pub class_rays: ClassRays,
}

impl Film {
    /// A film of `pixels` pixels of `spp` samples, all dark and uncovered,
    /// in `environment`.
    pub fn new(
        context: &GpuContext,
        pixels: usize,
        spp: usize,
        environment: &Environment,
    ) -> Result<Film, GpuError> {
        let environment = EnvironmentRecord::from(environment);
        Ok(Film {
            samples: answer_buffer::<[f32; 4]>(context, "pixel samples", pixels * spp)?,
            counters: answer_buffer::<[u32; FILM_COUNTERS as usize]>(context, "counters", 1)?,
            environment: storage(context, "environment", &[environment])?,
            pixels,
        })
    }

    /// The frame's background and ambient sky, as uploaded.
    pub fn environment(&self) -> &wgpu::Buffer {
        &self.environment
    }

    /// Records the adding of `level`'s points, with their `direct` light.
    pub fn accumulate(
        &self,
        passes: &FilmPasses,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        level: &LevelBuffers,
        direct: &wgpu::Buffer,
    ) {
        let reads = [
            (ITEMS, &level.points),
            (DIRECT, direct),
            (ENVIRONMENT, &self.environment),
            (COUNTERS, &self.counters),
        ];
        let count = level.count;
        (passes.accumulate).record(
            context,
            encoder,
            Dispatch::new(scene, count),
            &reads,
            &self.samples,
        );
    }

    /// Resolves the samples into pixels and reads them back.
    pub fn develop(
        &self,
        passes: &FilmPasses,
        context: &GpuContext,
        scene: &GpuScene,
    ) -> Result<Developed, GpuError> {
        let pixels = answer_buffer::<[f32; 4]>(context, "pixels", self.pixels)?;
        let mut encoder = context.device.create_command_encoder(&Default::default());
        let reads = [(ITEMS, &self.samples), (ENVIRONMENT, &self.environment)];
        let count = self.pixels;
        (passes.resolve).record(
            context,
            &mut encoder,
            Dispatch::new(scene, count),
            &reads,
            &pixels,
        );
        let pixels: Vec<[f32; 4]> = read_back(context, encoder, &pixels, count)?;
        let encoder = context.device.create_command_encoder(&Default::default());
        let [counters]: [[u32; FILM_COUNTERS as usize]; 1] =
            read_back(context, encoder, &self.counters, 1)?
                .try_into()
                .map_err(|_| GpuError::Readback("no counters".into()))?;
        Ok(Developed {
            pixels: pixels.into_iter().map(Vec4::from_array).collect(),
            shading_points: counters[COUNTER_SHADING_POINTS as usize] as u64,
            other_rays: counters[COUNTER_OTHER_RAYS as usize] as u64,
            class_rays: ClassRays::new(std::array::from_fn(|class| {
                counters[COUNTER_CLASS_RAYS as usize + class] as u64
            })),
        })
    }
}
