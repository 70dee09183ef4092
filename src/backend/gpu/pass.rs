//! One compute pass, end to end: its pipeline and bind group layout, its
//! dispatch recorded into a command encoder (one invocation per item), and
//! the answers read back. A pass reads its items (binding [`ITEMS`]),
//! optionally the uploaded world's arrays, and further read-only arrays,
//! and writes one answer per item (binding [`ANSWERS`]). Passes that feed each other are
//! recorded into one encoder and their intermediate answers never leave
//! the GPU; [`WorldPass::run`] is the round trip for a single pass.

use bytemuck::Pod;

use super::context::{GpuContext, GpuError};
use super::contract::{ANSWERS, ITEMS, PARAMS, WORKGROUP};
use super::scene::GpuScene;
use super::shaders::{self, Arithmetic, Entry};
use super::spirv;

/// Items per dispatch: within the 65535 workgroups a dispatch may have in
/// one dimension, and a few tens of MiB of items.
pub const BATCH: usize = 1 << 20;

/// The pass's shader: our own SPIR-V where the context takes it (every
/// float operation kept from fusing), else WGSL for wgpu to translate.
fn shader_module(
    context: &GpuContext,
    entry: Entry,
    layout: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::ShaderModule {
    let (arithmetic, capabilities) = if context.f64 {
        (Arithmetic::ExactF64, naga::valid::Capabilities::FLOAT64)
    } else {
        (Arithmetic::PlainF32, naga::valid::Capabilities::empty())
    };
    let source = shaders::source(entry, arithmetic);
    if !context.own_spirv {
        return context
            .device
            .create_shader_module(wgpu::ShaderModuleDescriptor {
                label: Some(entry.name()),
                source: wgpu::ShaderSource::Wgsl(source.into()),
            });
    }
    let bindings: Vec<u32> = layout.iter().map(|binding| binding.binding).collect();
    let words = spirv::compile(&source, entry.name(), capabilities, &bindings)
        .unwrap_or_else(|error| panic!("the {} pass does not compile: {error}", entry.name()));
    let descriptor = wgpu::ShaderModuleDescriptorPassthrough {
        label: Some(entry.name()),
        entry_points: vec![wgpu::PassthroughShaderEntryPoint {
            name: entry.name().into(),
            workgroup_size: (WORKGROUP, 1, 1),
        }]
        .into(),
        spirv: Some(words.into()),
        ..Default::default()
    };
    // SAFETY: the words are naga's translation of a module naga has just
    // validated, with decorations added that change no interface; the
    // bind group layout is the one the WGSL declares (the layout test in
    // `shaders.rs` holds the two together).
    unsafe { context.device.create_shader_module_passthrough(descriptor) }
}

/// A buffer bound at a binding number.
pub type Bound<'a> = (u32, &'a wgpu::Buffer);

/// Whether a pass binds the uploaded world's arrays (the ray queries and
/// formula (1) trace; making shading points does not).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum WorldUse {
    Traces,
    None,
}

/// What one recording of a pass runs over: the world (its arrays, for the
/// passes that trace, and its parameters), how many items (at most
/// [`BATCH`]: one invocation each), how many lights and how many light
/// layers (the `light` AOV's).
#[derive(Clone, Copy)]
pub struct Dispatch<'a> {
    scene: &'a GpuScene,
    items: usize,
    lights: u32,
    layers: u32,
}

impl<'a> Dispatch<'a> {
    pub fn new(scene: &'a GpuScene, items: usize) -> Dispatch<'a> {
        Dispatch {
            scene,
            items,
            lights: 0,
            layers: 0,
        }
    }

    pub fn with_lights(self, lights: u32) -> Dispatch<'a> {
        Dispatch { lights, ..self }
    }

    pub fn with_layers(self, layers: usize) -> Dispatch<'a> {
        let layers = layers as u32;
        Dispatch { layers, ..self }
    }
}

/// A compute pipeline and its bind group layout.
pub struct WorldPass {
    entry: Entry,
    world: WorldUse,
    layout: wgpu::BindGroupLayout,
    pipeline: wgpu::ComputePipeline,
}

impl WorldPass {
    /// The pipeline of `entry`, binding its items, its answers, the world
    /// as `world` says, the read-only arrays at `reads` and further
    /// writable ones at `writes`.
    pub fn new(
        context: &GpuContext,
        entry: Entry,
        world: WorldUse,
        reads: &[u32],
        writes: &[u32],
    ) -> WorldPass {
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
            buffer(PARAMS, wgpu::BufferBindingType::Uniform),
            buffer(ITEMS, read_only),
            buffer(
                ANSWERS,
                wgpu::BufferBindingType::Storage { read_only: false },
            ),
        ];
        let world_bindings: &[u32] = match world {
            WorldUse::Traces => &GpuScene::BINDINGS,
            WorldUse::None => &[],
        };
        let bindings = world_bindings.iter().chain(reads);
        entries.extend(bindings.map(|&binding| buffer(binding, read_only)));
        let writable = wgpu::BufferBindingType::Storage { read_only: false };
        entries.extend(writes.iter().map(|&binding| buffer(binding, writable)));
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(entry.name()),
            entries: &entries,
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(entry.name()),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let module = shader_module(context, entry, &entries);
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
            world,
            layout,
            pipeline,
        }
    }

    /// Records the pass into `encoder` as `dispatch` says, with `reads`
    /// bound (the items at [`ITEMS`] among them, and any further writable
    /// arrays) and the answers written to `answers`.
    pub fn record(
        &self,
        context: &GpuContext,
        encoder: &mut wgpu::CommandEncoder,
        dispatch: Dispatch,
        reads: &[Bound],
        answers: &wgpu::Buffer,
    ) {
        let Dispatch {
            scene,
            items: count,
            lights,
            layers,
        } = dispatch;
        debug_assert!(count <= BATCH);
        let device = &context.device;
        let params = scene.params(count as u32, lights, layers);
        let params = context.upload(
            "pass params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::UNIFORM,
        );
        let world = match self.world {
            WorldUse::Traces => scene.buffers().to_vec(),
            WorldUse::None => Vec::new(),
        };
        let entries: Vec<wgpu::BindGroupEntry> = [(PARAMS, &params), (ANSWERS, answers)]
            .into_iter()
            .chain(reads.iter().copied())
            .chain(world)
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
        let mut pass = encoder.begin_compute_pass(&Default::default());
        pass.set_pipeline(&self.pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        pass.dispatch_workgroups((count as u32).div_ceil(WORKGROUP), 1, 1);
    }

    /// Runs the pass over `items` (at most [`BATCH`]) with `inputs` bound
    /// as [`WorldPass::new`] declared them, `light_count` lights; one
    /// `Answer` per item.
    pub fn run<Item: Pod, Answer: Pod>(
        &self,
        context: &GpuContext,
        scene: &GpuScene,
        items: &[Item],
        inputs: &[Bound],
        light_count: u32,
    ) -> Result<Vec<Answer>, GpuError> {
        context.checked(self.entry.name(), || {
            let items_buffer = super::scene::storage(context, "pass items", items)?;
            let answers = answer_buffer::<Answer>(context, "pass answers", items.len())?;
            let mut encoder = context.device.create_command_encoder(&Default::default());
            let reads: Vec<Bound> = [(ITEMS, &items_buffer)]
                .into_iter()
                .chain(inputs.iter().copied())
                .collect();
            let dispatch = Dispatch::new(scene, items.len()).with_lights(light_count);
            self.record(context, &mut encoder, dispatch, &reads, &answers);
            read_back(context, encoder, &answers, items.len())
        })
    }
}

/// A storage buffer for `count` answers of type `Answer` (one at least:
/// a binding cannot be empty, zeroed as wgpu zeroes every buffer), which
/// a later pass may read, a copy may fill and [`read_back`] may copy out.
pub fn answer_buffer<Answer: Pod>(
    context: &GpuContext,
    what: &'static str,
    count: usize,
) -> Result<wgpu::Buffer, GpuError> {
    let bytes = (count.max(1) * size_of::<Answer>()) as u64;
    context.check_binding(what, bytes)?;
    Ok(context.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some(what),
        size: bytes,
        usage: wgpu::BufferUsages::STORAGE
            | wgpu::BufferUsages::COPY_SRC
            | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    }))
}

/// Submits `encoder` with a copy of `buffer`'s first `count` items added,
/// waits, and returns them.
pub fn read_back<Out: Pod>(
    context: &GpuContext,
    mut encoder: wgpu::CommandEncoder,
    buffer: &wgpu::Buffer,
    count: usize,
) -> Result<Vec<Out>, GpuError> {
    let bytes = (count.max(1) * size_of::<Out>()) as u64;
    let staging = context.device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("readback"),
        size: bytes,
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    encoder.copy_buffer_to_buffer(buffer, 0, &staging, 0, bytes);
    context.traffic.waited(bytes);
    context.queue.submit([encoder.finish()]);
    let slice = staging.slice(..);
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
