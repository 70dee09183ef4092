//! The GPU's ray queries: closest hits and any-hit (shadow) tests of a
//! batch of render-space rays against the uploaded world, one compute
//! invocation per ray. Rays go up as the CPU made them and answers come
//! back in the same order, or (closest hits of path rays) stay on the GPU
//! for the shading-point pass.

use bytemuck::{Pod, Zeroable};
use glam::Vec2;

use super::context::{GpuContext, GpuError};
use super::contract::{ITEMS, NO_MESH};
use super::pass::{WorldPass, WorldUse, BATCH};
use super::scene::GpuScene;
use super::shaders::Entry;
use super::surface::{LevelBuffers, PathRay};
use crate::accel::{Hit, MeshId, Ray, World};

/// `rays.wgsl`'s `Ray`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct GpuRay {
    pub origin: [f32; 3],
    pub t_max: f32,
    pub direction: [f32; 3],
    pub _pad: f32,
}

impl From<&Ray> for GpuRay {
    fn from(ray: &Ray) -> GpuRay {
        GpuRay {
            origin: ray.origin.to_array(),
            t_max: ray.t_max,
            direction: ray.direction.to_array(),
            _pad: 0.0,
        }
    }
}

/// `closest_hit.wgsl`'s `HitRecord`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct HitRecord {
    pub t: f32,
    pub u: f32,
    pub v: f32,
    /// 0 for the static mesh, 1 + i for instance i, [`NO_MESH`] for none.
    pub mesh: u32,
    pub slot: u32,
    /// The triangle's source, `(object, triangle)`.
    pub object: u32,
    pub triangle: u32,
    pub _pad: u32,
}

impl HitRecord {
    fn mesh(&self) -> Option<MeshId> {
        match self.mesh {
            NO_MESH => None,
            0 => Some(MeshId::Static),
            i => Some(MeshId::Instance(i - 1)),
        }
    }
}

/// The two ray-query pipelines, made once per run.
pub struct RayQueries {
    pub(super) closest: WorldPass,
    pub(super) any: WorldPass,
}

impl RayQueries {
    pub fn new(context: &GpuContext) -> RayQueries {
        RayQueries {
            closest: WorldPass::new(context, Entry::ClosestHit, WorldUse::Traces, &[], &[]),
            any: WorldPass::new(context, Entry::AnyHit, WorldUse::Traces, &[], &[]),
        }
    }

    /// The closest hit of each ray, completed on the CPU from the world
    /// (sources, normals) exactly as `World::closest_hit` completes its own.
    pub fn closest_hits(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        world: &World,
        rays: &[Ray],
    ) -> Result<Vec<Option<Hit>>, GpuError> {
        let mut records: Vec<HitRecord> = Vec::with_capacity(rays.len());
        for batch in rays.chunks(BATCH) {
            let paths: Vec<PathRay> = batch.iter().map(PathRay::from).collect();
            records.extend(self.closest.run::<PathRay, HitRecord>(
                "the rays' closest hits",
                context,
                scene,
                &paths,
                &[],
                0,
            )?);
        }
        Ok(records
            .iter()
            .map(|record| {
                let mesh = record.mesh()?;
                world.hit_at(mesh, record.slot, record.t, Vec2::new(record.u, record.v))
            })
            .collect())
    }

    /// Records the closest hits of `level`'s path rays into its hits.
    pub fn record_closest(
        &self,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        level: &LevelBuffers,
    ) {
        let reads = [(ITEMS, &level.paths)];
        (self.closest).record(context, encoder, level.dispatch(scene), &reads, &level.hits);
    }

    /// Whether anything lies on each ray in `(0, t_max)`.
    pub fn occluded(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        rays: &[Ray],
    ) -> Result<Vec<bool>, GpuError> {
        let mut occluded = Vec::with_capacity(rays.len());
        for batch in rays.chunks(BATCH) {
            let gpu_rays: Vec<GpuRay> = batch.iter().map(GpuRay::from).collect();
            let words: Vec<u32> = self.any.run(
                "whether each ray is blocked",
                context,
                scene,
                &gpu_rays,
                &[],
                0,
            )?;
            occluded.extend(words.into_iter().map(|word| word != 0));
        }
        Ok(occluded)
    }
}
