//! One compute pass over the uploaded world, end to end: the pass's items
//! (binding 1) and any further inputs bound beside the world's arrays, one
//! invocation per item, and an answer per item read back in item order.
//! The ray queries and the direct-light pass differ only in what they bind
//! and what they answer.

use bytemuck::Pod;
use wgpu::util::DeviceExt;

use super::context::{GpuContext, GpuError};
use super::scene::GpuScene;
use super::shaders::{self, Arithmetic, Entry};

/// Invocations per workgroup, as the shaders declare.
const WORKGROUP: u32 = 64;
/// Items per dispatch: within the 65535 workgroups a dispatch may have in
/// one dimension, and a few tens of MiB of items.
pub const BATCH: usize = 1 << 20;

/// The binding of a pass's items; its answers go to [`ANSWERS`].
const ITEMS: u32 = 1;
const ANSWERS: u32 = 7;

/// A compute pipeline and its bind group layout.
pub struct WorldPass {
    entry: Entry,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl WorldPass {
    /// The pipeline of `entry`, binding the world, its items, its answers
    /// and the read-only arrays at `inputs`.
    pub fn new(context: &GpuContext, entry: Entry, inputs: &[u32]) -> WorldPass {
        let device = &context.device;
        let buffer = |binding, ty| wgpu::BindGroupLayoutEntry {
            binding,
            visibility: wgpu::ShaderStages::COMPUTE,
            ty: wgpu::BindingType::Buffer {
                ty,
                has_dynamic_offset: false,
                min_binding_size: None,
            },
            count: None,
        };
        let read_only = wgpu::BufferBindingType::Storage { read_only: true };
        let mut entries = vec![
            buffer(0, wgpu::BufferBindingType::Uniform),
            buffer(ITEMS, read_only),
            buffer(
                ANSWERS,
                wgpu::BufferBindingType::Storage { read_only: false },
            ),
        ];
        let world = GpuScene::BINDINGS.iter().chain(inputs);
        entries.extend(world.map(|&binding| buffer(binding, read_only)));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(entry.name()),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(entry.name()),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let arithmetic = if context.exact {
            Arithmetic::ExactF64
        } else {
            Arithmetic::PlainF32
        };
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some(entry.name()),
            source: wgpu::ShaderSource::Wgsl(shaders::source(entry, arithmetic).into()),
        });
        let pipeline = device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(entry.name()),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(entry.name()),
            compilation_options: Default::default(),
            cache: None,
        });
        WorldPass {
            entry,
            layout,
            pipeline,
        }
    }

    /// Runs the pass over `items` (at most [`BATCH`]) with `inputs` bound
    /// as [`WorldPass::new`] declared them, `light_count` lights; one
    /// `Answer` per item.
    pub fn run<Item: Pod, Answer: Pod>(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        items: &[Item],
        inputs: &[(u32, &wgpu::Buffer)],
        light_count: u32,
    ) -> Result<Vec<Answer>, GpuError> {
        debug_assert!(items.len() <= BATCH);
        context.checked(self.entry.name(), || {
            self.dispatch(context, scene, items, inputs, light_count)
        })
    }

    fn dispatch<Item: Pod, Answer: Pod>(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        items: &[Item],
        inputs: &[(u32, &wgpu::Buffer)],
        light_count: u32,
    ) -> Result<Vec<Answer>, GpuError> {
        let device = &context.device;
        let params = scene.params(items.len() as u32, light_count);
        let params = device.create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some("pass params"),
            contents: bytemuck::bytes_of(&params),
            usage: wgpu::BufferUsages::UNIFORM,
        });
        let item_buffer = super::scene::storage(context, "pass items", items)?;
        let answer_bytes = (items.len().max(1) * size_of::<Answer>()) as u64;
        context.check_binding("pass answers", answer_bytes)?;
        let answers = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pass answers"),
            size: answer_bytes,
            usage: wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        let readback = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("pass readback"),
            size: answer_bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let own = [(0, &params), (ITEMS, &item_buffer), (ANSWERS, &answers)];
        let entries: Vec<wgpu::BindGroupEntry> = own
            .into_iter()
            .chain(inputs.iter().copied())
            .chain(scene.buffers())
            .map(|(binding, buffer)| wgpu::BindGroupEntry {
                binding,
                resource: buffer.as_entire_binding(),
            })
            .collect();
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(self.entry.name()),
            layout: &self.layout,
            entries: &entries,
        });
        let mut encoder = device.create_command_encoder(&Default::default());
        {
            let mut pass = encoder.begin_compute_pass(&Default::default());
            pass.set_pipeline(&self.pipeline);
            pass.set_bind_group(0, &bind_group, &[]);
            pass.dispatch_workgroups((items.len() as u32).div_ceil(WORKGROUP), 1, 1);
        }
        encoder.copy_buffer_to_buffer(&answers, 0, &readback, 0, answer_bytes);
        context.queue.submit([encoder.finish()]);
        read_back(context, &readback, items.len())
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
