//! The one wgpu device of a run: found once, with the features and limits
//! the ray queries need, and described once for the user.

use std::fmt;
use std::path::Path;

use super::pass_timer::PassTimer;
use super::pipeline_cache::{self, PipelineCache};
use super::shaders::Arithmetic;
use super::traffic::Traffic;

/// Storage buffers one pass binds at most: formula (2)'s, which binds its
/// parameters (storage, not uniform: see `common.wgsl`), its points and
/// answers, the flat world's seven arrays, the lights, the points'
/// reaching lights, the mask pool, its directory, its tile summaries and
/// its counters.
pub const STORAGE_BUFFERS: u32 = 16;
/// Storage buffers formula (2) binds when it keeps its terms per light
/// layer (`--aovs light`): one more, the points' layer sums. An adapter
/// that binds fewer renders everything else.
pub const LAYERED_STORAGE_BUFFERS: u32 = STORAGE_BUFFERS + 1;

#[derive(Debug, thiserror::Error)]
pub enum GpuError {
    #[error(
        "--backend gpu: no GPU adapter with compute shaders was found \
         (on Linux without a GPU, Debian's mesa-vulkan-drivers gives a software one)"
    )]
    NoAdapter,
    #[error("--backend gpu: the adapter '{adapter}' refused a device: {reason}")]
    Device { adapter: String, reason: String },
    #[error("--backend gpu: the adapter '{adapter}' binds {limit} storage buffers per shader, the GPU passes need {STORAGE_BUFFERS}")]
    TooFewBuffers { adapter: String, limit: u32 },
    #[error("--backend gpu: the adapter '{adapter}' binds {limit} storage buffers per shader, the GPU's light layers (--aovs light) need {LAYERED_STORAGE_BUFFERS}; render them with --backend cpu")]
    TooFewBuffersForLayers { adapter: String, limit: u32 },
    #[error("--backend gpu: {what} takes {bytes} bytes, more than the {limit} bytes the adapter '{adapter}' binds at once")]
    TooLarge {
        what: &'static str,
        bytes: u64,
        limit: u64,
        adapter: String,
    },
    #[error("--backend gpu: {what} is {depth} levels deep, deeper than the {limit} the GPU traversal's stack holds")]
    TooDeep {
        what: &'static str,
        depth: usize,
        limit: usize,
    },
    /// The adapter ended shader loops early (lavapipe's budget of 65,535
    /// loop iterations per invocation): its frame would be wrong.
    #[error("--backend gpu: the adapter '{adapter}' cut the light mesh's shader loops short at {points} points (it ends loops after a fixed number of iterations); render this frame with --backend cpu, or lighten each point's work (--penumbra fixed traces no rays per lamp)")]
    LoopsCutShort { adapter: String, points: u32 },
    #[error("--backend gpu: reading results back failed: {0}")]
    Readback(String),
    /// The device refused work (out of memory, or a limit the checks
    /// before it missed).
    #[error("--backend gpu: the adapter '{adapter}' failed {what}: {reason}")]
    Refused {
        what: &'static str,
        adapter: String,
        reason: String,
    },
}

/// The device, its queue, and what the shaders may count on.
pub struct GpuContext {
    pub device: wgpu::Device,
    pub queue: wgpu::Queue,
    pub info: wgpu::AdapterInfo,
    pub limits: wgpu::Limits,
    /// Whether the adapter has f64 in shaders: then quotients and roots
    /// round as on the CPU (see `shaders/exact_f64.wgsl`).
    pub f64: bool,
    /// Whether the passes go to the driver as our own SPIR-V, every float
    /// operation marked `NoContraction` (Vulkan; see `super::spirv`).
    pub own_spirv: bool,
    /// Both, which makes the arithmetic `Arithmetic::ExactUncontracted`:
    /// then every answer is the CPU's to the bit.
    pub exact: bool,
    /// What crossed the bus so far.
    pub traffic: Traffic,
    /// How long each pass ran on the GPU, where the adapter can say.
    pub pass_timer: Option<PassTimer>,
    /// The pipelines made so far, and the driver's cache they go through.
    pub pipelines: PipelineCache,
}

impl GpuContext {
    /// The first adapter of Vulkan, Metal or D3D12 that wgpu prefers for
    /// high performance (`WGPU_ADAPTER_NAME` picks another).
    pub fn new() -> Result<GpuContext, GpuError> {
        let mut descriptor = wgpu::InstanceDescriptor::new_without_display_handle_from_env();
        descriptor.backends &= wgpu::Backends::PRIMARY;
        let instance = wgpu::Instance::new(descriptor);
        let options = wgpu::RequestAdapterOptions {
            power_preference: wgpu::PowerPreference::HighPerformance,
            ..Default::default()
        };
        let adapter = pollster::block_on(instance.request_adapter(&options))
            .map_err(|_| GpuError::NoAdapter)?;
        let info = adapter.get_info();
        let available = adapter.limits();
        if available.max_storage_buffers_per_shader_stage < STORAGE_BUFFERS {
            return Err(GpuError::TooFewBuffers {
                adapter: info.name,
                limit: available.max_storage_buffers_per_shader_stage,
            });
        }
        let f64 = adapter.features().contains(wgpu::Features::SHADER_F64);
        let own_spirv = info.backend == wgpu::Backend::Vulkan
            && adapter
                .features()
                .contains(wgpu::Features::PASSTHROUGH_SHADERS);
        let mut features = wgpu::Features::empty();
        features.set(wgpu::Features::SHADER_F64, f64);
        features.set(wgpu::Features::PASSTHROUGH_SHADERS, own_spirv);
        for wanted in [
            wgpu::Features::PIPELINE_CACHE,
            wgpu::Features::TIMESTAMP_QUERY,
        ] {
            features.set(wanted, adapter.features().contains(wanted));
        }
        let storage_buffers =
            (available.max_storage_buffers_per_shader_stage).min(LAYERED_STORAGE_BUFFERS);
        let limits = wgpu::Limits {
            max_storage_buffers_per_shader_stage: storage_buffers,
            max_storage_buffer_binding_size: available.max_storage_buffer_binding_size,
            max_buffer_size: available.max_buffer_size,
            ..wgpu::Limits::downlevel_defaults()
        };
        let descriptor = wgpu::DeviceDescriptor {
            label: Some("lmanim"),
            required_features: features,
            required_limits: limits.clone(),
            ..Default::default()
        };
        let (device, queue) =
            pollster::block_on(adapter.request_device(&descriptor)).map_err(|error| {
                GpuError::Device {
                    adapter: info.name.clone(),
                    reason: error.to_string(),
                }
            })?;
        let pass_timer = PassTimer::new(&device, &queue);
        Ok(GpuContext {
            device,
            queue,
            info,
            limits,
            f64,
            own_spirv,
            exact: Arithmetic::for_adapter(f64, own_spirv) == Arithmetic::ExactUncontracted,
            traffic: Traffic::default(),
            pass_timer,
            pipelines: PipelineCache::none(),
        })
    }

    /// How the shaders round on this adapter (see [`GpuContext::f64`]
    /// and [`GpuContext::own_spirv`]).
    pub fn arithmetic(&self) -> Arithmetic {
        Arithmetic::for_adapter(self.f64, self.own_spirv)
    }

    /// Makes the pipelines from now on through the driver's cache kept in
    /// `dir` (loaded from it now, saved by [`PipelineCache::save`]).
    pub fn keep_pipelines_in(&mut self, dir: &Path) {
        let shaders = pipeline_cache::shader_hash(self.arithmetic(), self.own_spirv);
        self.pipelines = PipelineCache::open(&self.device, &self.info, dir, shaders);
    }

    /// Whether the adapter is a CPU (lavapipe, WARP, SwiftShader): its
    /// timings say nothing of a GPU's.
    pub fn is_software(&self) -> bool {
        self.info.device_type == wgpu::DeviceType::Cpu
    }

    /// Runs `work` (buffer creation, passes) with the device's errors
    /// caught and returned as [`GpuError::Refused`] naming `what`: wgpu
    /// would otherwise hand them to its default handler, which panics.
    pub fn checked<T, E: From<GpuError>>(
        &self,
        what: &'static str,
        work: impl FnOnce() -> Result<T, E>,
    ) -> Result<T, E> {
        let memory = self.device.push_error_scope(wgpu::ErrorFilter::OutOfMemory);
        let validation = self.device.push_error_scope(wgpu::ErrorFilter::Validation);
        let done = work();
        let invalid = pollster::block_on(validation.pop());
        let exhausted = pollster::block_on(memory.pop());
        match invalid.or(exhausted) {
            Some(error) => Err(GpuError::Refused {
                what,
                adapter: self.info.name.clone(),
                reason: error.to_string().replace('\n', " "),
            }
            .into()),
            None => done,
        }
    }

    /// Fails in one line where the device binds too few storage buffers
    /// for formula (2) to keep its terms per light layer.
    pub fn check_light_layers(&self) -> Result<(), GpuError> {
        let limit = self.limits.max_storage_buffers_per_shader_stage;
        if limit < LAYERED_STORAGE_BUFFERS {
            return Err(GpuError::TooFewBuffersForLayers {
                adapter: self.info.name.clone(),
                limit,
            });
        }
        Ok(())
    }

    /// Fails with the adapter's limit when `bytes` cannot be bound at once.
    pub fn check_binding(&self, what: &'static str, bytes: u64) -> Result<(), GpuError> {
        let limit = self.limits.max_storage_buffer_binding_size;
        if bytes > limit {
            return Err(GpuError::TooLarge {
                what,
                bytes,
                limit,
                adapter: self.info.name.clone(),
            });
        }
        Ok(())
    }
}

impl fmt::Display for GpuContext {
    fn fmt(&self, f: &mut fmt::Formatter) -> fmt::Result {
        let info = &self.info;
        write!(f, "{} ({:?}", info.name, info.backend)?;
        if !info.driver.is_empty() {
            write!(f, ", {} {}", info.driver, info.driver_info)?;
        }
        if self.is_software() {
            write!(f, ", software")?;
        }
        if !self.f64 {
            write!(f, ", no f64: shared-edge ties may differ from the CPU")?;
        } else if !self.own_spirv {
            write!(
                f,
                ", WGSL to the driver: fused products may differ from the CPU"
            )?;
        }
        write!(f, ")")
    }
}
