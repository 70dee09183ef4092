//! The camera's rays on the GPU (`camera.wgsl`): a band's pixel samples
//! made where they are traced, as the CPU makes them (pixel centres, or
//! jittered strata drawn from the same PCG32 streams), so level 0 of a
//! frame uploads one camera record rather than a ray per sample.

use bytemuck::{Pod, Zeroable};

use super::context::{GpuContext, GpuError};
use super::contract::ITEMS;
use super::pass::{answer_buffer, Dispatch, WorldPass, WorldUse};
use super::scene::{storage, GpuScene};
use super::shaders::Entry;
use super::surface::{LevelBuffers, PathRay};
use crate::render::camera::RenderCamera;
use crate::render::FrameJob;
use crate::scene::Projection;

/// `camera.wgsl`'s `Camera`: the render camera and the band it shoots.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct CameraRecord {
    origin: [f32; 3],
    perspective: u32,
    right: [f32; 3],
    extent: f32,
    up: [f32; 3],
    t_max: f32,
    backward: [f32; 3],
    width: u32,
    height: u32,
    spp: u32,
    strata: u32,
    first_row: u32,
    first_sample: [u32; 2],
    batch_start: u32,
    _pad: u32,
}

impl CameraRecord {
    /// The record for the samples from `batch_start` on of the band of
    /// `job` that starts at row `first_row`.
    /// The tangent of the half field of view and the strata are computed
    /// here, so the GPU takes the CPU's roundings of both.
    pub fn new(job: &FrameJob, first_row: u32, batch_start: u32) -> CameraRecord {
        let camera: &RenderCamera = &job.frame.camera;
        let (perspective, extent, t_max) = match camera.projection {
            Projection::Perspective { yfov, zfar, .. } => {
                (1, (0.5 * yfov).tan(), zfar.unwrap_or(f32::INFINITY))
            }
            Projection::Orthographic { ymag, zfar, .. } => (0, ymag, zfar),
        };
        let first_sample = first_row as u64 * job.width as u64 * job.spp as u64;
        CameraRecord {
            origin: camera.origin.to_array(),
            perspective,
            right: camera.right.to_array(),
            extent,
            up: camera.up.to_array(),
            t_max,
            backward: camera.backward.to_array(),
            width: job.width,
            height: job.height,
            spp: job.spp,
            strata: (job.spp as f32).sqrt().floor() as u32,
            first_row,
            first_sample: [first_sample as u32, (first_sample >> 32) as u32],
            batch_start,
            _pad: 0,
        }
    }
}

/// The camera pipeline, made once per run.
pub struct CameraPass {
    pub(super) pass: WorldPass,
}

impl CameraPass {
    pub fn new(context: &GpuContext) -> CameraPass {
        CameraPass {
            pass: WorldPass::new(context, Entry::CameraRays, WorldUse::None, &[], &[]),
        }
    }

    /// Level 0 of a batch of `count` samples from `camera`'s band: the
    /// rays made on the GPU, into buffers for the passes that follow.
    pub fn rays(
        &self,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        scene: &GpuScene,
        camera: &CameraRecord,
        count: usize,
    ) -> Result<LevelBuffers, GpuError> {
        let record = storage(context, "camera", std::slice::from_ref(camera))?;
        let paths = answer_buffer::<PathRay>(context, "camera rays", count)?;
        let reads = [(ITEMS, &record)];
        (self.pass).record(
            context,
            encoder,
            Dispatch::new(scene, count),
            &reads,
            &paths,
        );
        LevelBuffers::with_paths(context, paths, count, None)
    }
}
