//! The `lmanim` command line: parse, call the library, report. Exit codes:
//! 0 on success, 2 for bad usage or bad input, 1 for other failures.
//!
//! `lmanim SCENE [flags]` renders; `lmanim inspect SCENE [flags]` prints the
//! animation's poses as JSON instead; `lmanim study SCENE --out DIR`
//! measures what each method's accuracy costs in time on one frame;
//! `lmanim bake-camera SCENE --camera-path PATH.ron --out OUT.gltf` writes
//! the scene with a camera path as a glTF camera and clip. (A scene file
//! literally named `inspect` or `study` is rendered as `lmanim ./inspect`.)

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

use anyhow::Context;
use clap::{Args, CommandFactory, FromArgMatches, Parser, Subcommand, ValueEnum};
use indicatif::{ProgressBar, ProgressStyle};

use lmanim::anim::inspect::inspect;
use lmanim::anim::ClipSelection;
use lmanim::camera_path::{bake, CameraPath};
use lmanim::import;
use lmanim::lightmesh::kernel::Kernel;
use lmanim::lightmesh::penumbra::Penumbra;
use lmanim::output::{self, ExrPrecision, FramePattern};
use lmanim::plan;
use lmanim::schedule::{FrameSet, Timeline};
use lmanim::sequence::{self, Job, RunEvent};
use lmanim::settings::{Aov, BackendKind, LightMeshSettings, Method, Settings};
use lmanim::stats::RunStats;
use lmanim::study::{self, StudyOptions};

/// Render a glTF scene's animation to an EXR image sequence, with soft
/// shadows from point lights by the Light Meshes Method.
///
/// Flags override the settings file (SCENE.ron, or --settings); a
/// default shown is the value when neither sets one.
#[derive(Debug, Parser)]
#[command(
    name = "lmanim",
    version,
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true
)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
    #[command(flatten)]
    render: Option<RenderArgs>,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// Print the animated pose (node transforms, morph weights, lights and
    /// cameras in world space) at chosen times as JSON, without rendering.
    Inspect(InspectArgs),
    /// Measure error against time on one frame: a reference, then every
    /// method over its settings, with tables and plots in --out.
    Study(StudyArgs),
    /// Compute the light mesh's masks that the frames will need and save
    /// them to the disk cache, without rendering: a farm job's first task,
    /// so that its render tasks start warm. Takes a render's arguments.
    Warm(RenderArgs),
    /// Print the effect plan: each light's shadow class and why, the
    /// objects that move within the frames, the materials that spawn
    /// secondary rays, the frames copied and the work per frame. Takes a
    /// render's arguments.
    Plan(PlanArgs),
    /// Write the scene with a camera path (--camera-path or --orbit) as an
    /// ordinary glTF camera node and animation clip, keyed at every frame,
    /// so other players show the same shot.
    BakeCamera(BakeArgs),
}

#[derive(Debug, Args)]
struct BakeArgs {
    /// The scene: a .gltf or .glb file.
    scene: PathBuf,
    /// The camera path to bake (as for rendering).
    #[arg(long, value_name = "PATH.ron", conflicts_with = "orbit")]
    camera_path: Option<PathBuf>,
    /// The turntable to bake (as for rendering).
    #[arg(
        long,
        value_name = "X,Y,Z,RADIUS,HEIGHT,SECONDS",
        allow_hyphen_values = true
    )]
    orbit: Option<String>,
    /// The .gltf file to write (buffers and images embedded).
    #[arg(long, value_name = "OUT.gltf")]
    out: PathBuf,
    /// Frames per second of the keys (by default the scene's settings
    /// file's, or 24 without one).
    #[arg(long)]
    fps: Option<f64>,
}

#[derive(Debug, Args)]
struct PlanArgs {
    #[command(flatten)]
    render: RenderArgs,
    /// Print the plan as JSON.
    #[arg(long)]
    json: bool,
}

#[derive(Debug, Args)]
struct StudyArgs {
    /// The scene: a .gltf or .glb file.
    scene: PathBuf,
    /// The frame to study (at the settings file's fps).
    #[arg(long, default_value_t = 0)]
    frame: u32,
    /// Image width in pixels (the scene's settings file's, if it has one).
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels (the scene's settings file's, if it has one).
    #[arg(long)]
    height: Option<u32>,
    /// Measure against this EXR (e.g. another renderer's) instead of
    /// rendering a reference.
    #[arg(long, value_name = "REF.exr")]
    reference: Option<PathBuf>,
    /// Leave out the pixels where this EXR is above 0: its alpha, else its
    /// Y, else its largest colour channel.
    #[arg(long, value_name = "MASK.exr", requires = "reference")]
    reference_mask: Option<PathBuf>,
    /// Read the reference from this layer of REF.exr (a part's name or a
    /// channel prefix such as `ViewLayer.Combined`) instead of its beauty.
    #[arg(long, value_name = "NAME", requires = "reference")]
    reference_layer: Option<String>,
    /// Samples per pixel of the rendered reference (method area).
    #[arg(long, default_value_t = study::DEFAULT_REFERENCE_SPP, conflicts_with = "reference")]
    reference_spp: u32,
    /// Methods to sweep, comma-separated.
    #[arg(
        long,
        value_enum,
        value_delimiter = ',',
        default_value = "whitted,lmm,lmm1,area"
    )]
    methods: Vec<Method>,
    /// Measure these frames too, made elsewhere in SECONDS each (another
    /// renderer's, or a still sequence's: several frames, whose errors are
    /// pooled and whose flicker is measured). Repeatable.
    #[arg(
        long = "candidate",
        value_name = "NAME=SECONDS:FRAME.exr[,FRAME.exr...]"
    )]
    candidates: Vec<study::candidate::Candidate>,
    /// Directory for study.json, study.csv, study.png, crops.png and reference.exr.
    #[arg(long)]
    out: PathBuf,
    /// Worker threads (default: one per core).
    #[arg(long)]
    threads: Option<usize>,
    /// Print nothing but errors.
    #[arg(long)]
    quiet: bool,
}

#[derive(Debug, Args)]
struct InspectArgs {
    /// The scene: a .gltf or .glb file.
    scene: PathBuf,
    /// Play only this clip (name or index); default: all clips together.
    #[arg(long)]
    clip: Option<String>,
    /// Times in seconds, comma-separated (e.g. `0,0.5,1`).
    #[arg(long, conflicts_with = "frames")]
    times: Option<String>,
    /// Frames to sample, as for rendering (`A..B`, `A..=B`, `N`, `1-30,47`).
    #[arg(long)]
    frames: Option<String>,
    /// Frames per second for --frames (the scene's settings file's, if it
    /// has one).
    #[arg(long)]
    fps: Option<f64>,
}

/// Rendering: the default command.
#[derive(Debug, Args)]
struct RenderArgs {
    /// The scene: a .gltf or .glb file.
    scene: PathBuf,
    /// Frames to render: `A..B` (half-open), `A..=B`, `N`, or lists like `1-30,47`.
    #[arg(long, default_value = "0")]
    frames: String,
    /// Frames per second of the timeline (frame f is at time f / fps).
    #[arg(long)]
    fps: Option<f64>,
    /// Output pattern; a run of `#` becomes the zero-padded frame number
    /// (by default renders/<scene>/frame.####.exr).
    #[arg(long)]
    out: Option<String>,
    /// Rendering method (`auto`: each light as the effect plan says).
    #[arg(long, value_enum)]
    method: Option<Method>,
    /// Plan over these frames of the shot instead of the rendered ones
    /// (they must hold them): every chunk of a farm job plans alike.
    #[arg(long, value_name = "RANGE")]
    plan_frames: Option<String>,
    /// Print the effect plan (as `lmanim plan` does) before rendering.
    #[arg(long)]
    explain: bool,
    /// Which hardware renders: `cpu` or `gpu` (wgpu compute).
    #[arg(long, value_enum)]
    backend: Option<BackendKind>,
    /// Image width in pixels.
    #[arg(long)]
    width: Option<u32>,
    /// Image height in pixels.
    #[arg(long)]
    height: Option<u32>,
    /// Play only this animation clip (name or index); default: all clips together.
    #[arg(long)]
    clip: Option<String>,
    /// Render through the camera with this name (default: the first).
    #[arg(long, conflicts_with_all = ["camera_path", "orbit"])]
    camera: Option<String>,
    // Not a flattened struct shared with `BakeArgs`: clap leaves an
    // optional flattened `RenderArgs` with a flattened field unmatched.
    /// Fly the camera along this path (RON: waypoints, field of view,
    /// ease; see README, "Camera paths") instead of the scene's cameras.
    #[arg(long, value_name = "PATH.ron", conflicts_with = "orbit")]
    camera_path: Option<PathBuf>,
    /// Turntable: one turn around the point X,Y,Z at RADIUS metres,
    /// HEIGHT metres above it, looking at it, in SECONDS.
    #[arg(
        long,
        value_name = "X,Y,Z,RADIUS,HEIGHT,SECONDS",
        allow_hyphen_values = true
    )]
    orbit: Option<String>,
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
    /// Light-mesh lattice step in metres (by default from the lamp radii).
    #[arg(long = "h", value_name = "METRES", allow_negative_numbers = true)]
    h: Option<f32>,
    /// Light-mesh interpolation radius in lattice steps (the paper's kI).
    #[arg(long, value_name = "K", allow_negative_numbers = true)]
    ki: Option<f32>,
    /// How formula (2) weighs the nodes: box (the paper) or smooth.
    #[arg(long, value_enum)]
    kernel: Option<Kernel>,
    /// How wide each light's set is where its nodes disagree: fixed (kI·h,
    /// the paper), blocker (from the lamp's radius and the blocker's
    /// distance) or wide (blocker, also where only a wider set of nodes
    /// sees the penumbra).
    #[arg(long, value_enum)]
    penumbra: Option<Penumbra>,
    /// The share of a point's lamp light whose penumbrae may keep the
    /// half-ball's answer instead of being sized by rays: a pixel moves by
    /// at most that share of its unshadowed light; 0 sizes every lamp's.
    #[arg(long, value_name = "SHARE")]
    faint_lamps: Option<f32>,
    /// Also write a tone-mapped sRGB PNG preview beside each frame.
    #[arg(long)]
    png: bool,
    /// Exposure of the PNG previews in stops: +1 doubles the radiance
    /// before tone mapping (the EXR frames are not scaled).
    #[arg(long, value_name = "EV", allow_negative_numbers = true)]
    exposure: Option<f32>,
    /// Render only the frames whose files (the EXR, and the PNG with
    /// --png) are missing or do not read back whole at the run's size: a
    /// stopped shot resumes where it stopped.
    #[arg(long)]
    skip_existing: bool,
    /// Write a contact sheet of the run's frames, labelled with their
    /// numbers, to this PNG at the end of the run.
    #[arg(long, value_name = "FILE.png")]
    contact_sheet: Option<String>,
    /// Thumbnails per row of the contact sheet.
    #[arg(long, value_name = "N")]
    sheet_columns: Option<u32>,
    /// Put every K-th frame of the run on the contact sheet.
    #[arg(long, value_name = "K")]
    sheet_every: Option<u32>,
    /// Width of the contact sheet's thumbnails in pixels (by default 256,
    /// or the frame's width where that is smaller); the sheet grows with
    /// the frames.
    #[arg(long, value_name = "PIXELS")]
    sheet_thumb_width: Option<u32>,
    /// The frames the contact sheet is over (e.g. the whole shot, `0..240`);
    /// those this run does not render are read back from their EXR files
    /// (by default the run's frames).
    #[arg(long, value_name = "RANGE")]
    sheet_frames: Option<String>,
    /// Write these layers into each EXR beside the beauty, comma-separated:
    /// light (one RGB layer per light or group), albedo, normal, depth.
    #[arg(long, value_name = "LIST")]
    aovs: Option<String>,
    /// A quick look: a quarter of the width and height, LMM1 on a coarse
    /// lattice, PNG frames only (other flags still override).
    #[arg(long)]
    preview: bool,
    /// Write 32-bit float EXR channels instead of half floats.
    #[arg(long)]
    exr_float: bool,
    /// Keep the light mesh's static masks in this directory, shared by
    /// runs of the same scene and lattice.
    #[arg(long, value_name = "DIR", conflicts_with = "no_cache")]
    cache: Option<String>,
    /// Neither read nor write the light-mesh disk cache.
    #[arg(long)]
    no_cache: bool,
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
    quiet_headless_vulkan();
    let cli = Cli::from_arg_matches(&command().get_matches()).unwrap_or_else(|error| error.exit());
    let outcome = match (&cli.command, &cli.render) {
        (Some(Command::Inspect(args)), _) => {
            init_logging(false);
            run_inspect(args)
        }
        (Some(Command::Study(args)), _) => {
            init_logging(args.quiet);
            run_study(args)
        }
        (Some(Command::Warm(args)), _) => {
            init_logging(args.quiet);
            run_warm(args)
        }
        (Some(Command::Plan(args)), _) => {
            init_logging(args.render.quiet);
            run_plan(args)
        }
        (Some(Command::BakeCamera(args)), _) => {
            init_logging(false);
            run_bake(args)
        }
        (None, Some(render)) => {
            init_logging(render.quiet);
            run(render)
        }
        // clap requires SCENE when no subcommand is given.
        (None, None) => Err(Failure::bad_input(anyhow::anyhow!("no scene given"))),
    };
    match outcome {
        Ok(()) => ExitCode::SUCCESS,
        Err(failure) => {
            eprintln!("lmanim: error: {}", one_line(&failure.error));
            ExitCode::from(if failure.bad_input { 2 } else { 1 })
        }
    }
}

/// The command line, each flag that overrides a setting documented with
/// `Settings::default()`'s value. Clap can give such a flag no default
/// of its own (it would override the settings file), so its
/// `[default: …]` is added to its help here, from the code, where it
/// cannot drift from the value.
fn command() -> clap::Command {
    let defaults = setting_defaults();
    let documented = |command: clap::Command| {
        defaults.iter().fold(command, |command, (id, value)| {
            let has = command.get_arguments().any(|arg| arg.get_id() == id);
            match has {
                true => command.mut_arg(*id, |arg| with_default(arg, value)),
                false => command,
            }
        })
    };
    let mut command = documented(Cli::command());
    for name in ["warm", "plan", "study", "inspect", "bake-camera"] {
        command = command.mut_subcommand(name, documented);
    }
    command
}

/// Each flag (by its argument id) that overrides a setting with a value
/// by default, and that value as the flag takes it.
fn setting_defaults() -> Vec<(&'static str, String)> {
    fn name(value: impl ValueEnum) -> String {
        value
            .to_possible_value()
            .map_or_else(String::new, |value| value.get_name().to_owned())
    }
    let settings = Settings::default();
    let mut defaults = vec![
        ("fps", settings.fps.to_string()),
        ("method", name(settings.method)),
        ("backend", name(settings.backend)),
        ("width", settings.width.to_string()),
        ("height", settings.height.to_string()),
        ("spp", settings.spp.to_string()),
        ("ki", settings.lightmesh.ki.to_string()),
        ("kernel", name(settings.lightmesh.kernel)),
        ("penumbra", name(settings.lightmesh.penumbra)),
        ("faint_lamps", settings.lightmesh.faint_lamps.to_string()),
        ("exposure", settings.exposure.to_string()),
        ("sheet_columns", settings.sheet_columns.to_string()),
        ("sheet_every", settings.sheet_every.to_string()),
    ];
    defaults.extend(settings.cache_dir.map(|dir| ("cache", dir)));
    defaults
}

/// `arg` with `[default: value]` after its help, as clap writes its own.
fn with_default(arg: clap::Arg, value: &str) -> clap::Arg {
    let note = format!("[default: {value}]");
    let help = arg
        .get_help()
        .map_or_else(|| note.clone(), |help| format!("{help} {note}"));
    let long_help = arg.get_long_help().map(|help| format!("{help}\n\n{note}"));
    let arg = arg.help(help);
    match long_help {
        Some(long_help) => arg.long_help(long_help),
        None => arg,
    }
}

/// On a machine without a desktop session (no `XDG_RUNTIME_DIR`: a farm
/// node, a container, CI), Mesa's Vulkan device-select layer asks
/// libwayland for a display, and libwayland prints an error line each
/// time. wgpu chooses the adapter itself, so the layer is switched off
/// there (`NODEVICE_SELECT`, Mesa's own switch), unless the user set it.
/// This runs first, while the process has one thread.
fn quiet_headless_vulkan() {
    let headless = std::env::var_os("XDG_RUNTIME_DIR").is_none();
    if headless && std::env::var_os("NODEVICE_SELECT").is_none() {
        std::env::set_var("NODEVICE_SELECT", "1");
    }
}

/// The error and its causes on one line, so scripts and render-farm logs
/// can grep it. Our error types already print their source in their own
/// message; a cause is appended only where the message lacks it.
fn one_line(error: &anyhow::Error) -> String {
    let mut message = error.to_string();
    for cause in error.chain().skip(1) {
        let cause = cause.to_string();
        if !message.contains(&cause) {
            message = format!("{message}: {cause}");
        }
    }
    message.replace('\n', " ")
}

fn init_logging(quiet: bool) {
    let level = if quiet {
        log::LevelFilter::Error
    } else {
        log::LevelFilter::Warn
    };
    env_logger::Builder::new()
        .filter_level(level)
        // wgpu relays the Vulkan loader's and driver's chatter (missing
        // ICD files, software adapters) as errors; what matters reaches
        // the user as lmanim's own one-line error.
        .filter_module("wgpu_hal", log::LevelFilter::Off)
        .filter_module("wgpu_core", log::LevelFilter::Off)
        .filter_module("naga", log::LevelFilter::Off)
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

fn run(cli: &RenderArgs) -> Result<(), Failure> {
    let settings = resolve_settings(cli)?;
    let frames = FrameSet::parse(&cli.frames)
        .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--frames {}: {fault}", cli.frames)))?;
    let pattern_text = settings
        .out
        .clone()
        .unwrap_or_else(|| default_pattern(&cli.scene));
    let pattern = FramePattern::parse(&pattern_text)
        .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--out {pattern_text}: {fault}")))?;

    let job = Job {
        scene_path: &cli.scene,
        settings: &settings,
        frames: &frames,
        pattern: &pattern,
    };
    if cli.explain {
        eprint!("{}", plan::report::text(&planned(&job)?));
    }
    let progress = progress_bar(cli.quiet, frames.len() as u64);
    // Frames left out by --skip-existing, for the bar's message.
    let mut skipped = 0;
    let stats = sequence::run(&job, |event| {
        let done = match event {
            RunEvent::Compiling {
                compiled,
                of,
                seconds,
            } => return report_compile(&progress, cli.quiet, compiled, of, seconds),
            RunEvent::Frame(done) => done,
        };
        if done.skipped {
            skipped += 1;
            progress.set_message(format!("{skipped} skipped (on disk)"));
            progress.inc(1);
            return;
        }
        if done.index == 0 && done.automatic_camera {
            progress.suspend(|| {
                log::warn!(
                    "{} has no camera: rendering through an automatic framing camera",
                    cli.scene.display()
                )
            });
        }
        if let (0, Some(adapter), false) = (done.index, done.adapter, cli.quiet) {
            progress.suspend(|| eprintln!("GPU adapter: {adapter}"));
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
        let written = done.path.display();
        progress.set_message(match skipped {
            0 => written.to_string(),
            _ => format!("{written}, {skipped} skipped (on disk)"),
        });
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
fn resolve_settings(cli: &RenderArgs) -> Result<Settings, Failure> {
    let sibling = cli.scene.with_extension("ron");
    let file = cli
        .settings
        .clone()
        .or_else(|| sibling.is_file().then_some(sibling));
    let mut settings = match &file {
        Some(path) => Settings::load(path).map_err(Failure::bad_input)?,
        None => Settings::default(),
    };
    if cli.preview {
        settings = settings.preview();
    }
    let flags = cli;
    settings.fps = flags.fps.unwrap_or(settings.fps);
    settings.method = flags.method.unwrap_or(settings.method);
    settings.backend = flags.backend.unwrap_or(settings.backend);
    settings.width = flags.width.unwrap_or(settings.width);
    settings.height = flags.height.unwrap_or(settings.height);
    settings.spp = flags.spp.unwrap_or(settings.spp);
    settings.threads = flags.threads.or(settings.threads);
    settings.camera = flags.camera.clone().or(settings.camera);
    settings.camera_path =
        camera_path(flags.camera_path.as_deref(), flags.orbit.as_deref())?.or(settings.camera_path);
    if settings.camera_path.is_some() {
        // The flags refuse both at once; a settings file's camera (the
        // city's "flythrough") gives way to the path, and says so.
        if let Some(name) = settings.camera.take() {
            log::warn!(
                "the settings' camera '{name}' is not used: the camera path flies the camera"
            );
        }
    }
    settings.clip = flags.clip.clone().or(settings.clip);
    settings.out = flags.out.clone().or(settings.out);
    settings.png |= flags.png;
    settings.skip_existing |= flags.skip_existing;
    settings.exposure = flags.exposure.unwrap_or(settings.exposure);
    settings.contact_sheet = flags.contact_sheet.clone().or(settings.contact_sheet);
    settings.sheet_columns = flags.sheet_columns.unwrap_or(settings.sheet_columns);
    settings.sheet_every = flags.sheet_every.unwrap_or(settings.sheet_every);
    settings.sheet_thumb_width = flags.sheet_thumb_width.or(settings.sheet_thumb_width);
    settings.sheet_frames = flags.sheet_frames.clone().or(settings.sheet_frames);
    settings.plan_frames = flags.plan_frames.clone().or(settings.plan_frames);
    if let Some(list) = &flags.aovs {
        settings.aovs = Aov::parse_list(list)
            .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--aovs {list}: {fault}")))?;
    }
    if let Some(h) = flags.h {
        let fault = LightMeshSettings::h_fault(h);
        let fault = fault.map(|fault| anyhow::anyhow!("--h {h}: {fault}"));
        fault.map_or(Ok(()), |fault| Err(Failure::bad_input(fault)))?;
        settings.lightmesh.h = Some(h);
    }
    if let Some(ki) = flags.ki {
        let fault = LightMeshSettings::ki_fault(ki);
        let fault = fault.map(|fault| anyhow::anyhow!("--ki {ki}: {fault}"));
        fault.map_or(Ok(()), |fault| Err(Failure::bad_input(fault)))?;
        settings.lightmesh.ki = ki;
    }
    if let Some(kernel) = flags.kernel {
        settings.lightmesh.kernel = kernel;
    }
    if let Some(penumbra) = flags.penumbra {
        settings.lightmesh.penumbra = penumbra;
    }
    if let Some(share) = flags.faint_lamps {
        let fault = LightMeshSettings::faint_lamps_fault(share);
        let fault = fault.map(|fault| anyhow::anyhow!("--faint-lamps {share}: {fault}"));
        fault.map_or(Ok(()), |fault| Err(Failure::bad_input(fault)))?;
        settings.lightmesh.faint_lamps = share;
    }
    if flags.no_cache {
        settings.cache_dir = None;
    } else if let Some(dir) = &flags.cache {
        settings.cache_dir = Some(dir.clone());
    }
    if flags.exr_float {
        settings.exr_precision = ExrPrecision::Float;
    }
    settings.validate().map_err(Failure::bad_input)?;
    Ok(settings)
}

/// `lmanim plan`: the effect plan on stdout, as text or JSON.
fn run_plan(args: &PlanArgs) -> Result<(), Failure> {
    let cli = &args.render;
    let settings = resolve_settings(cli)?;
    let frames = FrameSet::parse(&cli.frames)
        .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--frames {}: {fault}", cli.frames)))?;
    let pattern = FramePattern::parse(&default_pattern(&cli.scene))
        .map_err(|fault| Failure::bad_input(anyhow::anyhow!("{fault}")))?;
    let job = Job {
        scene_path: &cli.scene,
        settings: &settings,
        frames: &frames,
        pattern: &pattern,
    };
    let plan = planned(&job)?;
    match args.json {
        true => println!("{}", plan::report::json(&plan)),
        false => print!("{}", plan::report::text(&plan)),
    }
    Ok(())
}

/// The effect plan of `job`, its errors as the run's.
fn planned(job: &Job) -> Result<plan::Plan, Failure> {
    sequence::plan(job).map_err(|error| Failure {
        bad_input: error.is_bad_input(),
        error: error.into(),
    })
}

fn run_warm(cli: &RenderArgs) -> Result<(), Failure> {
    let settings = resolve_settings(cli)?;
    let frames = FrameSet::parse(&cli.frames)
        .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--frames {}: {fault}", cli.frames)))?;
    let pattern = FramePattern::parse(&default_pattern(&cli.scene))
        .map_err(|fault| Failure::bad_input(anyhow::anyhow!("{fault}")))?;
    let job = Job {
        scene_path: &cli.scene,
        settings: &settings,
        frames: &frames,
        pattern: &pattern,
    };
    let warm = sequence::warm(&job).map_err(|error| Failure {
        bad_input: error.is_bad_input(),
        error: error.into(),
    })?;
    if !cli.quiet {
        let cache = settings.cache_dir.as_deref().unwrap_or_default();
        eprintln!(
            "warmed {} frame(s) in {:.2} s: {} mask bits computed, {} loaded; cache {cache}",
            warm.frames, warm.seconds, warm.bits_computed, warm.bits_loaded
        );
    }
    Ok(())
}

fn run_inspect(args: &InspectArgs) -> Result<(), Failure> {
    // The error's own line names the file and the fault; its sources
    // would only repeat them.
    let scene = import::load(&args.scene)
        .map_err(|error| Failure::bad_input(anyhow::anyhow!("{error}")))?;
    let clips = match &args.clip {
        None => ClipSelection::All,
        Some(text) => ClipSelection::parse(&scene, text)
            .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--clip {text}: {fault}")))?,
    };
    let times = match &args.times {
        Some(text) => parse_times(text)
            .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--times {text}: {fault}")))?,
        None => {
            let text = args.frames.as_deref().unwrap_or("0");
            let frames = FrameSet::parse(text)
                .map_err(|fault| Failure::bad_input(anyhow::anyhow!("--frames {text}: {fault}")))?;
            let timeline = Timeline {
                fps: scene_fps(&args.scene, args.fps)?,
            };
            frames
                .frames()
                .iter()
                .map(|&frame| timeline.time_of(frame))
                .collect()
        }
    };
    let report = inspect(&scene, clips, &times);
    let mut stdout = std::io::stdout().lock();
    serde_json::to_writer_pretty(&mut stdout, &report).context("writing the report")?;
    writeln!(stdout).context("writing the report")?;
    Ok(())
}

/// `lmanim study`: progress on stderr, results in --out.
fn run_study(args: &StudyArgs) -> Result<(), Failure> {
    let options = StudyOptions {
        scene: args.scene.clone(),
        frame: args.frame,
        width: args.width,
        height: args.height,
        reference: args.reference.clone(),
        reference_mask: args.reference_mask.clone(),
        reference_layer: args.reference_layer.clone(),
        reference_spp: args.reference_spp,
        methods: args.methods.clone(),
        candidates: args.candidates.clone(),
        out: args.out.clone(),
        threads: args.threads,
    };
    study::run(&options, |line| {
        if !args.quiet {
            eprintln!("study: {line}");
        }
    })
    .map_err(|error| Failure {
        bad_input: error.is_bad_input(),
        error: error.into(),
    })?;
    if !args.quiet {
        eprintln!("study: results in {}", args.out.display());
    }
    Ok(())
}

/// Comma-separated finite seconds.
fn parse_times(text: &str) -> Result<Vec<f64>, String> {
    text.split(',')
        .map(|item| match item.trim().parse::<f64>() {
            Ok(time) if time.is_finite() => Ok(time),
            _ => Err(format!(
                "'{}' is not a finite number of seconds",
                item.trim()
            )),
        })
        .collect()
}

/// `lmanim bake-camera`: the scene with the path's camera to --out.
fn run_bake(args: &BakeArgs) -> Result<(), Failure> {
    let path = camera_path(args.camera_path.as_deref(), args.orbit.as_deref())?;
    let path = path.ok_or_else(|| {
        Failure::bad_input(anyhow::anyhow!(
            "bake-camera needs a path: --camera-path PATH.ron or --orbit"
        ))
    })?;
    let fps = scene_fps(&args.scene, args.fps)?;
    let name = bake::bake(&args.scene, &path, fps, &args.out).map_err(|error| Failure {
        bad_input: error.is_bad_input(),
        error: error.into(),
    })?;
    eprintln!(
        "baked camera '{name}' to {} (render it with --camera {name})",
        args.out.display()
    );
    Ok(())
}

/// The camera path of `--camera-path FILE` or `--orbit TEXT`, if either.
fn camera_path(file: Option<&Path>, orbit: Option<&str>) -> Result<Option<CameraPath>, Failure> {
    let path = match (file, orbit) {
        (Some(file), _) => CameraPath::load(file),
        (None, Some(text)) => CameraPath::orbit(text),
        (None, None) => return Ok(None),
    };
    path.map(Some).map_err(Failure::bad_input)
}

/// `fps` (the --fps flag), else the fps of the scene's sibling settings
/// file, else the default: the same frame times a render of the scene
/// would use.
fn scene_fps(scene: &Path, fps: Option<f64>) -> Result<f64, Failure> {
    let sibling = scene.with_extension("ron");
    let fps = match fps {
        Some(fps) => fps,
        None if sibling.is_file() => Settings::load(&sibling).map_err(Failure::bad_input)?.fps,
        None => Settings::default().fps,
    };
    if fps.is_finite() && fps > 0.0 {
        Ok(fps)
    } else {
        Err(Failure::bad_input(anyhow::anyhow!(
            "--fps {fps}: it must be a positive number"
        )))
    }
}

fn default_pattern(scene: &Path) -> String {
    let stem = scene
        .file_stem()
        .map_or("scene".into(), |stem| stem.to_string_lossy());
    format!("renders/{stem}/frame.####.exr")
}

/// Says what a fresh machine waits for before its first GPU frame: on
/// the bar while the pipelines compile (a farm's log, which has no bar,
/// gets a line when they begin), and a line once they are done.
fn report_compile(progress: &ProgressBar, quiet: bool, compiled: usize, of: usize, seconds: f64) {
    progress.set_message(format!("compiling GPU pipelines {compiled}/{of}"));
    if quiet {
        return;
    }
    if compiled == 0 && progress.is_hidden() {
        eprintln!("compiling {of} GPU pipelines (minutes on a machine that never ran lmanim)");
    }
    if compiled == of {
        progress.suspend(|| eprintln!("GPU pipelines: {of} compiled in {seconds:.1} s"));
    }
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
    let skipped = match stats.skipped.len() {
        0 => String::new(),
        count => format!("; skipped {count} frame(s) already on disk"),
    };
    format!(
        "rendered {} frame(s) with {} on {} thread(s) in {:.2} s ({:.3} s/frame, {:.2} Mrays/s) to {}{skipped}",
        stats.frames.len(),
        stats.method,
        stats.threads,
        stats.total_seconds,
        stats.total_seconds / frames,
        rays as f64 / stats.total_seconds.max(1e-9) / 1e6,
        pattern
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The setting each flag overrides, as a path into
    /// `Settings::default()` serialised: found apart from
    /// [`setting_defaults`], so a flag documented from the wrong field
    /// shows.
    const SETTING_OF_FLAG: [(&str, &str); 14] = [
        ("--fps", "/fps"),
        ("--method", "/method"),
        ("--backend", "/backend"),
        ("--width", "/width"),
        ("--height", "/height"),
        ("--spp", "/spp"),
        ("--ki", "/lightmesh/ki"),
        ("--kernel", "/lightmesh/kernel"),
        ("--penumbra", "/lightmesh/penumbra"),
        ("--faint-lamps", "/lightmesh/faint_lamps"),
        ("--exposure", "/exposure"),
        ("--sheet-columns", "/sheet_columns"),
        ("--sheet-every", "/sheet_every"),
        ("--cache", "/cache_dir"),
    ];

    /// The `(flag, value)` of every `[default: value]` in `command`'s long
    /// help, as a user reads it.
    fn documented_defaults(command: &mut clap::Command) -> Vec<(String, String)> {
        let help = command.render_long_help().to_string();
        let mut flag = String::new();
        let mut found = Vec::new();
        for line in help.lines() {
            let words: Vec<&str> = line.split_whitespace().collect();
            let named = (words.iter().take(2)).find(|word| word.starts_with("--"));
            // Flags start within 6 columns, their help further in.
            let indent = line.len() - line.trim_start().len();
            if indent <= 6 && words.first().is_some_and(|w| w.starts_with('-')) {
                flag = named
                    .map_or("", |word| word.trim_end_matches(','))
                    .to_owned();
            }
            let mut rest = line;
            while let Some(start) = rest.find("[default: ") {
                let value = &rest[start + "[default: ".len()..];
                let end = value.find(']').expect("a closed [default: …]");
                found.push((flag.clone(), value[..end].to_owned()));
                rest = &value[end..];
            }
        }
        found
    }

    /// The value `settings` gives `flag`, as the flag would take it, if
    /// the flag overrides a setting.
    fn setting_value(settings: &Settings, flag: &str) -> Option<String> {
        let (_, pointer) = SETTING_OF_FLAG.iter().find(|(name, _)| *name == flag)?;
        let json = serde_json::to_value(settings).unwrap();
        Some(match json.pointer(pointer).unwrap() {
            serde_json::Value::String(text) => text.clone(),
            serde_json::Value::Number(number) => number.as_f64().unwrap().to_string(),
            other => panic!("{flag}: a default of {other}"),
        })
    }

    /// Every documented default of every command that differs from
    /// `settings` (for a flag overriding a setting) or from clap's own
    /// default (for the others), and every flag overriding a setting
    /// that documents none.
    fn drift(settings: &Settings) -> Vec<String> {
        let mut root = command();
        let names: Vec<String> = (root.get_subcommands())
            .map(|sub| sub.get_name().to_owned())
            .collect();
        let mut commands = vec![root.clone()];
        commands.extend(
            names
                .iter()
                .map(|name| root.find_subcommand_mut(name).unwrap().clone()),
        );
        let mut faults = Vec::new();
        for mut command in commands {
            let documented = documented_defaults(&mut command);
            for (flag, value) in &documented {
                let clap_own = (command.get_arguments())
                    .find(|arg| {
                        arg.get_long()
                            .is_some_and(|long| format!("--{long}") == *flag)
                    })
                    .map(|arg| {
                        let values: Vec<String> = (arg.get_default_values().iter())
                            .map(|value| value.to_string_lossy().into_owned())
                            .collect();
                        values.join(",")
                    });
                let expected = setting_value(settings, flag).or(clap_own);
                if expected.as_deref() != Some(value.as_str()) {
                    faults.push(format!(
                        "{} {flag}: documented {value}, is {expected:?}",
                        command.get_name()
                    ));
                }
            }
            for arg in command.get_arguments() {
                let flag = arg
                    .get_long()
                    .map(|long| format!("--{long}"))
                    .unwrap_or_default();
                let overrides = setting_value(settings, &flag).is_some();
                if overrides && !documented.iter().any(|(name, _)| *name == flag) {
                    faults.push(format!(
                        "{} {flag}: no default documented",
                        command.get_name()
                    ));
                }
            }
        }
        faults
    }

    #[test]
    fn every_documented_default_is_the_settings_default() {
        assert_eq!(drift(&Settings::default()), Vec::<String>::new());
        let mut help = command();
        let penumbra = documented_defaults(&mut help);
        assert!(
            penumbra.contains(&("--penumbra".into(), "wide".into())),
            "{penumbra:?}"
        );
    }

    #[test]
    fn a_default_changed_without_its_doc_is_drift() {
        let mut changed = Settings::default();
        changed.lightmesh.penumbra = Penumbra::Blocker;
        changed.fps = 30.0;
        let faults = drift(&changed);
        assert!(
            faults
                .iter()
                .any(|fault| fault.contains("--penumbra: documented wide")),
            "{faults:?}"
        );
        assert!(
            faults
                .iter()
                .any(|fault| fault.contains("--fps: documented 24")),
            "{faults:?}"
        );
    }

    /// The rows of the README's flag table ("Command line"): the flags of
    /// the first cell, and the row.
    fn readme_flag_rows() -> Vec<(Vec<String>, String)> {
        let readme = include_str!("../README.md");
        let section = &readme[readme
            .find("\n## Command line")
            .expect("a Command line section")..];
        let section = &section[..section[1..]
            .find("\n#")
            .map_or(section.len(), |end| end + 1)];
        (section.lines())
            .filter(|line| line.starts_with("| `"))
            .map(|row| {
                let first = row.split('|').nth(1).unwrap_or("");
                let flags = (first.split('`').skip(1).step_by(2))
                    .map(str::to_owned)
                    .collect();
                (flags, row.to_owned())
            })
            .collect()
    }

    /// Whether `text` holds `value` as a word of its own after a
    /// "default".
    fn says_default(text: &str, value: &str) -> bool {
        let Some(start) = text.find("default") else {
            return false;
        };
        let text = &text[start..];
        let word = |c: char| c.is_alphanumeric() || c == '.' || c == '_';
        text.match_indices(value).any(|(at, _)| {
            let before = text[..at].chars().next_back().is_none_or(|c| !word(c));
            let after = text[at + value.len()..]
                .chars()
                .next()
                .is_none_or(|c| !word(c));
            before && after
        })
    }

    #[test]
    fn the_readme_flag_table_lists_the_flags_and_defaults_of_help() {
        let rows = readme_flag_rows();
        let mut in_readme: Vec<String> = rows.iter().flat_map(|(flags, _)| flags.clone()).collect();
        in_readme.sort();
        let root = command();
        let mut in_help: Vec<String> = (root.get_arguments())
            .filter(|arg| !["help", "version"].contains(&arg.get_id().as_str()))
            .map(|arg| match arg.get_long() {
                Some(long) => format!("--{long}"),
                None => arg.get_id().as_str().to_uppercase(),
            })
            .collect();
        in_help.sort();
        assert_eq!(in_readme, in_help, "README's flag table against --help");
        for (flag, value) in documented_defaults(&mut command()) {
            let (_, row) = (rows.iter())
                .find(|(flags, _)| flags.contains(&flag))
                .expect("every flag has a row");
            assert!(
                says_default(row, &value),
                "the README's {flag} does not say default {value}: {row}"
            );
        }
    }
}
