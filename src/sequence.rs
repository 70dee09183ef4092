//! The frame loop: load a scene once, build its ray-tracing world once, then
//! for each requested frame pose and place the scene, bring the world and
//! the light mesh up to it, render it on the backend and write the frame.
//! This is the only place that knows about time; the integrators see one
//! frame at a time. What changed between two frames, and how the world
//! follows, is [`FrameDelta`]'s; the light mesh's reuse across frames and
//! its disk cache are [`PersistentLightMesh`]'s.

use std::path::{Path, PathBuf};
use std::time::Instant;

use crate::accel::World;
use crate::anim::pose::ClipSelection;
use crate::backend::{Backend, BackendError, CpuBackend, RenderError};
use crate::import::{self, ImportError};
use crate::lightmesh::persistent::PersistentLightMesh;
use crate::lightmesh::{LightMesh, LightMeshError};
use crate::output::{
    self, BackgroundWriter, ContactSheet, FrameFiles, FramePattern, OutputError, RenderedFrame,
    ShotSheet,
};
use crate::plan::Plan;
use crate::render::frame::{CameraChoice, FrameScene, PlaceError, SceneBounds};
use crate::render::shadow_split::{FrameMethod, ShadowSplit};
use crate::render::FrameJob;
use crate::scene::pose::{dynamic_nodes, Pose};
use crate::scene::SceneDesc;
use crate::schedule::{FrameDelta, FrameSet, Timeline};
use crate::settings::{Method, Settings};
use crate::stats::{FrameStats, RunStats, StaticSet};

/// Why a run stopped. `is_bad_input` separates the user's mistakes (exit
/// code 2) from failures of the machine (exit code 1).
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error(transparent)]
    Import(#[from] ImportError),
    #[error("{file}: {source}")]
    Place { file: String, source: PlaceError },
    #[error("{file}: {source}")]
    LightMesh {
        file: String,
        source: LightMeshError,
    },
    #[error("{file}: --clip {fault}")]
    Clip { file: String, fault: String },
    #[error("the output pattern '{0}' has no '#' placeholder, so several frames would overwrite one file")]
    PatternWithoutPlaceholder(String),
    #[error("sheet_frames: {0}")]
    SheetFrames(String),
    #[error("{path}: {fault}")]
    SheetSize { path: String, fault: String },
    #[error(transparent)]
    Output(#[from] OutputError),
    #[error(transparent)]
    Backend(#[from] BackendError),
    #[error(transparent)]
    Render(RenderError),
    #[error("--plan-frames {planned} does not hold frame {frame}, which the run renders")]
    PlanFramesMissFrame { planned: String, frame: u32 },
    #[error("--plan-frames {0}")]
    PlanFrames(String),
    #[error("warm fills the light mesh's disk cache, and --method {0} has no light mesh here (use lmm or lmm1, or auto on a scene with lamps that have a radius)")]
    WarmWithoutLightMesh(Method),
    #[error("warm fills the light mesh's disk cache, and --no-cache leaves it none to fill")]
    WarmWithoutCache,
}

impl RunError {
    pub fn is_bad_input(&self) -> bool {
        matches!(
            self,
            RunError::Import(_)
                | RunError::Place { .. }
                | RunError::LightMesh { .. }
                | RunError::Clip { .. }
                | RunError::PatternWithoutPlaceholder(_)
                | RunError::SheetFrames(_)
                | RunError::SheetSize { .. }
                | RunError::WarmWithoutLightMesh(_)
                | RunError::PlanFramesMissFrame { .. }
                | RunError::PlanFrames(_)
                | RunError::WarmWithoutCache
        )
    }
}

/// What one run renders and where it goes.
pub struct Job<'a> {
    pub scene_path: &'a Path,
    pub settings: &'a Settings,
    pub frames: &'a FrameSet,
    pub pattern: &'a FramePattern,
}

/// What a run reports as it goes, for progress lines.
pub enum RunEvent<'a> {
    /// The GPU pipelines the frames need are being compiled before the
    /// first: `compiled` of `of` are done, `seconds` after the first was
    /// begun (reported once with 0 done before any is).
    Compiling {
        compiled: usize,
        of: usize,
        seconds: f64,
    },
    /// A frame's files are written, or it was skipped.
    Frame(FrameDone<'a>),
}

/// A frame has been written: what a run reports of it.
pub struct FrameDone<'a> {
    /// Position of the frame in the run (0 for the first).
    pub index: usize,
    pub stats: &'a FrameStats,
    pub path: &'a Path,
    /// The scene brought no camera; an automatic one framed it.
    pub automatic_camera: bool,
    /// The GPU adapter the run renders on, if any.
    pub adapter: Option<&'a str>,
    /// The frame was on disk already and not rendered (`skip_existing`).
    pub skipped: bool,
}

/// A loaded scene with its world built, ready to render frames.
pub struct Sequence {
    scene: SceneDesc,
    scene_file: String,
    world: World,
    anchor: glam::DVec3,
    /// Radius of the scene's bounding sphere at rest, in metres.
    scene_radius: f32,
    /// The light mesh, made on the first LMM frame and kept so that later
    /// frames reuse its masks, with its disk cache.
    light_mesh: PersistentLightMesh,
    /// The objects in the static structures and their hash.
    static_set: StaticSet,
    /// Which animation clips play.
    clips: ClipSelection,
    /// The previous frame's placement, to tell what changed.
    previous: Option<FrameScene>,
    /// Per scene node, whether its object may move: every animated or
    /// deforming one, or those the plan found moving in its frames.
    dynamic: Vec<bool>,
    /// The effect plan the frames follow, if the sequence has one, and
    /// its per-light shadow classes (by lamp radius without a plan).
    plan: Option<Plan>,
    shadows: ShadowSplit,
    /// The previous frame's image (and layers), and whether the frame now
    /// placed is the same picture (nothing changed), so it is copied.
    last_frame: Option<RenderedFrame>,
    still: bool,
}

impl Sequence {
    pub fn load(path: &Path) -> Result<Sequence, RunError> {
        let scene = import::load(path)?;
        Sequence::new(scene, path.display().to_string())
    }

    /// A sequence over a scene built in memory; `scene_file` names it in
    /// error messages.
    pub fn new(scene: SceneDesc, scene_file: String) -> Result<Sequence, RunError> {
        let rest = Pose::rest(&scene);
        let dynamic = dynamic_nodes(&scene);
        Sequence::build(scene, scene_file, &rest, dynamic, None)
    }

    /// A sequence that follows `plan`, made for `scene` played by `clips`:
    /// the objects static within its frames go into the static structures
    /// where those frames place them (the pose of `first`, its first
    /// frame, at `first_time` seconds).
    pub fn planned(
        scene: SceneDesc,
        scene_file: String,
        clips: ClipSelection,
        first_time: f64,
        plan: Plan,
    ) -> Result<Sequence, RunError> {
        let first = Pose::at(&scene, clips, first_time);
        let dynamic = plan.dynamic_nodes().to_vec();
        let mut sequence = Sequence::build(scene, scene_file, &first, dynamic, Some(plan))?;
        sequence.clips = clips;
        Ok(sequence)
    }

    fn build(
        scene: SceneDesc,
        scene_file: String,
        static_pose: &Pose,
        dynamic: Vec<bool>,
        plan: Option<Plan>,
    ) -> Result<Sequence, RunError> {
        // The anchor stays put for the whole sequence, so static geometry is
        // placed (and its BVH built) once.
        let bounds = SceneBounds::of(&scene, &Pose::rest(&scene));
        let anchor = Plan::anchor(&scene);
        let scene_radius = bounds.map_or(0.0, |b| b.radius() as f32);
        let choice = CameraChoice::First;
        let placed = FrameScene::place(
            &scene,
            static_pose,
            anchor,
            choice,
            &Default::default(),
            &dynamic,
        )
        .map_err(|source| RunError::Place {
            file: scene_file.clone(),
            source,
        })?;
        let light_mesh = PersistentLightMesh::new(&scene, &placed);
        let dynamic_objects = placed.objects.iter().filter(|o| o.dynamic).count() as u64;
        let static_set = StaticSet {
            static_objects: placed.objects.len() as u64 - dynamic_objects,
            dynamic_objects,
            hash: format!("{:032x}", light_mesh.static_geometry()),
        };
        Ok(Sequence {
            world: placed.build_world(&scene),
            light_mesh,
            static_set,
            scene,
            scene_file,
            anchor,
            scene_radius,
            clips: ClipSelection::All,
            previous: None,
            dynamic,
            shadows: plan.as_ref().map(Plan::shadow_split).unwrap_or_default(),
            plan,
            last_frame: None,
            still: false,
        })
    }

    /// The objects in the static structures, and the hash that keys the
    /// disk cache by them.
    pub fn static_set(&self) -> &StaticSet {
        &self.static_set
    }

    /// The plan the sequence follows, if it has one.
    pub fn plan(&self) -> Option<&Plan> {
        self.plan.as_ref()
    }

    pub fn scene(&self) -> &SceneDesc {
        &self.scene
    }

    /// The light mesh, once an LMM frame has made it.
    pub fn light_mesh(&self) -> Option<&LightMesh> {
        self.light_mesh.get()
    }

    /// Plays `clips` from the next frame on (all clips by default).
    pub fn set_clips(&mut self, clips: ClipSelection) {
        self.clips = clips;
    }

    /// Uses `dir` as the light mesh's disk cache (static masks), or none.
    /// Takes effect when the light mesh is made, on the first LMM frame.
    pub fn set_cache_dir(&mut self, dir: Option<PathBuf>) {
        self.light_mesh.set_cache_dir(dir);
    }

    /// Saves the light mesh's static masks to the disk cache, merged with
    /// what other workers saved there: for the lights where the last frame
    /// placed them, and where they stood when the light mesh was made.
    /// Does nothing without a cache directory, a light mesh or a frame.
    pub fn save_cache(&self) -> Result<(), OutputError> {
        match &self.previous {
            Some(placed) => self.light_mesh.save(&placed.lights),
            None => Ok(()),
        }
    }

    /// The frame at time 0, for single stills.
    pub fn place(&mut self, settings: &Settings) -> Result<FrameScene, RunError> {
        self.advance(0.0, settings, &mut FrameStats::default())
    }

    /// Poses the scene at `time` seconds and places it in render space, then
    /// brings the world and the light mesh up to date with what changed
    /// since the previous frame: moved dynamic objects get new instance
    /// transforms, deformed ones new positions, and the light mesh drops
    /// the bits that the changed geometry (the old and new bounds of moved
    /// objects, the old and new boxes of the moved parts of deformed ones)
    /// and moved lights can affect.
    /// `stats` gets the change summary and the invalidation's cost.
    pub fn advance(
        &mut self,
        time: f64,
        settings: &Settings,
        stats: &mut FrameStats,
    ) -> Result<FrameScene, RunError> {
        let camera = CameraChoice::for_frame(settings, time);
        let pose = Pose::at(&self.scene, self.clips, time);
        let lamps = &settings.lamps;
        let mut placed = FrameScene::place(
            &self.scene,
            &pose,
            self.anchor,
            camera,
            lamps,
            &self.dynamic,
        )
        .map_err(|source| RunError::Place {
            file: self.scene_file.clone(),
            source,
        })?;
        if let Some(plan) = &self.plan {
            plan.apply(&mut placed);
        }
        let delta = match &self.previous {
            Some(previous) => FrameDelta::between(previous, &placed),
            None => FrameDelta::first(&placed),
        };

        let started = Instant::now();
        let regions = delta.update_world(&mut self.world, &placed);
        let before = self.previous.as_ref().map(|previous| &previous.lights[..]);
        stats.bits_invalidated =
            self.light_mesh
                .invalidate(before, &placed.lights, &regions, &delta.lights_moved);
        stats.invalidate_seconds = started.elapsed().as_secs_f64();
        stats.camera_moved = delta.camera_moved;
        stats.lights_moved = delta.lights_moved.len() as u64;
        stats.objects_moved = (delta.objects_moved.len() + delta.objects_deformed.len()) as u64;
        self.still = self.previous.is_some() && delta.is_still();
        self.previous = Some(placed.clone());
        Ok(placed)
    }

    /// Renders one frame into an image, filling `stats`.
    pub fn render(
        &mut self,
        backend: &mut Backend,
        placed: &FrameScene,
        settings: &Settings,
        stats: &mut FrameStats,
    ) -> Result<output::Image, RunError> {
        Ok(self.render_frame(backend, placed, settings, stats)?.image)
    }

    /// Renders one frame with the AOV layers `settings` ask for, filling
    /// `stats`.
    pub fn render_frame(
        &mut self,
        backend: &mut Backend,
        placed: &FrameScene,
        settings: &Settings,
        stats: &mut FrameStats,
    ) -> Result<RenderedFrame, RunError> {
        if let (true, Some(frame)) = (self.still, &self.last_frame) {
            stats.copied = true;
            return Ok(frame.clone());
        }
        let file = &self.scene_file;
        let method = self.shadows.frame_method(settings.method, &placed.lights);
        let light_mesh = if self.shadows.uses_light_mesh(method, &placed.lights) {
            let mesh = &mut self.light_mesh;
            Some(prepared_light_mesh(
                mesh,
                file,
                self.scene_radius,
                placed,
                settings,
            )?)
        } else {
            None
        };
        let job = frame_job(&self.scene, &self.world, placed, settings, &self.shadows);
        let frame = (backend.render(&job, method, light_mesh, stats))
            .map_err(|error| run_error(file, error))?;
        self.report_cache_load(stats);
        self.last_frame = Some(frame.clone());
        Ok(frame)
    }

    /// Compiles the GPU pipelines the frames will need (`auto` resolved
    /// over the plan's lights), reporting (compiled, of) to `progress`.
    pub fn prepare_pipelines(
        &self,
        backend: &Backend,
        settings: &Settings,
        progress: impl FnMut(usize, usize),
    ) {
        let method = self.shadows.resolve(settings.method, &[]);
        backend.prepare_pipelines(method, &settings.aovs, progress);
    }

    /// Computes the light-mesh masks the placed frame will need, and the
    /// enclosure flags where the method is LMM1, without shading it
    /// (`lmanim warm`), filling `stats`.
    pub fn warm(
        &mut self,
        backend: &mut Backend,
        placed: &FrameScene,
        settings: &Settings,
        stats: &mut FrameStats,
    ) -> Result<(), RunError> {
        let file = &self.scene_file;
        let mesh = &mut self.light_mesh;
        let mesh = prepared_light_mesh(mesh, file, self.scene_radius, placed, settings)?;
        let job = frame_job(&self.scene, &self.world, placed, settings, &self.shadows);
        // As `render` resolves the frame's method.
        let method = self.shadows.frame_method(settings.method, &placed.lights);
        let probe_enclosure = !method.tests_point_to_node();
        (backend.warm(&job, mesh, probe_enclosure, stats))
            .map_err(|error| run_error(file, error))?;
        self.report_cache_load(stats);
        Ok(())
    }

    /// Puts what the disk cache gave the light mesh, if this frame made
    /// it, into the frame's `stats`: the bits, and the `cache_load` stage.
    fn report_cache_load(&mut self, stats: &mut FrameStats) {
        let load = self.light_mesh.take_load();
        if let Some(mesh_stats) = &mut stats.lightmesh {
            mesh_stats.bits_loaded = load.bits;
        }
        if load.seconds > 0.0 {
            stats.add_stage_time("cache_load", load.seconds);
        }
    }

    /// Renders the placed frame with every light visible from every point,
    /// on the CPU: what each pixel would get without shadows, the measure
    /// of how shadowed a pixel is (see `study`). Keeps no image.
    pub fn render_unshadowed(
        &self,
        cpu: &CpuBackend,
        placed: &FrameScene,
        settings: &Settings,
        stats: &mut FrameStats,
    ) -> output::Image {
        let job = frame_job(&self.scene, &self.world, placed, settings, &self.shadows);
        cpu.render_unshadowed(&job, stats)
    }
}

/// What the backend needs to render `placed` with `settings`.
/// The light mesh for the placed frame's lights, made (and loaded from
/// the disk cache) by the first frame that needs it; `file` names the
/// scene in errors.
fn prepared_light_mesh<'m>(
    light_mesh: &'m mut PersistentLightMesh,
    file: &str,
    scene_radius: f32,
    placed: &FrameScene,
    settings: &Settings,
) -> Result<&'m mut LightMesh, RunError> {
    (light_mesh)
        .prepare(&placed.lights, &settings.lightmesh, scene_radius)
        .map_err(|source| RunError::LightMesh {
            file: file.to_owned(),
            source,
        })
}

/// A backend's refusal as the run's error, naming the scene `file` where
/// the scene is at fault.
fn run_error(file: &str, error: RenderError) -> RunError {
    match error {
        RenderError::LightMesh(source) => RunError::LightMesh {
            file: file.to_owned(),
            source,
        },
        RenderError::Gpu(error) => RunError::Backend(error.into()),
        error @ RenderError::NoLightMesh => RunError::Render(error),
    }
}

fn frame_job<'a>(
    scene: &'a SceneDesc,
    world: &'a World,
    placed: &'a FrameScene,
    settings: &'a Settings,
    shadows: &'a ShadowSplit,
) -> FrameJob<'a> {
    FrameJob {
        scene,
        frame: placed,
        world,
        width: settings.width,
        height: settings.height,
        spp: settings.spp,
        max_depth: settings.max_depth,
        environment: settings.environment(),
        aovs: &settings.aovs,
        shadows,
    }
}

/// The contact sheet `settings` ask for at `path`: over `sheet_frames`
/// when given, else over the run's `frames`; refused before any frame
/// renders when it would be too large.
fn shot_sheet(path: &Path, settings: &Settings, frames: &FrameSet) -> Result<ShotSheet, RunError> {
    let sheet_frames = match &settings.sheet_frames {
        Some(text) => {
            FrameSet::parse(text).map_err(|fault| RunError::SheetFrames(fault.to_string()))?
        }
        None => frames.clone(),
    };
    let (columns, every) = (settings.sheet_columns, settings.sheet_every);
    let sheet = ContactSheet::new(columns, every, settings.sheet_thumb_width);
    let frame_size = (settings.width, settings.height);
    (sheet.fits(sheet_frames.len(), frame_size)).map_err(|fault| RunError::SheetSize {
        path: path.display().to_string(),
        fault,
    })?;
    Ok(ShotSheet::new(path, sheet_frames.frames(), sheet))
}

/// The backend and the loaded scene `job` runs on, following its plan,
/// with its disk cache and clips set, and the GPU pipelines its frames
/// need compiled (reporting (compiled, of) to `on_compile`). Where the
/// method alone says which pipelines those are (all but `auto`, which the
/// plan decides), they compile while the scene loads and its world is
/// built.
fn open(
    job: &Job,
    mut on_compile: impl FnMut(usize, usize),
) -> Result<(Backend, Sequence), RunError> {
    let settings = job.settings;
    let mut backend = Backend::new(settings.backend, settings.threads)?;
    backend.limit_mask_memory(settings.lightmesh.gpu_memory_mib.saturating_mul(1 << 20));
    if let Some(dir) = &settings.cache_dir {
        backend.keep_pipelines_in(Path::new(dir));
    }
    let forced = FrameMethod::forced(settings.method);
    let sequence = std::thread::scope(|scope| {
        let loading = scope.spawn(|| load_sequence(job));
        if let Some(method) = forced {
            backend.prepare_pipelines(method, &settings.aovs, &mut on_compile);
        }
        loading
            .join()
            .unwrap_or_else(|panic| std::panic::resume_unwind(panic))
    })?;
    if forced.is_none() {
        sequence.prepare_pipelines(&backend, settings, on_compile);
    }
    Ok((backend, sequence))
}

/// `job`'s scene loaded, planned and its world built, with its disk cache
/// set.
fn load_sequence(job: &Job) -> Result<Sequence, RunError> {
    let settings = job.settings;
    let (scene, clips, plan) = load_planned(job)?;
    let first_time = Timeline { fps: settings.fps }.time_of(plan.frames.frames()[0]);
    let file = job.scene_path.display().to_string();
    let mut sequence = Sequence::planned(scene, file, clips, first_time, plan)?;
    sequence.set_cache_dir(settings.cache_dir.as_ref().map(PathBuf::from));
    Ok(sequence)
}

/// The effect plan of `job` (`lmanim plan`, `--explain`).
pub fn plan(job: &Job) -> Result<Plan, RunError> {
    Ok(load_planned(job)?.2)
}

/// `job`'s scene, the clips it plays and its plan, over `--plan-frames`
/// (which must hold the run's frames) or else the run's frames.
fn load_planned(job: &Job) -> Result<(SceneDesc, ClipSelection, Plan), RunError> {
    let settings = job.settings;
    let scene = import::load(job.scene_path)?;
    let file = job.scene_path.display().to_string();
    let clips = match &settings.clip {
        Some(clip) => ClipSelection::parse(&scene, clip).map_err(|fault| RunError::Clip {
            file: file.clone(),
            fault,
        })?,
        None => ClipSelection::All,
    };
    let planned = match &settings.plan_frames {
        Some(text) => {
            FrameSet::parse(text).map_err(|fault| RunError::PlanFrames(fault.to_string()))?
        }
        None => job.frames.clone(),
    };
    if let Some(&frame) =
        (job.frames.frames().iter()).find(|f| planned.frames().binary_search(f).is_err())
    {
        return Err(RunError::PlanFramesMissFrame {
            planned: settings.plan_frames.clone().unwrap_or_default(),
            frame,
        });
    }
    let plan = Plan::make(&scene, settings, clips, &planned)
        .map_err(|source| RunError::Place { file, source })?;
    Ok((scene, clips, plan))
}

/// What warming the disk cache did (`lmanim warm`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct WarmStats {
    pub frames: usize,
    /// (node, light) bits computed, and taken from the cache at the start.
    pub bits_computed: u64,
    pub bits_loaded: u64,
    pub seconds: f64,
}

/// Computes the light-mesh masks `job`'s frames will need, frame by frame,
/// without shading or writing any, and saves their static layer to the
/// disk cache: the first task of a farm job, so that the render tasks
/// start warm. Refuses a job without a cache or whose method has no light
/// mesh.
pub fn warm(job: &Job) -> Result<WarmStats, RunError> {
    let started = Instant::now();
    let settings = job.settings;
    if settings.cache_dir.is_none() {
        return Err(RunError::WarmWithoutCache);
    }
    // A farm's warm step fills the pipeline cache as well as the masks':
    // its render tasks then start without the driver's compile.
    let (mut backend, mut sequence) = open(job, |_, _| {})?;
    let method = sequence.shadows.resolve(settings.method, &[]);
    if !sequence.shadows.uses_light_mesh(method, &[]) {
        return Err(RunError::WarmWithoutLightMesh(settings.method));
    }
    let timeline = Timeline { fps: settings.fps };
    let mut warm = WarmStats::default();
    for &frame in job.frames.frames() {
        let mut stats = FrameStats {
            frame,
            ..FrameStats::default()
        };
        let placed = sequence.advance(timeline.time_of(frame), settings, &mut stats)?;
        sequence.warm(&mut backend, &placed, settings, &mut stats)?;
        let mesh = stats.lightmesh.unwrap_or_default();
        warm.frames += 1;
        warm.bits_computed += mesh.bits_computed;
        warm.bits_loaded += mesh.bits_loaded;
    }
    sequence.save_cache()?;
    warm.seconds = started.elapsed().as_secs_f64();
    Ok(warm)
}

/// A rendered frame whose files the writer has, or a frame skipped as on
/// disk already: what reporting it takes.
struct FrameInWriting {
    index: usize,
    stats: FrameStats,
    path: PathBuf,
    automatic_camera: bool,
    skipped: bool,
}

/// Whether `settings` skip `frame` as on disk already: its files whole
/// and of the run's size ([`output::frame_on_disk`]).
fn skips(settings: &Settings, pattern: &FramePattern, frame: u32) -> bool {
    let exr = settings.exr.then(|| pattern.path_for(frame));
    let png = settings.png.then(|| pattern.png_path_for(frame));
    let size = (settings.width, settings.height);
    settings.skip_existing && output::frame_on_disk(exr.as_deref(), png.as_deref(), size)
}

/// Renders every frame of `job`, writing each while the next renders, and
/// reports the pipelines' compile and each frame once its files are
/// written to `on_event`.
pub fn run(job: &Job, mut on_event: impl FnMut(RunEvent)) -> Result<RunStats, RunError> {
    let started = Instant::now();
    let settings = job.settings;
    if job.frames.len() > 1 && !job.pattern.has_placeholder() {
        return Err(RunError::PatternWithoutPlaceholder(
            job.pattern.path_for(0).display().to_string(),
        ));
    }
    let compile_started = Instant::now();
    let (mut backend, mut sequence) = open(job, |compiled, of| {
        let seconds = compile_started.elapsed().as_secs_f64();
        on_event(RunEvent::Compiling {
            compiled,
            of,
            seconds,
        })
    })?;
    let mut run = RunStats {
        threads: backend.threads(),
        method: settings.method.to_string(),
        adapter: backend.adapter(),
        static_set: sequence.static_set().clone(),
        ..RunStats::default()
    };
    let timeline = Timeline { fps: settings.fps };
    let mut sheet = match &settings.contact_sheet {
        Some(path) => Some(shot_sheet(Path::new(path), settings, job.frames)?),
        None => None,
    };
    // Each frame's files are written while the next frame renders; a
    // frame is reported once its files are on disk.
    let mut writer = BackgroundWriter::new();
    let mut in_writing: Option<FrameInWriting> = None;
    let mut report = |done: FrameInWriting, writer: &mut BackgroundWriter| {
        let mut stats = done.stats;
        if !done.skipped {
            let write_seconds = writer.wait()?.unwrap_or_default();
            stats.add_stage_time("output", write_seconds);
            stats.seconds += write_seconds;
        }
        on_event(RunEvent::Frame(FrameDone {
            index: done.index,
            stats: &stats,
            path: &done.path,
            automatic_camera: done.automatic_camera,
            adapter: run.adapter.as_deref(),
            skipped: done.skipped,
        }));
        match done.skipped {
            true => run.skipped.push(stats.frame),
            false => run.frames.push(stats),
        }
        Ok::<(), RunError>(())
    };
    for (index, &frame) in job.frames.frames().iter().enumerate() {
        let frame_started = Instant::now();
        let mut stats = FrameStats {
            frame,
            ..FrameStats::default()
        };
        // A skipped frame is not advanced to: the next frame rendered
        // follows the last one rendered, as a farm chunk's first frame
        // follows nothing, and the masks invalidate across the gap alike.
        // The contact sheet reads it back from disk.
        if skips(settings, job.pattern, frame) {
            if let Some(done) = in_writing.take() {
                report(done, &mut writer)?;
            }
            let path = job.pattern.path_for(frame);
            let skipped = FrameInWriting {
                index,
                stats,
                path,
                automatic_camera: false,
                skipped: true,
            };
            report(skipped, &mut writer)?;
            continue;
        }
        let placed = sequence.advance(timeline.time_of(frame), settings, &mut stats)?;
        let rendered = sequence.render_frame(&mut backend, &placed, settings, &mut stats)?;
        if let Some(sheet) = &mut sheet {
            sheet.add_rendered(frame, &rendered.image);
        }
        stats.seconds = frame_started.elapsed().as_secs_f64();
        if let Some(done) = in_writing.take() {
            report(done, &mut writer)?;
        }
        let path = job.pattern.path_for(frame);
        writer.write(FrameFiles {
            rendered,
            exr: settings.exr.then(|| (path.clone(), settings.exr_precision)),
            png: settings
                .png
                .then(|| (job.pattern.png_path_for(frame), settings.exposure)),
        });
        in_writing = Some(FrameInWriting {
            index,
            stats,
            path,
            automatic_camera: placed.automatic_camera,
            skipped: false,
        });
    }
    if let Some(done) = in_writing.take() {
        report(done, &mut writer)?;
    }
    // Saved once, after the last frame: static bits only grow during a run
    // except where a light moves, and what a light leaves at its starting
    // position was kept aside; one merge-and-write per worker keeps the
    // lock short. A failed save costs later runs time, not this one its
    // frames.
    if let Err(error) = sequence.save_cache() {
        log::warn!("{error}; the light-mesh cache was not saved");
    }
    if let Some(sheet) = sheet {
        for unread in sheet.finish(job.pattern, settings.exposure)? {
            log::warn!("{unread}; the contact sheet leaves that frame out");
        }
    }
    run.total_seconds = started.elapsed().as_secs_f64();
    Ok(run)
}
