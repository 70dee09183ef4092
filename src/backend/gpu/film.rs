//! A band's film on the GPU: each level's shading points add what they
//! send to their pixel samples (`accumulate.wgsl`), in point order, and
//! the samples resolve into pixels (`resolve.wgsl`), as the CPU's
//! `Environment::shaded_value` and `resolve` do, with the frame's
//! background and ambient sky; only the pixels and the band's counters
//! come back, with whatever else the band's one wait brings.

use bytemuck::{Pod, Zeroable};
use glam::Vec4;

use super::context::{GpuContext, GpuError};
use super::contract::{
    COUNTERS, COUNTER_CLASS_RAYS, COUNTER_OTHER_RAYS, COUNTER_SECONDARY_RAYS,
    COUNTER_SHADING_POINTS, DIRECT, ENVIRONMENT, FILM_COUNTERS, ITEMS,
};
use super::pass::{answer_buffer, Dispatch, WorldPass, WorldUse};
use super::recording::{Downloaded, Downloads, Part};
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

/// The film's counters, as the shaders add them up.
type Counters = [u32; FILM_COUNTERS as usize];

/// One band's samples, pixels and counters, and the frame's environment.
pub struct Film {
    samples: wgpu::Buffer,
    pixels: wgpu::Buffer,
    counters: wgpu::Buffer,
    environment: wgpu::Buffer,
    pixel_count: usize,
}

/// Where a band's pixels and counters lie in what its wait brings back.
pub struct FilmParts {
    pixels: Part<[f32; 4]>,
    counters: Part<Counters>,
}

/// What a band's film gives back.
pub struct Developed {
    pub pixels: Vec<Vec4>,
    pub shading_points: u64,
    /// Segments of no light's class (LMM's point-to-node tests, the
    /// blockers' rays).
    pub other_rays: u64,
    /// The rays of the levels after the camera's.
    pub secondary_rays: u64,
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
            pixels: answer_buffer::<[f32; 4]>(context, "pixels", pixels)?,
            counters: answer_buffer::<Counters>(context, "counters", 1)?,
            environment: storage(context, "environment", &[environment])?,
            pixel_count: pixels,
        })
    }

    /// The band's counters, which the passes add to.
    pub fn counters(&self) -> &wgpu::Buffer {
        &self.counters
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
        (passes.accumulate).record(
            context,
            encoder,
            level.dispatch(scene),
            &reads,
            &self.samples,
        );
    }

    /// Records the samples' resolving into pixels, and adds the pixels
    /// and the counters to what the band's wait brings back.
    pub fn develop<'f>(
        &'f self,
        passes: &FilmPasses,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        downloads: &mut Downloads<'f>,
    ) -> FilmParts {
        let reads = [(ITEMS, &self.samples), (ENVIRONMENT, &self.environment)];
        let count = self.pixel_count;
        let dispatch = Dispatch::new(scene, count);
        (passes.resolve).record(context, encoder, dispatch, &reads, &self.pixels);
        FilmParts {
            pixels: downloads.add(&self.pixels, count),
            counters: downloads.add(&self.counters, 1),
        }
    }
}

impl FilmParts {
    /// The band's pixels and counts, from what its wait brought back.
    pub fn developed(self, downloaded: &Downloaded) -> Developed {
        let pixels = downloaded.take(self.pixels);
        let counters = (downloaded.take(self.counters).first().copied()).unwrap_or_default();
        let count = |at: u32| counters[at as usize] as u64;
        Developed {
            pixels: pixels.into_iter().map(Vec4::from_array).collect(),
            shading_points: count(COUNTER_SHADING_POINTS),
            other_rays: count(COUNTER_OTHER_RAYS),
            secondary_rays: count(COUNTER_SECONDARY_RAYS),
            class_rays: ClassRays::new(std::array::from_fn(|class| {
                count(COUNTER_CLASS_RAYS + class as u32)
            })),
        }
    }
}
