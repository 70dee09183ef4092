//! How long the GPU spent in each pass, by the pass's name: the GPU
//! writes a timestamp as each compute pass begins and ends
//! ([`PassTimer::writes`]), and the timestamps come back with the next
//! blocking wait (`recording::Recording::wait`), which resolves them
//! beside what it reads back anyway, so timing adds no wait of its own.
//! A frame's sums are the `gpu.pass_seconds` of `--stats`: where a
//! frame's GPU time goes (the light mesh's fill against its shading, say)
//! without a profiler, which the machines lent for an hour cannot be
//! asked to run.
//!
//! Adapters without timestamp queries time nothing, and a frame then
//! reports no pass times. A pass recorded when every query of the set is
//! claimed is counted in `untimed` instead: the sums are lower bounds
//! then. A band that fails between recording a pass and submitting it
//! leaves that pass pending: the next wait reads its queries unwritten
//! (untimed, or a stale pair). Only a failed frame does that, and its
//! error ends the run.

use std::collections::BTreeMap;
use std::sync::{Mutex, MutexGuard, PoisonError};

use serde::Serialize;

use super::recording::{Downloaded, Downloads, Part};

/// Queries in the set: two per pass, so 2,048 passes between two waits.
const QUERIES: u32 = wgpu::QUERY_SET_MAX_QUERIES;

/// Timestamps written by the GPU, and the sums they came to.
pub struct PassTimer {
    queries: wgpu::QuerySet,
    /// Where the queries are resolved to, for the wait's copy.
    resolved: wgpu::Buffer,
    /// Nanoseconds per timestamp tick.
    period: f64,
    state: Mutex<TimerState>,
}

#[derive(Default)]
struct TimerState {
    /// The passes given queries since the last wait, in query order: the
    /// pass at `i` wrote queries 2i and 2i + 1.
    pending: Vec<&'static str>,
    times: PassTimes,
}

/// Seconds on the GPU per pass name, and the passes left untimed: part
/// of a frame's `gpu` object in `--stats`, absent where the adapter
/// times nothing.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct PassTimes {
    #[serde(rename = "pass_seconds", skip_serializing_if = "BTreeMap::is_empty")]
    pub seconds: BTreeMap<&'static str, f64>,
    #[serde(rename = "passes_untimed", skip_serializing_if = "is_zero")]
    pub untimed: u64,
}

fn is_zero(count: &u64) -> bool {
    *count == 0
}

/// What a wait brings back for the timer: the passes' timestamps.
pub struct PendingTimes {
    passes: Vec<&'static str>,
    stamps: Part<u64>,
}

impl PassTimer {
    /// The device's timer, where it has timestamp queries (asked for
    /// when it was made: `context::GpuContext::new`).
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue) -> Option<PassTimer> {
        if !device.features().contains(wgpu::Features::TIMESTAMP_QUERY) {
            return None;
        }
        let queries = device.create_query_set(&wgpu::QuerySetDescriptor {
            label: Some("pass timestamps"),
            ty: wgpu::QueryType::Timestamp,
            count: QUERIES,
        });
        let resolved = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("resolved pass timestamps"),
            size: u64::from(QUERIES) * size_of::<u64>() as u64,
            usage: wgpu::BufferUsages::QUERY_RESOLVE | wgpu::BufferUsages::COPY_SRC,
            mapped_at_creation: false,
        });
        Some(PassTimer {
            queries,
            resolved,
            period: f64::from(queue.get_timestamp_period()),
            state: Mutex::default(),
        })
    }

    /// Where the pass named `name` writes its timestamps, or `None` (the
    /// pass counted untimed) when every query is claimed until the next
    /// wait.
    pub fn writes(&self, name: &'static str) -> Option<wgpu::ComputePassTimestampWrites<'_>> {
        let mut state = self.state();
        let first = 2 * state.pending.len() as u32;
        if first + 2 > QUERIES {
            state.times.untimed += 1;
            return None;
        }
        state.pending.push(name);
        Some(wgpu::ComputePassTimestampWrites {
            query_set: &self.queries,
            beginning_of_pass_write_index: Some(first),
            end_of_pass_write_index: Some(first + 1),
        })
    }

    /// Records the resolution of the timestamps written since the last
    /// wait into `encoder`, and adds them to what the wait brings back.
    pub fn resolve<'t>(
        &'t self,
        encoder: &mut wgpu::CommandEncoder,
        downloads: &mut Downloads<'t>,
    ) -> Option<PendingTimes> {
        let passes = std::mem::take(&mut self.state().pending);
        if passes.is_empty() {
            return None;
        }
        let count = 2 * passes.len();
        encoder.resolve_query_set(&self.queries, 0..count as u32, &self.resolved, 0);
        let stamps = downloads.add::<u64>(&self.resolved, count);
        Some(PendingTimes { passes, stamps })
    }

    /// Adds the passes' times that `downloaded` holds to the sums (a pass
    /// [`seconds_between`] cannot time is counted untimed).
    pub fn keep(&self, downloaded: &Downloaded, pending: PendingTimes) {
        let stamps = downloaded.take(pending.stamps);
        let mut state = self.state();
        for (name, pair) in pending.passes.into_iter().zip(stamps.chunks_exact(2)) {
            match seconds_between(pair[0], pair[1], self.period) {
                Some(seconds) => *state.times.seconds.entry(name).or_default() += seconds,
                None => state.times.untimed += 1,
            }
        }
    }

    /// The sums since the last call (or since the timer was made): one
    /// frame's, when taken at its end.
    pub fn take(&self) -> PassTimes {
        std::mem::take(&mut self.state().times)
    }

    /// The state, also where a thread panicked holding it: the sums are
    /// whole numbers of passes either way.
    fn state(&self) -> MutexGuard<'_, TimerState> {
        self.state.lock().unwrap_or_else(PoisonError::into_inner)
    }
}

/// The seconds from timestamp `start` to `end`, at `period` nanoseconds a
/// tick; `None` where the end does not follow the start (a driver that
/// wrapped its counter) or the start is 0 (a query left unwritten reads
/// 0).
fn seconds_between(start: u64, end: u64, period: f64) -> Option<f64> {
    let ticks = end.checked_sub(start).filter(|_| start != 0)?;
    Some(ticks as f64 * period / 1e9)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_pass_is_timed_only_where_its_end_follows_its_start() {
        assert_eq!(seconds_between(1_000, 3_000, 1.0), Some(2e-6));
        // lavapipe's ticks are nanoseconds; NVIDIA's too; others differ.
        let odd_period = seconds_between(10, 20, 83.333).unwrap();
        assert!((odd_period - 833.33e-9).abs() < 1e-18, "{odd_period}");
        assert_eq!(seconds_between(5, 5, 1.0), Some(0.0), "a pass of no work");
        assert_eq!(
            seconds_between(3_000, 1_000, 1.0),
            None,
            "a wrapped counter"
        );
        assert_eq!(seconds_between(0, 1_000, 1.0), None, "an unwritten start");
        let longest = seconds_between(1, u64::MAX, 1.0).unwrap();
        assert!((longest - 1.8446744073709552e10).abs() < 1.0, "{longest}");
    }
}
