//! The `lmanim` command line: parse, call the library, report. Exit codes:
//! 0 on success, 2 for bad usage or bad input, 1 for other failures.

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::Parser;
use indicatif::{ProgressBar, ProgressStyle};

use lmanim::output::{self, ExrPrecision, FramePattern};
use lmanim::schedule::FrameSet;
use lmanim::sequence::{self, Job};
use lmanim::settings::{Method, Settings};
use lmanim::stats::RunStats;

/// Render a glTF scene's animation to an EXR image sequence, with soft
/// shadows from point lights by the Light Meshes Method.
#[derive(Debug, Parser)]
#[command(name = "lmanim", version)]
struct Cli {
    /// The scene: a .gltf or .glb file.
    scene: PathBuf,
    /// Frames to render: `A..B` (half-open), `A..=B`, `N`, or lists like `1-30,47`.
    #[arg(long, default_value = "0")]
    frames: String,
    /// Frames per second of the timeline (frame f is at time f / fps).
    #[arg(long)]
    fps: Option<f64>,
    /// Output pattern; a run of `#` becomes the zero-padded frame number.
    /// [default: renders/<scene>/frame.####.exr]
    #[arg(long)]
    out: Option<String>,
    /// Rendering method.
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Image width in pixels.
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels.
    #[arg(long)]
    height: Option<u32>,
    /// Render through the camera with this name (default: the first).
    #[arg(long)]
    camera: Option<String>,
    /// Render settings in RON; flags override it. Default: SCENE with the
    /// extension .ron, when that file exists.
    #[arg(long)]
    settings: Option<PathBuf>,
    /// Samples per pixel (jittered, stratified).
    #[arg(long)]
    spp: Option<u32>,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Also write a tone-mapped sRGB PNG preview beside each frame.
    #[arg(long)]
    png: bool,
    /// Write 32-bit float EXR channels instead of half floats.
    #[arg(long)]
    exr_float: bool,
    /// Write per-frame statistics as JSON to this file.
    #[arg(long)]
    stats: Option<PathBuf>,
    /// Print nothing but errors.
    #[arg(long)]
    quiet: bool,
}

/// A failure with the exit code it calls for.
struct Failure {
    bad_input: bool,
    error: anyhow::Error,
}

impl Failure {
    fn bad_input(error: impl Into<anyhow::Error>) -> Failure {
        Failure {
            bad_input: true,
            error: error.into(),
        }
    }
}

impl From<anyhow::Error> for Failure {
    fn from(error: anyhow::Error) -> Failure {
        Failure {
            bad_input: false,
            error,
        }
    }
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    init_logging(cli.quiet);
    match run(&cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            // One line, so scripts and render-farm logs can grep it.
            let message = format!("{:#}", failure.error).replace('\n', " ");
            eprintln!("lmanim: error: {message}");
            ExitCode::from(if failure.bad_input { 2 } else { 1 })
        }
    }
}

fn init_logging(quiet: bool) {
    let level = if quiet {
        log::LevelFilter::Error
    } else {
        log::LevelFilter::Warn
    };
    env_logger::Builder::new()
        .filter_level(level)
        .format(|out, record| {
            writeln!(
                out,
                "lmanim: {}: {}",
                record.level().as_str().to_lowercase(),
                record.args()
            )
        })
        .init();
}

fn run(cli: &Cli) -> Result<(), Failure> {
    let settings = resolve_settings(cli)?;
    let frames = FrameSet::parse(&cli.frames)
        .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--frames {}: {fault}", cli.frames)))?;
    let pattern_text = settings
        .out
        .clone()
        .unwrap_or_else(|| default_pattern(&cli.scene));
    let pattern = FramePattern::parse(&pattern_text)
        .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--out {pattern_text}: {fault}")))?;

    let progress = progress_bar(cli.quiet, frames.len() as u64);
    let job = Job {
        scene_path: &cli.scene,
        settings: &settings,
        frames: &frames,
        pattern: &pattern,
    };
    let stats = sequence::run(&job, |done| {
        if done.index == 0 && done.automatic_camera {
            progress.suspend(|| {
                log::warn!(
                    "{} has no camera: rendering through an automatic framing camera",
                    cli.scene.display()
                )
            });
        }
        if let (0, Some(mesh), false) = (done.index, done.stats.lightmesh, cli.quiet) {
            let source = if settings.lightmesh.h.is_some() {
                "set"
            } else {
                "from the lamp radii"
            };
            progress.suspend(|| {
                eprintln!(
                    "light mesh: h = {:.4} m ({source}), kI = {}",
                    mesh.h, mesh.ki
                )
            });
        }
        progress.set_message(done.path.display().to_string());
        progress.inc(1);
    })
    .map_err(|error| Failure {
        bad_input: error.is_bad_input(),
        error: error.into(),
    })?;
    progress.finish_and_clear();

    if let Some(path) = &cli.stats {
        let json = serde_json::to_vec_pretty(&stats).context("serialising statistics")?;
        output::write_atomically(path, |file| {
            file.write_all(&json)
                .map_err(|source| output::OutputError::Write {
                    path: path.clone(),
                    source,
                })
        })
        .map_err(anyhow::Error::from)?;
    }
    if !cli.quiet {
        eprintln!("{}", summary(&stats, &pattern_text));
    }
    Ok(())
}

/// The settings file (given, or the scene's sibling `.ron`), then the flags.
fn resolve_settings(cli: &Cli) -> Result<Settings, Failure> {
    let sibling = cli.scene.with_extension("ron");
    let file = cli
        .settings
        .clone()
        .or_else(|| sibling.is_file().then_some(sibling));
    let mut settings = match &file {
        Some(path) => Settings::load(path).map_err(Failure::bad_input)?,
        None => Settings::default(),
    };
    let flags = cli;
    settings.fps = flags.fps.unwrap_or(settings.fps);
    settings.method = flags.method.unwrap_or(settings.method);
    settings.width = flags.width.unwrap_or(settings.width);
    settings.height = flags.height.unwrap_or(settings.height);
    settings.spp = flags.spp.unwrap_or(settings.spp);
    settings.threads = flags.threads.or(settings.threads);
    settings.camera = flags.camera.clone().or(settings.camera);
    settings.out = flags.out.clone().or(settings.out);
    settings.png |= flags.png;
    if flags.exr_float {
        settings.exr_precision = ExrPrecision::Float;
    }
    settings.validate().map_err(Failure::bad_input)?;
    Ok(settings)
}

fn default_pattern(scene: &Path) -> String {
    let stem = scene
        .file_stem()
        .map_or("scene".into(), |stem| stem.to_string_lossy());
    format!("renders/{stem}/frame.####.exr")
}

/// A bar with ETA on stderr; indicatif draws nothing when stderr is not a
/// terminal, so logs and CI stay clean.
fn progress_bar(quiet: bool, frames: u64) -> ProgressBar {
    if quiet {
        return ProgressBar::hidden();
    }
    let bar = ProgressBar::new(frames);
    let style = ProgressStyle::with_template(
        "{bar:40} {pos}/{len} frames  {elapsed} elapsed, ETA {eta}  {msg}",
    )
    .unwrap_or_else(|_| ProgressStyle::default_bar());
    bar.set_style(style);
    bar
}

fn summary(stats: &RunStats, pattern: &str) -> String {
    let frames = stats.frames.len().max(1) as f64;
    let rays: u64 = stats
        .frames
        .iter()
        .map(|f| f.rays.primary + f.rays.shadow + f.rays.secondary)
        .sum();
    format!(
        "rendered {} frame(s) with {} on {} thread(s) in {:.2} s ({:.3} s/frame, {:.2} Mrays/s) to {}",
        stats.frames.len(),
        stats.method,
        stats.threads,
        stats.total_seconds,
        stats.total_seconds / frames,
        rays as f64 / stats.total_seconds.max(1e-9) / 1e6,
        pattern
    )
}
