//! `lmanim study`: what accuracy costs in time, on one frame of a user's
//! scene. It renders a reference (the Monte Carlo lamps at many samples,
//! or a ground-truth EXR from another renderer), then the sweep of
//! [`sweep::plan`]: every method at the settings a user would choose
//! between, each timed in this process on a warm machine, and then the
//! [`candidate`]s, frames made elsewhere and timed there. Each frame's
//! error against the reference is [`measure`]'s; the tables are
//! [`report`]'s, the default's standing against `area` [`verdict`]'s and
//! the pictures [`plot`]'s.
//!
//! It sits beside the frame loop, not in it: it drives [`Sequence`] one
//! frame at a time, a fresh sequence per run, so that every run starts as
//! a first frame does (no masks yet) and is timed from its light mesh's
//! making to its last pixel. Nothing is read from or written to the light
//! mesh's disk cache.

pub mod candidate;
pub mod measure;
pub mod plot;
pub mod report;
pub mod sweep;
pub mod verdict;

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::backend::{Backend, BackendError, CpuBackend};
use crate::import;
use crate::lightmesh::spacing::median_lamp_radius;
use crate::output::{self, ExrPicture, ExrPrecision, Image, OutputError};
use crate::render::frame::FrameScene;
use crate::scene::SceneDesc;
use crate::schedule::Timeline;
use crate::sequence::{RunError, Sequence};
use crate::settings::{BackendKind, Method, Settings, SettingsError};
use crate::stats::FrameStats;
use candidate::Candidate;
use measure::{Mask, Reference, SizeMismatch};
use plot::{Crop, PlotError};
use report::{ReferenceReport, StudyReport};
use sweep::{RunResult, RunSpec, Source};

/// Samples per pixel of the default reference: 16 times the densest
/// `area` run of the sweep (64), so that its Monte Carlo noise is about a
/// quarter of that run's error, the smallest error the sweep usually
/// ranks (`estimated_noise` in `study.json` says what it was).
pub const DEFAULT_REFERENCE_SPP: u32 = 1024;

/// Samples per pixel of the unshadowed frame averaged over each pixel,
/// enough to tell a geometric edge from a flat pixel.
const EDGE_SPP: u32 = 16;

/// A run faster than this is repeated (fresh each time) and its fastest
/// time kept, so that short runs are not ranked by scheduler noise.
const REPEAT_BELOW_SECONDS: f64 = 1.0;
const MAX_REPEATS: usize = 3;

/// What to study and where the results go.
#[derive(Clone, Debug, PartialEq)]
pub struct StudyOptions {
    pub scene: PathBuf,
    /// The frame number, at the settings' fps.
    pub frame: u32,
    /// Image size; None keeps the settings file's (or the default).
    pub width: Option<u32>,
    pub height: Option<u32>,
    /// A ground-truth EXR to measure against instead of rendering one,
    /// with an optional mask EXR (the pixels [`measure::Mask`] says are
    /// left out).
    pub reference: Option<PathBuf>,
    pub reference_mask: Option<PathBuf>,
    /// The reference's layer (a part's name or a channel prefix); None
    /// takes its beauty. The mask is always read from its beauty.
    pub reference_layer: Option<String>,
    /// Samples per pixel of a rendered reference.
    pub reference_spp: u32,
    /// Methods to sweep, in the order they are run and drawn.
    pub methods: Vec<Method>,
    /// Frames made elsewhere, measured after the sweep.
    pub candidates: Vec<Candidate>,
    pub out: PathBuf,
    /// Worker threads; None uses every core.
    pub threads: Option<usize>,
}

/// Why a study stopped.
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    #[error(transparent)]
    Settings(#[from] SettingsError),
    #[error(transparent)]
    Run(#[from] RunError),
    #[error(transparent)]
    Backend(#[from] BackendError),
    #[error("{0}")]
    Usage(String),
    #[error("{file}: no light has a lamp radius, so no shadow is soft and there is nothing to study (give lights extras.radius or set lamps.default_radius)")]
    NoLampRadius { file: String },
    #[error(transparent)]
    ReadReference(OutputError),
    #[error("candidate {name:?}: {source}")]
    ReadCandidate { name: String, source: OutputError },
    #[error("{file}: {source}")]
    Size { file: String, source: SizeMismatch },
    #[error("{file}: {fault}")]
    NothingToMeasure { file: String, fault: String },
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error(transparent)]
    Plot(#[from] PlotError),
}

impl StudyError {
    /// The user's mistakes (exit code 2), as opposed to the machine's.
    pub fn is_bad_input(&self) -> bool {
        match self {
            StudyError::Run(error) => error.is_bad_input(),
            StudyError::Settings(_)
            | StudyError::Usage(_)
            | StudyError::NoLampRadius { .. }
            | StudyError::ReadReference(_)
            | StudyError::ReadCandidate { .. }
            | StudyError::Size { .. }
            | StudyError::NothingToMeasure { .. } => true,
            StudyError::Backend(_) | StudyError::Output(_) | StudyError::Plot(_) => false,
        }
    }
}

/// Runs the study of `options`, writing `study.json`, `study.csv`,
/// `study.png`, `crops.png` and the reference (`reference.exr`) to
/// `options.out`; `progress` hears one line per step. Candidates' frames
/// are read before anything is rendered, so that a wrong path stops the
/// study at once.
pub fn run(
    options: &StudyOptions,
    mut progress: impl FnMut(&str),
) -> Result<StudyReport, StudyError> {
    if options.methods.is_empty() {
        return Err(StudyError::Usage("--methods names no method".into()));
    }
    if options.reference_spp == 0 {
        return Err(StudyError::Usage(
            "--reference-spp is 0; it must be at least 1".into(),
        ));
    }
    let settings = base_settings(options)?;
    let scene_file = options.scene.display().to_string();
    let mut bench = Bench {
        scene: import::load(&options.scene).map_err(RunError::from)?,
        scene_file: scene_file.clone(),
        time: Timeline { fps: settings.fps }.time_of(options.frame),
        backend: Backend::new(BackendKind::Cpu, options.threads)?,
    };
    let (_, placed) = bench.fresh(&settings)?;
    let lamp_radius =
        median_lamp_radius(&placed.lights).ok_or_else(|| StudyError::NoLampRadius {
            file: scene_file.clone(),
        })?;

    let candidates = options
        .candidates
        .iter()
        .map(read_candidate)
        .collect::<Result<Vec<_>, _>>()?;
    let (reference, mut reference_report) =
        bench.reference(options, &settings, lamp_radius, &mut progress)?;
    let reference_path = options.out.join("reference.exr");
    output::write_exr(&reference_path, &reference.image, ExrPrecision::Float)?;

    let specs = sweep::plan(&options.methods, lamp_radius, settings.lightmesh.ki);
    let mut runs = Vec::with_capacity(specs.len());
    // Per method, the most accurate run in the penumbra and its frame.
    let mut best: Vec<(RunSpec, Image, f64)> = Vec::new();
    // A light-mesh method's run at the default lattice: what a user gets
    // without tuning, cropped beside its best.
    let mut defaults: Vec<(RunSpec, Image, f64)> = Vec::new();
    for (index, spec) in specs.iter().enumerate() {
        let (image, seconds, h) = bench.timed(&spec.settings(&settings))?;
        let errors = reference
            .errors(&image)
            .map_err(|source| StudyError::Size {
                file: scene_file.clone(),
                source,
            })?;
        progress(&format!(
            "[{}/{}] {}: {seconds:.3} s, RMSE {:.4}, penumbra RMSE {}",
            index + 1,
            specs.len(),
            spec.label(),
            errors.rmse,
            errors
                .penumbra_rmse
                .map_or("-".into(), |e| format!("{e:.4}")),
        ));
        let accuracy = errors.penumbra_rmse.unwrap_or(errors.rmse);
        let default_lattice = spec.method.uses_light_mesh() && spec.h.is_none();
        if default_lattice {
            defaults.push((*spec, image.clone(), accuracy));
        }
        match best
            .iter_mut()
            .find(|(kept, ..)| kept.method == spec.method)
        {
            Some(kept) if kept.2 <= accuracy => {}
            Some(kept) => *kept = (*spec, image, accuracy),
            None => best.push((*spec, image, accuracy)),
        }
        runs.push(RunResult {
            source: Source::Method(spec.method),
            h: h.or(spec.h),
            ki: spec.ki,
            spp: spec.spp,
            seconds,
            errors,
            default_lattice,
            pareto: false,
            frames: 1,
            flicker: None,
        });
    }
    // Per family of candidates, its most accurate one's first frame.
    let mut best_candidates: Vec<(String, Image, f64)> = Vec::new();
    for (candidate, frames) in options.candidates.iter().zip(candidates) {
        let (errors, flicker) =
            reference
                .sequence_errors(&frames)
                .map_err(|source| StudyError::Size {
                    file: candidate.frames[0].display().to_string(),
                    source,
                })?;
        progress(&format!(
            "candidate {}: {:.3} s, RMSE {:.4}, penumbra RMSE {}{}",
            candidate.name,
            candidate.seconds,
            errors.rmse,
            errors
                .penumbra_rmse
                .map_or("-".into(), |e| format!("{e:.4}")),
            flicker.map_or(String::new(), |f| format!(
                ", flicker {:.4} over {} frames",
                f.lit,
                frames.len()
            )),
        ));
        let accuracy = errors.penumbra_rmse.unwrap_or(errors.rmse);
        let family = Candidate::family(&candidate.name);
        let count = frames.len();
        let first = frames.into_iter().next().expect("a candidate has a frame");
        match (best_candidates.iter_mut()).find(|(kept, ..)| Candidate::family(kept) == family) {
            Some(kept) if kept.2 <= accuracy => {}
            Some(kept) => *kept = (candidate.name.clone(), first, accuracy),
            None => best_candidates.push((candidate.name.clone(), first, accuracy)),
        }
        runs.push(RunResult {
            source: Source::Candidate(candidate.name.clone()),
            h: None,
            ki: None,
            spp: 1,
            seconds: candidate.seconds,
            errors,
            default_lattice: false,
            pareto: false,
            frames: count,
            flicker,
        });
    }
    sweep::mark_pareto_front(&mut runs);
    reference_report.estimated_noise = estimated_noise(&reference_report, &runs);
    let default_verdict = verdict::judge_default(&runs);
    for line in default_verdict.iter().flat_map(|verdict| verdict.lines()) {
        progress(&line);
    }

    let report = StudyReport {
        reference: reference_report,
        runs,
        default_verdict,
    };
    report.write_json(&options.out.join("study.json"))?;
    report.write_csv(&options.out.join("study.csv"))?;
    plot::error_against_time(
        &options.out.join("study.png"),
        &report.runs,
        &options.methods,
    )?;
    let mut crops = vec![Crop {
        image: &reference.image,
        title: "reference".into(),
        figures: reference_label(&report.reference),
    }];
    for (spec, image, accuracy) in &best {
        let default = defaults
            .iter()
            .find(|(kept, ..)| kept.method == spec.method);
        if let Some((default, image, accuracy)) = default.filter(|(kept, ..)| kept != spec) {
            crops.push(Crop {
                image,
                title: default.label(),
                figures: format!("penumbra RMSE {accuracy:.4}"),
            });
        }
        crops.push(Crop {
            image,
            title: spec.label(),
            figures: format!("penumbra RMSE {accuracy:.4}"),
        });
    }
    for (name, image, accuracy) in &best_candidates {
        crops.push(Crop {
            image,
            title: name.clone(),
            figures: format!("penumbra RMSE {accuracy:.4}"),
        });
    }
    plot::penumbra_crops(&options.out.join("crops.png"), &reference, &crops)?;
    Ok(report)
}

/// The scene's settings file (its sibling `.ron`, if any) with the
/// study's image size; method, samples and lattice are each run's.
fn base_settings(options: &StudyOptions) -> Result<Settings, StudyError> {
    let sibling = options.scene.with_extension("ron");
    let mut settings = match sibling.is_file() {
        true => Settings::load(&sibling)?,
        false => Settings::default(),
    };
    settings.width = options.width.unwrap_or(settings.width);
    settings.height = options.height.unwrap_or(settings.height);
    settings.backend = BackendKind::Cpu;
    settings.threads = options.threads;
    settings.validate()?;
    Ok(settings)
}

/// The scene loaded once, the frame's time and the backend every run
/// renders on.
struct Bench {
    scene: SceneDesc,
    scene_file: String,
    time: f64,
    backend: Backend,
}

impl Bench {
    /// A sequence with no light mesh yet, and the study's frame placed.
    fn fresh(&self, settings: &Settings) -> Result<(Sequence, FrameScene), RunError> {
        let mut sequence = Sequence::new(self.scene.clone(), self.scene_file.clone())?;
        let placed = sequence.advance(self.time, settings, &mut FrameStats::default())?;
        Ok((sequence, placed))
    }

    /// Renders the frame with `settings` from a fresh sequence; returns
    /// the image, the fastest of its repeats in seconds, and the lattice
    /// step the light mesh used (if any).
    fn timed(&mut self, settings: &Settings) -> Result<(Image, f64, Option<f32>), RunError> {
        let mut fastest = f64::INFINITY;
        let mut spent = 0.0;
        let mut frame = None;
        for _ in 0..MAX_REPEATS {
            let (mut sequence, placed) = self.fresh(settings)?;
            let mut stats = FrameStats::default();
            let started = Instant::now();
            let image = sequence.render(&mut self.backend, &placed, settings, &mut stats)?;
            let seconds = started.elapsed().as_secs_f64();
            fastest = fastest.min(seconds);
            spent += seconds;
            frame = Some((image, stats.lightmesh.map(|mesh| mesh.h)));
            if spent >= REPEAT_BELOW_SECONDS {
                break;
            }
        }
        let (image, h) = frame.expect("at least one repeat ran");
        Ok((image, fastest, h))
    }

    /// The reference, from the file given or rendered by `area`, with the
    /// unshadowed frames its measure needs.
    fn reference(
        &mut self,
        options: &StudyOptions,
        settings: &Settings,
        lamp_radius: f32,
        progress: &mut impl FnMut(&str),
    ) -> Result<(Reference, ReferenceReport), StudyError> {
        let mut report = ReferenceReport {
            source: "area".into(),
            spp: None,
            seconds: None,
            estimated_noise: None,
            scene: self.scene_file.clone(),
            frame: options.frame,
            width: settings.width,
            height: settings.height,
            lamp_radius,
            census: Default::default(),
        };
        let (image, mask) = match &options.reference {
            Some(path) => {
                report.source = path.display().to_string();
                progress(&format!("reference: {}", path.display()));
                let mask = (options.reference_mask.as_deref())
                    .map(|mask| read_reference(mask, None))
                    .transpose()?;
                let layer = options.reference_layer.as_deref();
                (
                    read_reference(path, layer)?.image,
                    mask.as_ref().map(Mask::of),
                )
            }
            None => {
                let spp = options.reference_spp;
                progress(&format!("reference: area at {spp} spp"));
                let area = Settings {
                    method: Method::Area,
                    spp,
                    ..settings.clone()
                };
                let (mut sequence, placed) = self.fresh(&area)?;
                let started = Instant::now();
                let image = sequence.render(
                    &mut self.backend,
                    &placed,
                    &area,
                    &mut FrameStats::default(),
                )?;
                let seconds = started.elapsed().as_secs_f64();
                progress(&format!("reference: {seconds:.1} s"));
                report.spp = Some(spp);
                report.seconds = Some(seconds);
                (image, None)
            }
        };
        let unshadowed = |spp: u32| -> Result<Image, StudyError> {
            let settings = Settings {
                spp,
                ..settings.clone()
            };
            let (sequence, placed) = self.fresh(&settings)?;
            let cpu = CpuBackend::new(settings.threads)?;
            Ok(sequence.render_unshadowed(&cpu, &placed, &settings, &mut FrameStats::default()))
        };
        let (centre, area) = (unshadowed(1)?, unshadowed(EDGE_SPP)?);
        let file = options
            .reference
            .as_ref()
            .map_or(self.scene_file.clone(), |path| path.display().to_string());
        let reference = Reference::new(image, &centre, &area, mask.as_ref()).map_err(|source| {
            StudyError::Size {
                file: file.clone(),
                source,
            }
        })?;
        if let Some(fault) = reference.census.nothing_to_measure() {
            return Err(StudyError::NothingToMeasure { file, fault });
        }
        report.census = reference.census;
        progress(&format!(
            "reference: {} lit pixels, {} in penumbra, {} edge pixels left out",
            reference.census.lit_pixels,
            reference.census.penumbra_pixels,
            reference.census.edge_pixels
        ));
        Ok((reference, report))
    }
}

fn read_reference(path: &Path, layer: Option<&str>) -> Result<ExrPicture, StudyError> {
    output::read_exr_picture(path, layer).map_err(StudyError::ReadReference)
}

/// A candidate's frames, each its file's beauty.
fn read_candidate(candidate: &Candidate) -> Result<Vec<Image>, StudyError> {
    (candidate.frames.iter())
        .map(|frame| {
            output::read_exr_picture(frame, None)
                .map(|picture| picture.image)
                .map_err(|source| StudyError::ReadCandidate {
                    name: candidate.name.clone(),
                    source,
                })
        })
        .collect()
}

/// The rendered reference's own RMSE, from the densest `area` run at s
/// samples: its error holds the noise of both, σ²/s + σ²/N, so the
/// reference's (σ/√N) is that error over √(N/s + 1).
fn estimated_noise(reference: &ReferenceReport, runs: &[RunResult]) -> Option<f64> {
    let n = f64::from(reference.spp?);
    let densest = runs
        .iter()
        .filter(|run| run.method() == Some(Method::Area))
        .max_by_key(|run| run.spp)?;
    Some(densest.errors.rmse / (n / f64::from(densest.spp) + 1.0).sqrt())
}

fn reference_label(reference: &ReferenceReport) -> String {
    match reference.spp {
        Some(spp) => format!("area {spp} spp"),
        None => Path::new(&reference.source)
            .file_name()
            .map_or(reference.source.clone(), |name| {
                name.to_string_lossy().into_owned()
            }),
    }
}
