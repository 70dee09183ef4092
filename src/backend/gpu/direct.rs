//! Formula (1) on the GPU: each shading point's Omega for every light, its
//! shadow segments and their sum, in one pass (`direct_light.wgsl`), over
//! the points the shading-point pass left on the GPU (or points the CPU
//! made and uploads). Only a colour and a ray count per point come back,
//! where the ray queries would move a segment and an answer per point and
//! light.
//!
//! The shader repeats the CPU's eight-lane Omega operation for operation,
//! rounding as the CPU does where the adapter has f64, so a point gets the
//! CPU backend's bits wherever its segments get the CPU's answers (the GPU
//! tests compare whole frames). Where the adapter has no f64, or flushes a
//! denormal to zero, a term can differ in its last bits.

use bytemuck::{Pod, Zeroable};
use glam::Vec3;
use rayon::prelude::*;

use super::context::{GpuContext, GpuError};
use super::contract::{
    CLASS_SHIFT, ITEMS, LIGHTS, SHADED_BY_FORMULA_ONE, SHADED_BY_LIGHT_MESH, TESTS_SEGMENT,
};
use super::layered::{LayeredPass, PointLayers};
use super::pass::{WorldUse, BATCH};
use super::scene::{storage, GpuScene};
use super::shaders::Entry;
use super::surface::{LevelBuffers, SurfacePoint};
use crate::plan::Shadows;
use crate::render::light::RenderLight;
use crate::render::omega::OmegaLight;
use crate::render::shadow_split::{FrameMethod, LightRole};
use crate::render::surface::ShadingPoint;
use crate::render::FrameJob;
use crate::stats::ClassRays;

/// Each of `job`'s lights' `shading` bits under `method`: its role in the
/// frame's [`ShadowSplit`](crate::render::shadow_split::ShadowSplit), so
/// that one frame's passes can shade some lights by formula (1) and the
/// others by formula (2), as `auto` resolves where some light is soft. A light switched off, or one
/// whose lamp the CPU samples (`area`), has no integrator bit.
pub fn shading_flags(job: &FrameJob, method: FrameMethod) -> Vec<u32> {
    let (shadows, lights) = (job.shadows, &job.frame.lights);
    (0..lights.len())
        .map(|index| {
            let segment = match shadows.tests_segment(index) {
                true => TESTS_SEGMENT,
                false => 0,
            };
            let class = (shadows.class(index, lights) as u32) << CLASS_SHIFT;
            let integrator = match shadows.role(method, index, lights) {
                LightRole::FormulaOne { .. } => SHADED_BY_FORMULA_ONE | segment,
                LightRole::LightMesh => SHADED_BY_LIGHT_MESH | segment,
                LightRole::Off | LightRole::Lamp => 0,
            };
            integrator | class
        })
        .collect()
}

/// `omega.wgsl`'s `Light`: an [`OmegaLight`] whose missing range is 0
/// rather than infinite, so the shader needs no infinities, with its layer
/// of the `light` AOV and its `shading` bits.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FlatLight {
    origin: [f32; 3],
    directional: u32,
    power: [f32; 3],
    range_squared: f32,
    axis: [f32; 3],
    cos_outer: f32,
    cos_inner: f32,
    layer: u32,
    shading: u32,
    /// The lamp's radius, which sizes its penumbrae
    /// (`lightmesh::penumbra`).
    lamp_radius: f32,
}

impl FlatLight {
    /// `light`, adding to the `light` AOV's layer `layer`, shaded as
    /// `shading` says.
    fn new(light: &RenderLight, layer: usize, shading: u32) -> FlatLight {
        let lamp_radius = light.lamp_radius;
        let light = OmegaLight::from(light);
        FlatLight {
            origin: light.origin.to_array(),
            directional: light.directional as u32,
            power: light.power.to_array(),
            range_squared: if light.range_squared.is_finite() {
                light.range_squared
            } else {
                0.0
            },
            axis: light.axis.to_array(),
            cos_outer: light.cos_outer,
            cos_inner: light.cos_inner,
            layer: layer as u32,
            shading,
            lamp_radius,
        }
    }
}

/// `formula_one.wgsl`'s `DirectLight`: one point's answer.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct DirectLight {
    radiance: [f32; 3],
    /// Segments of no light's class: LMM's point-to-node tests and the
    /// rays that found penumbrae's blockers.
    other_rays: u32,
    /// Formula (1)'s shadow rays and lamp samples, by the plan's class of
    /// their light (as [`Shadows::ALL`] lists them).
    class_rays: [u32; 4],
}

impl DirectLight {
    /// A point's direct light made on the CPU (`--method area`), with its
    /// lamp samples' rays by class.
    pub fn new(radiance: Vec3, rays: ClassRays) -> DirectLight {
        DirectLight {
            radiance: radiance.to_array(),
            other_rays: 0,
            class_rays: Shadows::ALL.map(|class| rays.of(class) as u32),
        }
    }

    pub fn radiance(&self) -> Vec3 {
        Vec3::from_array(self.radiance)
    }

    pub fn shadow_rays(&self) -> u64 {
        self.other_rays as u64 + self.class_rays.iter().map(|&rays| rays as u64).sum::<u64>()
    }
}

/// A frame's lights, uploaded once for all its batches.
pub struct FrameLights {
    buffer: wgpu::Buffer,
    count: u32,
}

impl FrameLights {
    pub fn buffer(&self) -> &wgpu::Buffer {
        &self.buffer
    }

    pub fn count(&self) -> u32 {
        self.count
    }

    /// `lights`, each shaded by formula (1) with its segment tested, all
    /// in the `light` AOV's first layer: what the passes run outside a
    /// frame (tests, benchmarks) take.
    pub fn upload(context: &GpuContext, lights: &[RenderLight]) -> Result<FrameLights, GpuError> {
        let shading = vec![SHADED_BY_FORMULA_ONE | TESTS_SEGMENT; lights.len()];
        FrameLights::upload_shaded(context, lights, &shading, &[])
    }

    /// `lights` with their `shading` bits ([`shading_flags`]), each in
    /// its layer of `layer_of` (the first where it has none).
    pub fn upload_shaded(
        context: &GpuContext,
        lights: &[RenderLight],
        shading: &[u32],
        layer_of: &[usize],
    ) -> Result<FrameLights, GpuError> {
        let layer = |index: usize| layer_of.get(index).copied().unwrap_or_default();
        let flat: Vec<FlatLight> = (lights.iter().enumerate())
            .map(|(index, light)| FlatLight::new(light, layer(index), shading[index]))
            .collect();
        Ok(FrameLights {
            buffer: storage(context, "lights", &flat)?,
            count: lights.len() as u32,
        })
    }
}

/// The direct-light pipelines, made once per run (the light layers' when
/// first asked for).
pub struct DirectLightPass {
    pub(super) pass: LayeredPass,
}

impl DirectLightPass {
    pub fn new(context: &GpuContext) -> DirectLightPass {
        DirectLightPass {
            pass: LayeredPass::new(
                context,
                (Entry::DirectLight, Entry::DirectLightLayers),
                WorldUse::Traces,
                &[LIGHTS],
                &[],
            ),
        }
    }

    /// Records formula (1) at each of `level`'s shading points into
    /// `direct` (zero for rays that hit nothing), and their terms per
    /// light layer into `layers` where given.
    #[allow(clippy::too_many_arguments)]
    pub fn record(
        &self,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        lights: &FrameLights,
        level: &LevelBuffers,
        direct: &wgpu::Buffer,
        layers: Option<&PointLayers>,
    ) {
        let reads = [(ITEMS, &level.points), (LIGHTS, &lights.buffer)];
        (self.pass).record(
            context,
            encoder,
            level.dispatch(scene).with_lights(lights.count),
            &reads,
            direct,
            layers,
        );
    }

    /// Formula (1) at each of `points`, in order, and the shadow segments
    /// traced for them.
    pub fn run(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        lights: &FrameLights,
        points: &[ShadingPoint],
    ) -> Result<(Vec<Vec3>, u64), GpuError> {
        let mut radiance = Vec::with_capacity(points.len());
        let mut shadow_rays = 0;
        for batch in points.chunks(BATCH) {
            let items: Vec<SurfacePoint> = batch.par_iter().map(SurfacePoint::from).collect();
            let answers: Vec<DirectLight> = self.pass.plain().run(
                "formula (1) at points the CPU made",
                context,
                scene,
                &items,
                &[(LIGHTS, &lights.buffer)],
                lights.count,
            )?;
            for answer in answers {
                radiance.push(answer.radiance());
                shadow_rays += answer.shadow_rays();
            }
        }
        Ok((radiance, shadow_rays))
    }
}
