//! The run's pipelines, each compiled once, timed, and made through the
//! driver's pipeline cache, which lmanim keeps in its cache folder
//! between runs ([`super::pipeline_file`]).
//!
//! Compiling is most of what a fresh machine waits for before its first
//! GPU frame (74 s on an H100 whose driver cache was empty, BENCHMARKS.md):
//! a farm node that finds the file, which `lmanim warm --backend gpu`
//! writes, hands the driver its compiled pipelines back instead. Where
//! the adapter keeps no pipeline cache (wgpu's `PIPELINE_CACHE` is
//! Vulkan's), or the run keeps no cache folder (`--no-cache`), pipelines
//! are compiled from scratch, and still timed.

use std::collections::{BTreeSet, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use serde::Serialize;
use xxhash_rust::xxh3::Xxh3;

use super::pipeline_file::StoredPipelines;
use super::shaders::{self, Arithmetic, Entry};
use crate::output::{self, OutputError};

/// One pipeline made in a run, for `--stats` (`gpu.pipelines`).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct PipelineMade {
    pub name: &'static str,
    /// Wall time of compiling it (with its first, empty dispatch where the
    /// run prepared it: see `WorldPass::prepare`).
    pub ms: f64,
    /// Whether the cache file the run started from held it: then the
    /// driver had its compiled code at hand.
    pub cached: bool,
}

pub struct PipelineCache {
    driver: Option<wgpu::PipelineCache>,
    /// Where the cache is kept, for an adapter that keeps one.
    file: Option<PathBuf>,
    /// [`shader_hash`] of the run's shaders.
    shaders: u64,
    /// The pipelines the loaded file held.
    held: HashSet<&'static str>,
    made: Mutex<Made>,
}

#[derive(Default)]
struct Made {
    /// Made since the last [`PipelineCache::take_made`].
    log: Vec<PipelineMade>,
    /// Every pipeline the driver's cache holds now.
    names: BTreeSet<&'static str>,
    /// Whether some pipeline was made since the file was last written.
    unsaved: bool,
}

impl PipelineCache {
    /// No cache: every pipeline is compiled from scratch.
    pub fn none() -> PipelineCache {
        PipelineCache {
            driver: None,
            file: None,
            shaders: 0,
            held: HashSet::new(),
            made: Mutex::default(),
        }
    }

    /// The cache kept in `dir` for `info`'s adapter, loaded from its file
    /// where one is there. A file that cannot be read, or is not a
    /// pipeline cache, is ignored with a warning naming it; one made by
    /// other shaders or another adapter silently gives way to a new one.
    pub fn open(
        device: &wgpu::Device,
        info: &wgpu::AdapterInfo,
        dir: &Path,
        shaders: u64,
    ) -> PipelineCache {
        let Some(key) = (device.features())
            .contains(wgpu::Features::PIPELINE_CACHE)
            .then(|| wgpu::util::pipeline_cache_key(info))
            .flatten()
        else {
            return PipelineCache::none();
        };
        let file = dir.join(format!("gpu-pipelines-{key}.bin"));
        let stored = read(&file).filter(|stored| stored.shaders == shaders);
        let data = stored.as_ref().map(|stored| stored.data.as_slice());
        // SAFETY: wgpu asks that `data` come from `PipelineCache::get_data`;
        // what `save` wrote came from there, and the envelope's checksum
        // refuses a damaged file. wgpu checks the data's header against
        // this adapter and driver, and `fallback` makes a cache of anything
        // it refuses an empty one.
        let driver = unsafe {
            device.create_pipeline_cache(&wgpu::PipelineCacheDescriptor {
                label: Some("lmanim pipelines"),
                data,
                fallback: true,
            })
        };
        let held: HashSet<&'static str> = (stored.iter())
            .flat_map(|stored| &stored.names)
            .filter_map(|name| pipeline_named(name))
            .collect();
        let made = Made {
            names: held.iter().copied().collect(),
            ..Made::default()
        };
        PipelineCache {
            driver: Some(driver),
            file: Some(file),
            shaders,
            held,
            made: Mutex::new(made),
        }
    }

    /// Makes the pipeline `name` by `compile`, through the driver's cache
    /// where there is one, and logs how long it took.
    pub fn make<P>(
        &self,
        name: &'static str,
        compile: impl FnOnce(Option<&wgpu::PipelineCache>) -> P,
    ) -> P {
        let started = Instant::now();
        let pipeline = compile(self.driver.as_ref());
        let made = PipelineMade {
            name,
            ms: started.elapsed().as_secs_f64() * 1e3,
            cached: self.held.contains(name),
        };
        let mut log = self.made();
        log.unsaved |= log.names.insert(name);
        log.log.push(made);
        pipeline
    }

    /// The log of pipelines made. A thread that panicked holding it left
    /// it whole (each edit is one insert or push), so a poisoned lock is
    /// taken as it is: losing the log must not stop a render.
    fn made(&self) -> std::sync::MutexGuard<'_, Made> {
        self.made
            .lock()
            .unwrap_or_else(|poisoned| poisoned.into_inner())
    }

    /// The pipelines made since the last call, in the order they were.
    pub fn take_made(&self) -> Vec<PipelineMade> {
        let mut made = self.made();
        std::mem::take(&mut made.log)
    }

    /// Writes the cache file, atomically, if a pipeline it lacks was made
    /// since it was read or written.
    pub fn save(&self) -> Result<(), OutputError> {
        let (Some(driver), Some(file)) = (&self.driver, &self.file) else {
            return Ok(());
        };
        let mut made = self.made();
        if !made.unsaved {
            return Ok(());
        }
        let Some(data) = driver.get_data() else {
            return Ok(());
        };
        let stored = StoredPipelines {
            shaders: self.shaders,
            names: made.names.iter().map(|name| name.to_string()).collect(),
            data,
        };
        let bytes = stored.to_bytes();
        output::write_atomically(file, |writer| {
            use std::io::Write;
            writer
                .write_all(&bytes)
                .map_err(|source| OutputError::Write {
                    path: file.clone(),
                    source,
                })
        })?;
        made.unsaved = false;
        Ok(())
    }
}

/// What `file` holds, or None where there is no file or it is damaged
/// (with a warning naming it).
fn read(file: &Path) -> Option<StoredPipelines> {
    let bytes = match std::fs::read(file) {
        Ok(bytes) => bytes,
        Err(error) if error.kind() == std::io::ErrorKind::NotFound => return None,
        Err(error) => {
            log::warn!(
                "ignoring the GPU pipeline cache {}: {error}",
                file.display()
            );
            return None;
        }
    };
    StoredPipelines::from_bytes(&bytes)
        .map_err(|fault| {
            log::warn!(
                "ignoring the GPU pipeline cache {}: {fault}",
                file.display()
            )
        })
        .ok()
}

/// The pipeline named `name`, as [`Entry::pipeline_name`] names it.
fn pipeline_named(name: &str) -> Option<&'static str> {
    (Entry::ALL.iter())
        .map(|entry| entry.pipeline_name())
        .find(|known| *known == name)
}

/// What identifies the pipelines a run makes besides the adapter: lmanim's
/// version and every module as it goes to the driver.
pub fn shader_hash(arithmetic: Arithmetic, own_spirv: bool) -> u64 {
    let mut hasher = Xxh3::new();
    hasher.update(env!("CARGO_PKG_VERSION").as_bytes());
    hasher.update(&[own_spirv as u8]);
    for entry in Entry::ALL {
        hasher.update(shaders::source(entry, arithmetic).as_bytes());
    }
    hasher.digest()
}
