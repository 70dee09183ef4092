//! The GPU's ray queries: closest hits and any-hit (shadow) tests of a
//! batch of render-space rays against the uploaded world, one compute
//! invocation per ray. Rays go up as the CPU made them and answers come
//! back in the same order, so every stage around a query stays the CPU's
//! own code and the two backends differ only where a query does.

use bytemuck::{Pod, Zeroable};
use glam::Vec2;
use wgpu::util::DeviceExt;

use super::context::{GpuContext, GpuError};
use super::scene::GpuScene;
use super::shaders::{self, Arithmetic, Query};
use crate::accel::{Hit, MeshId, Ray, World};

/// Invocations per workgroup, as the shaders declare.
const WORKGROUP: u32 = 64;
/// Rays per dispatch: 32 MiB of rays, and within the 65535 workgroups a
/// dispatch may have in one dimension.
const BATCH: usize = 1 << 20;

/// `scene.wgsl`'s `Ray`.
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
    /// 0 for the static mesh, 1 + i for instance i, `u32::MAX` for none.
    pub mesh: u32,
    pub slot: u32,
}

impl HitRecord {
    fn mesh(&self) -> Option<MeshId> {
        match self.mesh {
            u32::MAX => None,
            0 => Some(MeshId::Static),
            i => Some(MeshId::Instance(i - 1)),
        }
    }
}

/// The two compute pipelines and their common bind group layout, made
/// once per run.
pub struct RayQueries {
    layout: wgpu::BindGroupLayout,
    closest: wgpu::ComputePipeline,
    any: wgpu::ComputePipeline,
}

impl RayQueries {
    pub fn new(context: &GpuContext) -> RayQueries {
        let device = &context.device;
        let storage = |binding, read_only| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Storage { read_only },
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let uniform = wgpu::BindGroupLayoutEntry {
            ty: wgpu::BindingType::Buffer {
                ty: wgpu::BufferBindingType::Uniform,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            ..storage(0, true)
        };
        let mut entries = vec![uniform, storage(7, false)];
        entries.extend([1, 2, 3, 4, 5, 6, 8, 9].map(|binding| storage(binding, true)));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("ray queries"),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("ray queries"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let arithmetic = if context.exact {
            Arithmetic::ExactF64
        } else {
            Arithmetic::PlainF32
        };
        let pipeline = |query: Query| {
            let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(query.entry_point()),
                source: wgpu::ShaderSource::Wgsl(shaders::source(query, arithmetic).into()),
            });
            device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
                label: Some(query.entry_point()),
                layout: Some(&pipeline_layout),
                module: &module,
                entry_point: Some(query.entry_point()),
                compilation_options: Default::default(),
                cache: None,
            })
        };
        RayQueries {
            closest: pipeline(Query::ClosestHit),
            any: pipeline(Query::AnyHit),
            layout,
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
        let records: Vec<HitRecord> = self.run(context, scene, Query::ClosestHit, rays)?;
        Ok(records
            .iter()
            .map(|record| {
                let mesh = record.mesh()?;
                world.hit_at(mesh, record.slot, record.t, Vec2::new(record.u, record.v))
            })
            .collect())
    }

    /// Whether anything lies on each ray in `(0, t_max)`.
    pub fn occluded(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        rays: &[Ray],
    ) -> Result<Vec<bool>, GpuError> {
        let words: Vec<u32> = self.run(context, scene, Query::AnyHit, rays)?;
        Ok(words.into_iter().map(|word| word != 0).collect())
    }

    /// Runs `query` over `rays` batch by batch; one `Out` per ray.
    fn run<Out: Pod>(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        query: Query,
        rays: &[Ray],
    ) -> Result<Vec<Out>, GpuError> {
        let mut out = Vec::with_capacity(rays.len());
        for batch in rays.chunks(BATCH) {
            out.extend(self.run_batch::<Out>(context, scene, query, batch)?);
        }
        Ok(out)
    }

    fn run_batch<Out: Pod>(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        query: Query,
        rays: &[Ray],
    ) -> Result<Vec<Out>, GpuError> {
        let device = &context.device;
        let params = scene.params(rays.len() as u32);
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("ray query params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let gpu_rays: Vec<GpuRay> = rays.iter().map(GpuRay::from).collect();
        let ray_buffer = super::scene::storage(context, "rays", &gpu_rays)?;
        let out_bytes = (rays.len().max(1) * size_of::<Out>()) as u64;
        context.check_binding("ray query results", out_bytes)?;
        let output = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ray query results"),
            size: out_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("ray query readback"),
            size: out_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let mut entries = vec![
            wgpu::BindGroupEntry {
                binding: 0,
                resource: params.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 1,
                resource: ray_buffer.as_entire_binding(),
            },
            wgpu::BindGroupEntry {
                binding: 7,
                resource: output.as_entire_binding(),
            },
        ];
        entries.extend(scene.entries());
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(query.entry_point()),
            layout: &self.layout,
            entries: &entries,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(match query {
                Query::ClosestHit => &self.closest,
                Query::AnyHit => &self.any,
            });
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups((rays.len() as u32).div_ceil(WORKGROUP), 1, 1);
        }
        encoder.copy_buffer_to_buffer(&output, 0, &readback, 0, out_bytes);
        context.queue.submit([encoder.finish()]);
        read_back(context, &readback, rays.len())
    }
}

/// Waits for `buffer` and copies its first `count` items out.
fn read_back<Out: Pod>(
    context: &GpuContext,
    buffer: &wgpu::Buffer,
    count: usize,
) -> Result<Vec<Out>, GpuError> {
    let slice = buffer.slice(..);
    let (sender, receiver) = std::sync::mpsc::channel();
    slice.map_async(wgpu::MapMode::Read, move |result| {
        let _ = sender.send(result);
    });
    context
        .device
        .poll(wgpu::PollType::wait_indefinitely())
        .map_err(|error| GpuError::Readback(error.to_string()))?;
    receiver
        .recv()
        .map_err(|error| GpuError::Readback(error.to_string()))?
        .map_err(|error| GpuError::Readback(error.to_string()))?;
    let view = slice
        .get_mapped_range()
        .map_err(|error| GpuError::Readback(error.to_string()))?;
    let items: &[Out] = bytemuck::cast_slice(&view);
    Ok(items[..count].to_vec())
}
