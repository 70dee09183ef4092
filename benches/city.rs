//! Reuse across frames on the showcase animation, `animations/city.gltf`
//! with its own settings (1280×720, LMM1): the fly-through rendered as a
//! sequence (masks kept, invalidated where cars, trees and lamps change
//! them), against frames rendered cold (a fresh sequence each, so nothing
//! is reused). No disk cache either way and no files written: this measures
//! rendering.
//!
//! `cargo bench --bench city` renders frames 0..240 with reuse and every
//! 10th frame cold, and prints per-frame rows and a Markdown summary for
//! BENCHMARKS.md. `LMANIM_BENCH_FRAMES=A..B` picks the frames,
//! `LMANIM_BENCH_COLD_EVERY=N` the cold sample (0 for none),
//! `LMANIM_BENCH_SIZE=WxH` overrides the size, `LMANIM_BENCH_CLIP=NAME`
//! plays one clip ("Traffic": the cars alone, under a still camera).

use std::path::Path;
use std::time::Instant;

use lmanim::anim::pose::ClipSelection;
use lmanim::backend::Backend;
use lmanim::schedule::{FrameSet, Timeline};
use lmanim::sequence::Sequence;
use lmanim::settings::Settings;
use lmanim::stats::FrameStats;

const SCENE: &str = "animations/city.gltf";
const SETTINGS: &str = "animations/city.ron";

fn main() {
    let frames = FrameSet::parse(&env_or("LMANIM_BENCH_FRAMES", "0..240")).expect("frame range");
    let cold_every: usize = env_or("LMANIM_BENCH_COLD_EVERY", "10")
        .parse()
        .expect("LMANIM_BENCH_COLD_EVERY is a number");
    let mut settings = Settings::load(Path::new(SETTINGS)).expect("city settings");
    if let Ok(size) = std::env::var("LMANIM_BENCH_SIZE") {
        let (w, h) = size.split_once('x').expect("LMANIM_BENCH_SIZE is WxH");
        settings.width = w.parse().expect("width");
        settings.height = h.parse().expect("height");
    }
    settings.validate().expect("settings");
    let mut backend =
        lmanim::backend::Backend::new(lmanim::settings::BackendKind::Cpu, settings.threads)
            .expect("thread pool");
    let timeline = Timeline { fps: settings.fps };
    println!(
        "{SCENE} (clip {}): {}x{} {}, {} threads, frames {}..={}",
        std::env::var("LMANIM_BENCH_CLIP").unwrap_or_else(|_| "all".into()),
        settings.width,
        settings.height,
        settings.method,
        backend.threads(),
        frames.frames()[0],
        frames.frames()[frames.len() - 1]
    );

    println!("| frame | seconds | invalidate s | bits invalidated | bits computed | bits cached | computed / cached |");
    println!("|---|---|---|---|---|---|---|");
    let mut sequence = load();
    let started = Instant::now();
    let mut reused = Vec::new();
    for &frame in frames.frames() {
        let stats = render(
            &mut sequence,
            &mut backend,
            &settings,
            timeline.time_of(frame),
        );
        let mesh = stats.lightmesh.unwrap_or_default();
        println!(
            "| {frame} | {:.2} | {:.4} | {} | {} | {} | {:.2}% |",
            stats.seconds,
            stats.invalidate_seconds,
            stats.bits_invalidated,
            mesh.bits_computed,
            mesh.bits_cached,
            percent(mesh.bits_computed, mesh.bits_cached)
        );
        reused.push(stats);
    }
    let reuse_total = started.elapsed().as_secs_f64();

    let mut cold = Vec::new();
    if cold_every > 0 {
        for &frame in frames.frames().iter().step_by(cold_every) {
            let mut fresh = load();
            let stats = render(&mut fresh, &mut backend, &settings, timeline.time_of(frame));
            println!("cold frame {frame}: {:.2} s", stats.seconds);
            cold.push(stats.seconds);
        }
    }

    let steady = &reused[1.min(reused.len() - 1)..];
    let mean = |values: &mut dyn Iterator<Item = f64>, count: usize| {
        values.sum::<f64>() / count.max(1) as f64
    };
    let steady_seconds = mean(&mut steady.iter().map(|s| s.seconds), steady.len());
    let invalidate_share = mean(
        &mut steady.iter().map(|s| s.invalidate_seconds / s.seconds),
        steady.len(),
    );
    let recomputed = mean(
        &mut steady.iter().map(|s| {
            let mesh = s.lightmesh.unwrap_or_default();
            percent(mesh.bits_computed, mesh.bits_cached) / 100.0
        }),
        steady.len(),
    );
    let invalidated = mean(
        &mut steady.iter().map(|s| {
            let mesh = s.lightmesh.unwrap_or_default();
            percent(s.bits_invalidated, mesh.bits_cached) / 100.0
        }),
        steady.len(),
    );
    println!();
    println!("| measure | value |");
    println!("|---|---|");
    println!(
        "| cold frame (frame {}, sequence start) | {:.2} s |",
        frames.frames()[0],
        reused[0].seconds
    );
    println!("| steady-state frame (mean of frames after the first) | {steady_seconds:.2} s |");
    println!(
        "| bits invalidated per frame / bits cached (mean) | {:.2}% |",
        invalidated * 100.0
    );
    println!(
        "| bits computed per frame / bits cached (mean; new nodes included) | {:.2}% |",
        recomputed * 100.0
    );
    println!(
        "| invalidation time / frame time (mean) | {:.2}% |",
        invalidate_share * 100.0
    );
    println!(
        "| {} frames with reuse | {reuse_total:.1} s |",
        frames.len()
    );
    if !cold.is_empty() {
        let cold_mean = cold.iter().sum::<f64>() / cold.len() as f64;
        println!(
            "| {} frames cold (mean of {} sampled cold frames × {}) | {:.1} s ({cold_mean:.2} s a frame) |",
            frames.len(),
            cold.len(),
            frames.len(),
            cold_mean * frames.len() as f64
        );
    }
}

fn env_or(name: &str, default: &str) -> String {
    std::env::var(name).unwrap_or_else(|_| default.to_owned())
}

fn percent(part: u64, whole: u64) -> f64 {
    100.0 * part as f64 / whole.max(1) as f64
}

fn load() -> Sequence {
    let mut sequence = Sequence::load(Path::new(SCENE)).expect("city loads");
    sequence.set_cache_dir(None);
    if let Ok(clip) = std::env::var("LMANIM_BENCH_CLIP") {
        let clips = ClipSelection::parse(sequence.scene(), &clip).expect("a clip of the city");
        sequence.set_clips(clips);
    }
    sequence
}

fn render(
    sequence: &mut Sequence,
    backend: &mut Backend,
    settings: &Settings,
    time: f64,
) -> FrameStats {
    let started = Instant::now();
    let mut stats = FrameStats::default();
    let placed = sequence
        .advance(time, settings, &mut stats)
        .expect("frame places");
    sequence
        .render(backend, &placed, settings, &mut stats)
        .expect("frame renders");
    stats.seconds = started.elapsed().as_secs_f64();
    stats
}
