//! What crosses between the CPU and the GPU in a run, counted where it
//! crosses: every upload goes through [`GpuContext::upload`] or
//! [`GpuContext::write`], and every blocking read-back through
//! `recording::Recording::wait`, so these counters see all of it. A frame's share is
//! the difference of two snapshots ([`Traffic::since`]), reported as the
//! `gpu` object of `--stats`: the measure the GPU-resident light mesh
//! (issue 33) is held to, a steady frame waiting on the GPU at most twice.

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use serde::Serialize;
use wgpu::util::DeviceExt;

use super::context::GpuContext;
use super::pass_timer::PassTimes;
use super::pipeline_cache::PipelineMade;

/// A frame's `gpu` object in `--stats`: its traffic, the time of its
/// passes on the GPU, and the pipelines compiled for it (the first
/// frame's, mostly; see `pipelines`).
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct GpuFrameStats {
    #[serde(flatten)]
    pub traffic: GpuTraffic,
    #[serde(flatten)]
    pub passes: PassTimes,
    pub pipelines: Vec<PipelineMade>,
}

/// Running totals since the device was made.
#[derive(Debug, Default)]
pub struct Traffic {
    waits: AtomicU64,
    bytes_up: AtomicU64,
    bytes_down: AtomicU64,
    segments_traced: AtomicU64,
    wait_nanos: AtomicU64,
}

/// One frame's traffic (or a run's, from its first snapshot).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct GpuTraffic {
    /// Blocking read-backs: each submits what was recorded and waits for
    /// the GPU to finish it, bringing back one or several buffers.
    pub waits: u64,
    /// Bytes written into GPU buffers (uploads, uniforms, mask bricks).
    pub bytes_up: u64,
    /// Bytes read back.
    pub bytes_down: u64,
    /// The light mesh's node-to-light segments the GPU traced for the
    /// fill (`super::fill`): the fill's work that crossed to the GPU.
    pub segments_traced: u64,
    /// Seconds the CPU spent blocked in those waits: from each wait's
    /// call (its copies recorded, then submitted) to holding the bytes. A frame's `seconds` less this is what the CPU
    /// spent on its own work, which on a fast GPU is most of the frame.
    pub wait_seconds: f64,
}

impl Traffic {
    pub fn snapshot(&self) -> GpuTraffic {
        GpuTraffic {
            waits: self.waits.load(Ordering::Relaxed),
            bytes_up: self.bytes_up.load(Ordering::Relaxed),
            bytes_down: self.bytes_down.load(Ordering::Relaxed),
            segments_traced: self.segments_traced.load(Ordering::Relaxed),
            wait_seconds: seconds(self.wait_nanos.load(Ordering::Relaxed)),
        }
    }

    /// What crossed since `before` was taken.
    pub fn since(&self, before: GpuTraffic) -> GpuTraffic {
        let now = self.snapshot();
        GpuTraffic {
            waits: now.waits - before.waits,
            bytes_up: now.bytes_up - before.bytes_up,
            bytes_down: now.bytes_down - before.bytes_down,
            segments_traced: now.segments_traced - before.segments_traced,
            wait_seconds: now.wait_seconds - before.wait_seconds,
        }
    }

    /// Counts one blocking read-back of `bytes`, which held the CPU for
    /// `blocked`.
    pub fn waited(&self, bytes: u64, blocked: Duration) {
        self.waits.fetch_add(1, Ordering::Relaxed);
        self.bytes_down.fetch_add(bytes, Ordering::Relaxed);
        let nanos = u64::try_from(blocked.as_nanos()).unwrap_or(u64::MAX);
        self.wait_nanos.fetch_add(nanos, Ordering::Relaxed);
    }

    /// Counts `segments` traced for the fill.
    pub fn traced(&self, segments: u64) {
        self.segments_traced.fetch_add(segments, Ordering::Relaxed);
    }

    fn sent(&self, bytes: u64) {
        self.bytes_up.fetch_add(bytes, Ordering::Relaxed);
    }
}

fn seconds(nanos: u64) -> f64 {
    Duration::from_nanos(nanos).as_secs_f64()
}

impl GpuContext {
    /// A buffer made holding `contents`, counted as uploaded.
    pub fn upload(
        &self,
        label: &'static str,
        contents: &[u8],
        usage: wgpu::BufferUsages,
    ) -> wgpu::Buffer {
        self.traffic.sent(contents.len() as u64);
        (self.device).create_buffer_init(&wgpu::util::BufferInitDescriptor {
            label: Some(label),
            contents,
            usage,
        })
    }

    /// Writes `bytes` into `buffer` at `offset` (queued with the next
    /// submission), counted as uploaded.
    pub fn write(&self, buffer: &wgpu::Buffer, offset: u64, bytes: &[u8]) {
        self.traffic.sent(bytes.len() as u64);
        self.queue.write_buffer(buffer, offset, bytes);
    }
}
