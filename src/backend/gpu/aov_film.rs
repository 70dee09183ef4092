//! The AOV layers' film on the GPU (`--aovs`), beside the beauty's
//! ([`super::film`]): per sample of a band, its camera hit
//! (`first_hits.wgsl`, from the camera level's points and rays) and, for
//! the `light` AOV, what its points sent per light layer
//! (`accumulate_layers.wgsl`, from each level's [`PointLayers`]). Both
//! come back as the [`BandSamples`] the CPU backend fills, for the one
//! resolve both backends share (`backend/aov.rs`), so the layers can
//! differ from the CPU's only where the samples do.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;

use super::context::{GpuContext, GpuError};
use super::contract::{ENVIRONMENT, ITEMS, PATHS, POINT_LAYERS};
use super::film::Film;
use super::layered::PointLayers;
use super::pass::{answer_buffer, WorldPass, WorldUse};
use super::recording::{Downloaded, Downloads, Part};
use super::scene::GpuScene;
use super::shaders::Entry;
use super::surface::LevelBuffers;
use crate::backend::aov::{BandSamples, FirstHit, LightLayers};

/// `first_hits.wgsl`'s `FirstHit`: a [`FirstHit`] as the GPU writes it.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FirstHitRecord {
    albedo: [f32; 3],
    depth: f32,
    normal: [f32; 3],
    covered: u32,
}

impl From<&FirstHitRecord> for FirstHit {
    fn from(record: &FirstHitRecord) -> FirstHit {
        FirstHit {
            covered: record.covered != 0,
            albedo: Vec3::from_array(record.albedo),
            normal: Vec3::from_array(record.normal),
            depth: record.depth,
        }
    }
}

/// The AOV film's two pipelines, made by the first frame with AOVs.
pub struct AovPasses {
    pub(super) first_hits: WorldPass,
    pub(super) layers: WorldPass,
}

impl AovPasses {
    pub fn new(context: &GpuContext) -> AovPasses {
        AovPasses {
            first_hits: WorldPass::new(context, Entry::FirstHits, WorldUse::None, &[PATHS], &[]),
            layers: WorldPass::new(
                context,
                Entry::AccumulateLayers,
                WorldUse::None,
                &[POINT_LAYERS, ENVIRONMENT],
                &[],
            ),
        }
    }
}

/// One band's AOV samples on the GPU.
pub struct AovFilm {
    first_hits: wgpu::Buffer,
    /// With the `light` AOV: per sample, its light layers and `other`;
    /// and which layer each of the frame's lights adds to.
    light: Option<(wgpu::Buffer, Vec<usize>)>,
    layers: usize,
    samples: usize,
}

impl AovFilm {
    /// A film of `samples` samples, split into `lights`' layers where the
    /// `light` AOV asks for them.
    pub fn new(
        context: &GpuContext,
        samples: usize,
        lights: Option<&LightLayers>,
    ) -> Result<AovFilm, GpuError> {
        let layers = lights.map_or(0, |lights| lights.names.len());
        let light = match lights {
            Some(lights) => Some((
                answer_buffer::<[f32; 4]>(context, "light layers", samples * (layers + 1))?,
                lights.layer_of.clone(),
            )),
            None => None,
        };
        Ok(AovFilm {
            first_hits: answer_buffer::<FirstHitRecord>(context, "first hits", samples)?,
            light,
            layers,
            samples,
        })
    }

    /// Which light layer each of the frame's lights adds to, and how
    /// many there are, where the `light` AOV asks for them.
    pub fn layer_of(&self) -> Option<(&[usize], usize)> {
        (self.light.as_ref()).map(|(_, layer_of)| (&layer_of[..], self.layers))
    }

    /// Zeroed layer sums for a level of `points` points to fill, where the
    /// `light` AOV asks for them.
    pub fn point_layers(
        &self,
        context: &GpuContext,
        points: usize,
    ) -> Result<Option<PointLayers>, GpuError> {
        match self.light {
            Some(_) => Ok(Some(PointLayers::zeroed(context, points, self.layers)?)),
            None => Ok(None),
        }
    }

    /// Records the camera hits of the camera level `level`.
    pub fn record_first_hits(
        &self,
        passes: &AovPasses,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        level: &LevelBuffers,
    ) {
        let reads = [(ITEMS, &level.points), (PATHS, &level.paths)];
        let dispatch = level.dispatch(scene);
        (passes.first_hits).record(context, encoder, dispatch, &reads, &self.first_hits);
    }

    /// Records the adding of what `level`'s points sent, per light layer
    /// as `layers` holds it, where the `light` AOV asks for it.
    #[allow(clippy::too_many_arguments)]
    pub fn accumulate(
        &self,
        passes: &AovPasses,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        film: &Film,
        level: &LevelBuffers,
        layers: &PointLayers,
    ) {
        let Some((light, _)) = &self.light else {
            return;
        };
        let reads = [
            (ITEMS, &level.points),
            (POINT_LAYERS, &layers.buffer),
            (ENVIRONMENT, film.environment()),
        ];
        let dispatch = level.dispatch(scene).with_layers(self.layers);
        (passes.layers).record(context, encoder, dispatch, &reads, light);
    }

    /// Adds the band's samples to what its wait brings back.
    pub fn develop<'f>(&'f self, downloads: &mut Downloads<'f>) -> AovParts {
        AovParts {
            first_hits: downloads.add(&self.first_hits, self.samples),
            light: (self.light.as_ref())
                .map(|(buffer, _)| downloads.add(buffer, self.samples * (self.layers + 1))),
        }
    }
}

/// Where a band's AOV samples lie in what its wait brings back.
pub struct AovParts {
    first_hits: Part<FirstHitRecord>,
    light: Option<Part<[f32; 4]>>,
}

impl AovParts {
    /// The band's samples, from what its wait brought back.
    pub fn samples(self, downloaded: &Downloaded) -> BandSamples {
        let records = downloaded.take(self.first_hits);
        let light = match self.light {
            Some(part) => (downloaded.take(part).iter())
                .map(|&[r, g, b, _]| Vec3::new(r, g, b))
                .collect(),
            None => Vec::new(),
        };
        BandSamples {
            first_hits: records.iter().map(FirstHit::from).collect(),
            light,
        }
    }
}
