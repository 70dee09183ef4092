//! One compute pass, end to end: its pipeline and bind group layout, its
//! dispatch recorded into a command encoder (one invocation per item,
//! counted on the CPU or, for a level the compaction made, on the GPU),
//! and [`WorldPass::run`], the round trip for a single pass. A pass reads
//! its items (binding [`ITEMS`]), optionally the uploaded world's arrays,
//! and further read-only arrays, and writes one answer per item (binding
//! [`ANSWERS`]). Passes that feed each other are recorded into one
//! encoder and their intermediate answers never leave the GPU.

use std::sync::OnceLock;

use bytemuck::Pod;

use super::context::{GpuContext, GpuError};
use super::contract::{ANSWERS, ITEMS, PARAMS, WORKGROUP};
use super::recording::Recording;
use super::scene::GpuScene;
use super::shaders::{self, Entry};
use super::spirv;

/// Items per dispatch: within the 65535 workgroups a dispatch may have in
/// one dimension, and a few tens of MiB of items.
pub const BATCH: usize = 1 << 20;

/// The size of each array an empty dispatch binds: more than the
/// parameters and any one record a shader reads from an array, as the
/// layout test in `shaders.rs` sizes them.
const EMPTY_BINDING_BYTES: u64 = 4096;

/// The pass's shader: our own SPIR-V where the context takes it (every
/// float operation kept from fusing), else WGSL for wgpu to translate.
fn shader_module(
    context: &GpuContext,
    entry: Entry,
    layout: &[wgpu::BindGroupLayoutEntry],
) -> wgpu::ShaderModule {
    let arithmetic = context.arithmetic();
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
    let words = spirv::compile(&source, entry.name(), arithmetic.capabilities(), &bindings)
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
    /// Where the GPU wrote the item count, at most `items`, and the
    /// workgroups for it
    /// ([`super::contract::LEVEL_LENGTH_WORDS`] words), for a level the CPU has not
    /// counted.
    length: Option<&'a wgpu::Buffer>,
    lights: u32,
    layers: u32,
}

impl<'a> Dispatch<'a> {
    pub fn new(scene: &'a GpuScene, items: usize) -> Dispatch<'a> {
        Dispatch {
            scene,
            items,
            length: None,
            lights: 0,
            layers: 0,
        }
    }

    /// Over at most `bound` items, as many as the GPU wrote into `length`.
    pub fn counted_on_gpu(
        scene: &'a GpuScene,
        bound: usize,
        length: &'a wgpu::Buffer,
    ) -> Dispatch<'a> {
        Dispatch {
            length: Some(length),
            ..Dispatch::new(scene, bound)
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

/// A compute pass: its bind group layout, made with the pass, and its
/// pipeline, compiled the first time the pass is prepared or recorded
/// (compiling is what a fresh machine waits for: see
/// [`super::pipeline_cache`]).
pub struct WorldPass {
    entry: Entry,
    world: WorldUse,
    bindings: Vec<wgpu::BindGroupLayoutEntry>,
    layout: wgpu::BindGroupLayout,
    pipeline: OnceLock<wgpu::ComputePipeline>,
}

impl WorldPass {
    /// The pass of `entry`, binding its items, its answers, the world
    /// as `world` says, the read-only arrays at `reads` and further
    /// writable ones at `writes`.
    pub fn new(
        context: &GpuContext,
        entry: Entry,
        world: WorldUse,
        reads: &[u32],
        writes: &[u32],
    ) -> WorldPass {
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
        let mut bindings = vec![
            buffer(PARAMS, read_only),
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
        let reads = world_bindings.iter().chain(reads);
        bindings.extend(reads.map(|&binding| buffer(binding, read_only)));
        let writable = wgpu::BufferBindingType::Storage { read_only: false };
        bindings.extend(writes.iter().map(|&binding| buffer(binding, writable)));
        let layout = (context.device).create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some(entry.name()),
            entries: &bindings,
        });
        WorldPass {
            entry,
            world,
            bindings,
            layout,
            pipeline: OnceLock::new(),
        }
    }

    /// The name the pipeline goes by in stats and in the pipeline cache.
    pub fn name(&self) -> &'static str {
        self.entry.pipeline_name()
    }

    /// The size of the module the driver compiles, the measure of how
    /// long it takes.
    pub fn source_bytes(&self, context: &GpuContext) -> usize {
        shaders::source(self.entry, context.arithmetic()).len()
    }

    /// Compiles the pipeline now unless it is compiled, and runs it once
    /// over no items: some drivers (lavapipe) compile at a pipeline's
    /// first dispatch, and a run should wait for that here, where it is
    /// timed and reported, not inside its first frame.
    pub fn prepare(&self, context: &GpuContext) {
        self.pipeline.get_or_init(|| {
            context.pipelines.make(self.name(), |cache| {
                let pipeline = self.compile(context, cache);
                self.run_empty(context, &pipeline);
                pipeline
            })
        });
    }

    /// The pipeline, compiled now if it is not yet.
    fn pipeline(&self, context: &GpuContext) -> &wgpu::ComputePipeline {
        self.pipeline.get_or_init(|| {
            (context.pipelines).make(self.name(), |cache| self.compile(context, cache))
        })
    }

    fn compile(
        &self,
        context: &GpuContext,
        cache: Option<&wgpu::PipelineCache>,
    ) -> wgpu::ComputePipeline {
        let device = &context.device;
        let name = self.entry.name();
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some(name),
            bind_group_layouts: &[Some(&self.layout)],
            immediate_size: 0,
        });
        let module = shader_module(context, self.entry, &self.bindings);
        device.create_compute_pipeline(&wgpu::ComputePipelineDescriptor {
            label: Some(name),
            layout: Some(&pipeline_layout),
            module: &module,
            entry_point: Some(name),
            compilation_options: Default::default(),
            cache,
        })
    }

    /// Dispatches `pipeline` once with zero items (every entry point
    /// returns at once: the parameters' item count is zero), every
    /// binding bound to a zeroed buffer (one shared by the read-only
    /// ones), and waits. A refusal only means the driver compiles later:
    /// it is logged, not returned.
    fn run_empty(&self, context: &GpuContext, pipeline: &wgpu::ComputePipeline) {
        let device = &context.device;
        let zeroed = || {
            device.create_buffer(&wgpu::BufferDescriptor {
                label: Some("empty dispatch"),
                size: EMPTY_BINDING_BYTES,
                usage: wgpu::BufferUsages::STORAGE,
                mapped_at_creation: false,
            })
        };
        let shared = zeroed();
        let writable = |ty: &wgpu::BindingType| {
            matches!(
                ty,
                wgpu::BindingType::Buffer {
                    ty: wgpu::BufferBindingType::Storage { read_only: false },
                    ..
                }
            )
        };
        let own: Vec<Option<wgpu::Buffer>> = (self.bindings.iter())
            .map(|binding| writable(&binding.ty).then(zeroed))
            .collect();
        let entries: Vec<wgpu::BindGroupEntry> = (self.bindings.iter().zip(&own))
            .map(|(binding, own)| wgpu::BindGroupEntry {
                binding: binding.binding,
                resource: own.as_ref().unwrap_or(&shared).as_entire_binding(),
            })
            .collect();
        let ran = context.checked("an empty dispatch", || {
            let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some(self.entry.name()),
                layout: &self.layout,
                entries: &entries,
            });
            let mut encoder = device.create_command_encoder(&Default::default());
            {
                let mut pass = encoder.begin_compute_pass(&Default::default());
                pass.set_pipeline(pipeline);
                pass.set_bind_group(0, &bind_group, &[]);
                pass.dispatch_workgroups(1, 1, 1);
            }
            context.queue.submit([encoder.finish()]);
            (device.poll(wgpu::PollType::wait_indefinitely()))
                .map_err(|error| GpuError::Readback(error.to_string()))
        });
        if let Err(error) = ran {
            log::debug!("{}: {error}", self.name());
        }
    }

    /// Records the pass into `encoder` as `dispatch` says, with `reads`
    /// bound (the items at [`ITEMS`] among them, and any further writable
    /// arrays) and the answers written to `answers`. Where the GPU counts
    /// the items, a copy puts its count into the parameters and the
    /// dispatch takes its workgroups from the same words.
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
            length,
            lights,
            layers,
        } = dispatch;
        debug_assert!(count <= BATCH);
        let device = &context.device;
        let params = scene.params(count as u32, lights, layers);
        let params = context.upload(
            "pass params",
            bytemuck::bytes_of(&params),
            wgpu::BufferUsages::STORAGE | wgpu::BufferUsages::COPY_DST,
        );
        if let Some(length) = length {
            encoder.copy_buffer_to_buffer(length, 0, &params, 0, size_of::<u32>() as u64);
        }
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
        let pipeline = self.pipeline(context);
        let timer = context.pass_timer.as_ref();
        let mut pass = encoder.begin_compute_pass(&wgpu::ComputePassDescriptor {
            label: Some(self.name()),
            timestamp_writes: timer.and_then(|timer| timer.writes(self.name())),
        });
        pass.set_pipeline(pipeline);
        pass.set_bind_group(0, &bind_group, &[]);
        match length {
            Some(length) => pass.dispatch_workgroups_indirect(length, size_of::<u32>() as u64),
            None => pass.dispatch_workgroups((count as u32).div_ceil(WORKGROUP), 1, 1),
        }
    }

    /// Runs the pass over `items` (at most [`BATCH`]) with `inputs` bound
    /// as [`WorldPass::new`] declared them, `light_count` lights, and
    /// waits for its answers, one `Answer` per item, which the CPU needs
    /// for what `why` says.
    pub fn run<Item: Pod, Answer: Pod>(
        &self,
        why: &'static str,
        context: &GpuContext,
        scene: &GpuScene,
        items: &[Item],
        inputs: &[Bound],
        light_count: u32,
    ) -> Result<Vec<Answer>, GpuError> {
        context.checked(self.entry.name(), || {
            let items_buffer = super::scene::storage(context, "pass items", items)?;
            let answers = answer_buffer::<Answer>(context, "pass answers", items.len())?;
            let mut recording = Recording::new(context);
            let reads: Vec<Bound> = [(ITEMS, &items_buffer)]
                .into_iter()
                .chain(inputs.iter().copied())
                .collect();
            let dispatch = Dispatch::new(scene, items.len()).with_lights(light_count);
            self.record(context, recording.encoder(), dispatch, &reads, &answers);
            recording.read_back(why, &answers, items.len())
        })
    }
}

/// A storage buffer for `count` answers of type `Answer` (one at least:
/// a binding cannot be empty, zeroed as wgpu zeroes every buffer), which
/// a later pass may read, a copy may fill and a [`Recording`] may copy
/// out.
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
