//! GPU work as a recording, as vello records a frame: passes and copies
//! go into [`Recording::encoder`], [`Recording::submit`] sends what is
//! recorded without waiting, and the CPU blocks only at
//! [`Recording::wait`] (or its one-buffer form [`Recording::read_back`]),
//! whose first argument says what the CPU needs and why it cannot go on
//! without it. So a frame's waits are its calls of those two, each named
//! at its call site, and `--stats` counts them as `gpu.waits`
//! ([`super::traffic`]). What several buffers give back at one point
//! ([`Downloads`]) comes back in one copy and one map.

use std::marker::PhantomData;
use std::time::Instant;

use bytemuck::Pod;

use super::context::{GpuContext, GpuError};

/// Work recorded for the GPU and not yet submitted.
pub struct Recording<'c> {
    context: &'c GpuContext,
    encoder: wgpu::CommandEncoder,
}

impl<'c> Recording<'c> {
    pub fn new(context: &'c GpuContext) -> Recording<'c> {
        Recording {
            context,
            encoder: context.device.create_command_encoder(&Default::default()),
        }
    }

    /// Where passes and copies are recorded.
    pub fn encoder(&mut self) -> &mut wgpu::CommandEncoder {
        &mut self.encoder
    }

    /// Submits what is recorded so far, without waiting: the GPU starts on
    /// it while the CPU records what follows.
    pub fn submit(&mut self) {
        let encoder = self.fresh_encoder();
        self.context.queue.submit([encoder.finish()]);
    }

    /// Submits what is recorded with `downloads` copied out after it, and
    /// waits for them: the one way the CPU blocks on the GPU. `why` names
    /// what the CPU needs (logged); recording goes on afterwards. The
    /// passes' timestamps come back with it (`super::pass_timer`), not
    /// counted in `gpu.bytes_down`, which is what the frame needs.
    pub fn wait(
        &mut self,
        why: &'static str,
        downloads: Downloads,
    ) -> Result<Downloaded, GpuError> {
        log::trace!("waiting on the GPU for {why}");
        let began = Instant::now();
        let bytes_wanted = downloads.bytes;
        let timer = self.context.pass_timer.as_ref();
        // The caller's buffers and the timer's, for as long as this wait.
        let mut downloads: Downloads<'_> = downloads;
        let times = timer.and_then(|timer| timer.resolve(&mut self.encoder, &mut downloads));
        let bytes = downloads.bytes.max(4);
        let staging = self.context.device.create_buffer(&wgpu::BufferDescriptor {
            label: Some(why),
            size: bytes,
            usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        for (buffer, at, size) in &downloads.copies {
            (self.encoder).copy_buffer_to_buffer(buffer, 0, &staging, *at, *size);
        }
        self.submit();
        let slice = staging.slice(..);
        let (sender, receiver) = std::sync::mpsc::channel();
        slice.map_async(wgpu::MapMode::Read, move |result| {
            let _ = sender.send(result);
        });
        let failed = |error: &dyn std::fmt::Display| GpuError::Readback(error.to_string());
        (self.context.device)
            .poll(wgpu::PollType::wait_indefinitely())
            .map_err(|error| failed(&error))?;
        receiver
            .recv()
            .map_err(|error| failed(&error))?
            .map_err(|error| failed(&error))?;
        let view = slice.get_mapped_range().map_err(|error| failed(&error))?;
        let downloaded = Downloaded {
            bytes: view.to_vec(),
        };
        self.context.traffic.waited(bytes_wanted, began.elapsed());
        if let (Some(timer), Some(times)) = (timer, times) {
            timer.keep(&downloaded, times);
        }
        Ok(downloaded)
    }

    /// [`Recording::wait`] for the first `count` items of one buffer.
    pub fn read_back<Out: Pod>(
        &mut self,
        why: &'static str,
        buffer: &wgpu::Buffer,
        count: usize,
    ) -> Result<Vec<Out>, GpuError> {
        let mut downloads = Downloads::default();
        let items = downloads.add::<Out>(buffer, count);
        Ok(self.wait(why, downloads)?.take(items))
    }

    fn fresh_encoder(&mut self) -> wgpu::CommandEncoder {
        let fresh = self
            .context
            .device
            .create_command_encoder(&Default::default());
        std::mem::replace(&mut self.encoder, fresh)
    }
}

/// The buffers one [`Recording::wait`] brings back, each copied to its own
/// range of one staging buffer.
#[derive(Default)]
pub struct Downloads<'b> {
    copies: Vec<(&'b wgpu::Buffer, u64, u64)>,
    bytes: u64,
}

/// Where one buffer's items lie in what a wait brings back.
pub struct Part<Out> {
    at: usize,
    count: usize,
    items: PhantomData<Out>,
}

impl<'b> Downloads<'b> {
    /// Adds the first `count` items of `buffer`. Every record that crosses
    /// is a whole number of 4-byte words, as copies need.
    pub fn add<Out: Pod>(&mut self, buffer: &'b wgpu::Buffer, count: usize) -> Part<Out> {
        let size = (count * size_of::<Out>()) as u64;
        let at = self.bytes;
        if size > 0 {
            self.copies.push((buffer, at, size));
        }
        self.bytes += size;
        Part {
            at: at as usize,
            count,
            items: PhantomData,
        }
    }
}

/// What a wait brought back.
pub struct Downloaded {
    bytes: Vec<u8>,
}

impl Downloaded {
    /// The items of `part`.
    pub fn take<Out: Pod>(&self, part: Part<Out>) -> Vec<Out> {
        let end = part.at + part.count * size_of::<Out>();
        bytemuck::pod_collect_to_vec(&self.bytes[part.at..end])
    }
}

/// Words of answers that passes wrote and the CPU has not brought back
/// yet: those a wait brought back, in the order the passes were
/// recorded, and the buffers still on the GPU, which the CPU's next wait
/// brings back ([`PendingWords::download`]) without a wait of its own.
#[derive(Default)]
pub struct PendingWords {
    words: Vec<u32>,
    pending: Vec<(wgpu::Buffer, usize)>,
}

impl PendingWords {
    /// Adds `words` words of `buffer`, written by a pass just recorded.
    pub fn push(&mut self, buffer: wgpu::Buffer, words: usize) {
        self.pending.push((buffer, words));
    }

    /// Adds the words still on the GPU to what a wait brings back.
    pub fn download<'s>(&'s self, downloads: &mut Downloads<'s>) -> Vec<Part<u32>> {
        (self.pending.iter())
            .map(|(buffer, words)| downloads.add(buffer, *words))
            .collect()
    }

    /// Keeps what a wait brought back of `parts`.
    pub fn keep(&mut self, downloaded: &Downloaded, parts: Vec<Part<u32>>) {
        for part in parts {
            self.words.extend(downloaded.take(part));
        }
        self.pending.clear();
    }

    /// Waits for the words still on the GPU, which the CPU needs for
    /// what `why` says: for passes run on their own, outside a frame.
    pub fn wait_for_all(
        &mut self,
        recording: &mut Recording,
        why: &'static str,
    ) -> Result<(), GpuError> {
        let mut downloads = Downloads::default();
        let parts = self.download(&mut downloads);
        let downloaded = recording.wait(why, downloads)?;
        self.keep(&downloaded, parts);
        Ok(())
    }

    /// Every word, once all are back.
    pub fn words(&self) -> &[u32] {
        debug_assert!(self.pending.is_empty(), "answers still on the GPU");
        &self.words
    }
}
