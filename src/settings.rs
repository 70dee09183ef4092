//! Render settings: how big, how fast, which method, where to. They come
//! from a RON file (`scene.ron` beside the scene, see `animations/`), CLI
//! flags override single fields, and [`Settings::validate`] rejects
//! impossible values before any work starts. Every field has a default, so
//! a settings file only names what it changes.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::camera_path::CameraPath;
use crate::lightmesh::faint::MAX_FAINT_SHARE;
use crate::lightmesh::kernel::Kernel;
use crate::lightmesh::lattice::MAX_KI;
use crate::lightmesh::penumbra::Penumbra;
use crate::output::ExrPrecision;
use crate::render::environment::Environment;
use crate::schedule::FrameSet;

/// The largest width or height accepted: beyond it a frame buffer no
/// longer fits a sensible amount of memory (and EXR viewers choke).
pub const MAX_DIMENSION: u32 = 32768;

/// The coarsest derived lattice accepted (h·kI/R): beyond it one node's
/// mask stands for a whole lamp's shadow.
pub const MAX_COARSENESS: f32 = 16.0;

/// The `--preview` preset's share of the settings' width and height.
pub const PREVIEW_SCALE: u32 = 4;

/// The deepest Whitted recursion accepted; deeper only costs time.
pub const MAX_DEPTH: u32 = 64;
/// Most thumbnails in a contact sheet's row: 64 of the default width make
/// a sheet as wide as the widest it may be (`output::contact_sheet`).
pub const MAX_SHEET_COLUMNS: u32 = 64;

/// Largest exposure, in stops either way: 2^±64 takes any radiance a float
/// holds to black or to white; more is a typo.
pub const MAX_EXPOSURE: f32 = 64.0;

/// Everything that decides how frames are rendered and written.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct Settings {
    /// Output width in pixels.
    pub width: u32,
    /// Output height in pixels.
    pub height: u32,
    /// Frames per second of the timeline.
    pub fps: f64,
    pub method: Method,
    /// Which hardware renders the frames.
    pub backend: BackendKind,
    /// Samples per pixel (camera rays, jittered within the pixel).
    pub spp: u32,
    /// Whitted recursion depth for mirrors and refraction.
    pub max_depth: u32,
    /// Camera node or camera name; None takes the first camera.
    pub camera: Option<String>,
    /// Animation clip to play (name or index); None plays all together.
    pub clip: Option<String>,
    pub exr_precision: ExrPrecision,
    /// Write the EXR frames (`--preview` turns them off: PNG only).
    pub exr: bool,
    /// Also write a tone-mapped PNG preview of every frame.
    pub png: bool,
    /// Exposure of the PNG previews and the contact sheet, in stops (EV):
    /// +1 doubles the linear radiance before tone mapping. The EXR frames
    /// are never scaled.
    pub exposure: f32,
    /// Leave out the frames whose files are on disk already and read back
    /// whole (`--skip-existing`): a stopped shot resumes where it stopped.
    pub skip_existing: bool,
    /// A contact sheet of the run's frames to write at its end (PNG).
    pub contact_sheet: Option<String>,
    /// Thumbnails per row of the contact sheet.
    pub sheet_columns: u32,
    /// The sheet shows every this many-th frame of its frames.
    pub sheet_every: u32,
    /// Width of the contact sheet's thumbnails in pixels; None: 256, or
    /// the frame's width where that is smaller.
    pub sheet_thumb_width: Option<u32>,
    /// The frames of the shot the sheet is over (a frame range such as
    /// `0..240`); those the run does not render are read back from their
    /// EXR files. None: the run's frames.
    pub sheet_frames: Option<String>,
    /// The frames of the shot the effect plan is made over (a frame range
    /// such as `0..240`), so that every chunk a farm renders plans alike;
    /// it must hold the run's frames. None: the run's frames.
    pub plan_frames: Option<String>,
    /// Linear RGB radiance of the pixels where camera rays meet nothing,
    /// which makes frames opaque; None leaves them transparent black.
    pub background: Option<[f32; 3]>,
    /// Linear RGB radiance of a uniform sky lighting every surface's
    /// diffuse part, unshadowed (`render/environment.rs`); None: no
    /// ambient term.
    pub ambient: Option<[f32; 3]>,
    /// Layers written into each EXR frame beside the beauty (`--aovs`).
    pub aovs: Vec<Aov>,
    /// Worker threads; None uses every core.
    pub threads: Option<usize>,
    /// Output frame pattern (`frame.####.exr`); None derives one from the
    /// scene's name.
    pub out: Option<String>,
    /// Directory of the light mesh's disk cache (static masks shared by
    /// runs and workers), relative to the current directory; None turns
    /// the cache off.
    pub cache_dir: Option<String>,
    pub lamps: LampSettings,
    pub lightmesh: LightMeshSettings,
    /// The camera path flown instead of the scene's cameras
    /// (`--camera-path`, `--orbit`). Not a settings-file field: a path is
    /// a file of its own, checked when it is read.
    #[serde(skip)]
    pub camera_path: Option<CameraPath>,
}

impl Default for Settings {
    fn default() -> Self {
        Settings {
            width: 640,
            height: 360,
            fps: 24.0,
            method: Method::Auto,
            backend: BackendKind::Cpu,
            spp: 1,
            max_depth: 5,
            camera: None,
            clip: None,
            exr_precision: ExrPrecision::Half,
            exr: true,
            png: false,
            exposure: 0.0,
            skip_existing: false,
            contact_sheet: None,
            sheet_columns: 6,
            sheet_every: 1,
            sheet_thumb_width: None,
            sheet_frames: None,
            plan_frames: None,
            background: None,
            ambient: None,
            aovs: Vec::new(),
            threads: None,
            out: None,
            cache_dir: Some("cache".into()),
            lamps: LampSettings::default(),
            lightmesh: LightMeshSettings::default(),
            camera_path: None,
        }
    }
}

/// How shadows (and so the whole frame) are computed.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Method {
    /// Each light as the effect plan says (`src/plan/`): shadow rays for
    /// lights without a lamp radius, LMM1 for lamps with one, no shadow
    /// ray where nothing can cast a shadow, nothing for lights that reach
    /// nothing in view.
    #[default]
    Auto,
    /// Hard shadows with one shadow ray per light: the reference.
    Whitted,
    /// Light Meshes Method with point-to-node visibility tests.
    Lmm,
    /// LMM1: the Light Meshes Method without point-to-node tests.
    Lmm1,
    /// Monte Carlo sampling of spherical lamps: the soft-shadow reference.
    Area,
}

impl Method {
    /// Whether every frame shades from a light mesh (LMM, LMM1), which
    /// the sequence makes on the first frame and keeps for the next ones.
    /// (`auto` does where a frame has soft lights: see
    /// `ShadowSplit::resolve`.)
    pub fn uses_light_mesh(self) -> bool {
        matches!(self, Method::Lmm | Method::Lmm1)
    }
}

impl std::fmt::Display for Method {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Method::Auto => "auto",
            Method::Whitted => "whitted",
            Method::Lmm => "lmm",
            Method::Lmm1 => "lmm1",
            Method::Area => "area",
        })
    }
}

/// An arbitrary output variable: a layer of the EXR frames beside the
/// beauty (`R`, `G`, `B`, `A`), for compositing.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum Aov {
    /// One RGB layer per light, or per group of lights (`extras.group`):
    /// `light.<name>.R/G/B`, with `other.R/G/B` for what no light sent
    /// (emission, the ambient sky, the background); together they sum to
    /// the beauty.
    Light,
    /// The base colour of what the camera sees (`albedo.R/G/B`).
    Albedo,
    /// Its shading normal in world space (`N.X/Y/Z`).
    Normal,
    /// Its distance in metres along the camera ray (`Z`; infinite where
    /// the ray meets nothing).
    Depth,
}

impl Aov {
    pub const ALL: [Aov; 4] = [Aov::Light, Aov::Albedo, Aov::Normal, Aov::Depth];

    pub fn name(self) -> &'static str {
        match self {
            Aov::Light => "light",
            Aov::Albedo => "albedo",
            Aov::Normal => "normal",
            Aov::Depth => "depth",
        }
    }

    /// A comma-separated list such as `light,depth`, or why it is not one.
    pub fn parse_list(text: &str) -> Result<Vec<Aov>, String> {
        let mut aovs = Vec::new();
        for item in text.split(',').map(str::trim) {
            let aov = (Aov::ALL.into_iter())
                .find(|aov| aov.name() == item)
                .ok_or_else(|| {
                    let known: Vec<&str> = Aov::ALL.iter().map(|aov| aov.name()).collect();
                    format!("unknown AOV '{item}'; the AOVs are {}", known.join(", "))
                })?;
            aovs.push(aov);
        }
        Ok(aovs)
    }
}

/// Which backend runs a frame's stages. The CPU is the default, so a
/// render works on any machine.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum BackendKind {
    /// rayon threads over the frame's stages.
    #[default]
    Cpu,
    /// wgpu compute passes for the frame's ray queries.
    Gpu,
}

/// Lamp radii, which set the size of soft shadows. A light's own
/// `extras.radius` in the scene wins over `default_radius`; an entry in
/// `radius` (keyed by light name) wins over both.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LampSettings {
    /// Radius in metres for lights that state none.
    pub default_radius: Option<f32>,
    /// Radius in metres per light name.
    pub radius: BTreeMap<String, f32>,
}

/// Light-mesh lattice parameters.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct LightMeshSettings {
    /// Lattice spacing in metres; None derives it from the lamp radii.
    pub h: Option<f32>,
    /// Interpolation radius in units of `h` (the paper's kI).
    pub ki: f32,
    /// How formula (2) weighs the nodes within the radius: `box` counts
    /// them alike (the paper), `smooth` by (1 − d²/r²)².
    pub kernel: Kernel,
    /// How big each light's set is: `fixed`, kI·h everywhere (the paper);
    /// `blocker`, where the nodes disagree on a light, the radius of the
    /// penumbra a lamp of that size casts from the blocker's distance
    /// (`lightmesh::penumbra`).
    pub penumbra: Penumbra,
    /// The share ε of a point's lamp light whose penumbrae it may leave
    /// at the half-ball's answer instead of sizing them by rays: a pixel
    /// moves by at most ε of its unshadowed light (`lightmesh::faint`);
    /// 0 sizes every lamp's, at most 0.5.
    pub faint_lamps: f32,
    /// h·kI/R of the lattice derived from the lamps when `h` is None: 1
    /// makes the light mesh's transition the penumbra of an occluder
    /// halfway to the lamp; more makes the lattice coarser and faster.
    pub coarseness: f32,
    /// Memory the node masks may take, in MiB; a frame that would need
    /// more is refused with a clear error instead of exhausting memory.
    pub max_memory_mib: usize,
    /// GPU memory the resident masks may take, in MiB (`--backend gpu`):
    /// bricks no level reads are evicted first, and a level that reads
    /// more is refused with the same clear error.
    pub gpu_memory_mib: usize,
}

impl Default for LightMeshSettings {
    fn default() -> Self {
        LightMeshSettings {
            h: None,
            ki: 2.5,
            kernel: Kernel::default(),
            penumbra: Penumbra::default(),
            faint_lamps: 1.0 / 16.0,
            coarseness: 1.0,
            max_memory_mib: 4096,
            gpu_memory_mib: 1024,
        }
    }
}

impl LightMeshSettings {
    /// Why `h` cannot be a lattice step, if it cannot: shared by the
    /// settings file's check and the `--h` flag's.
    pub fn h_fault(h: f32) -> Option<String> {
        (!h.is_finite() || h <= 0.0).then(|| "it must be a positive number of metres".into())
    }

    /// Why `share` cannot be `faint_lamps`, if it cannot.
    pub fn faint_lamps_fault(share: f32) -> Option<String> {
        (!(0.0..=MAX_FAINT_SHARE).contains(&share))
            .then(|| format!("it must be a share from 0 to {MAX_FAINT_SHARE}"))
    }

    /// Why `ki` cannot be an interpolation radius, if it cannot.
    pub fn ki_fault(ki: f32) -> Option<String> {
        (!ki.is_finite() || ki <= 0.0 || ki > MAX_KI)
            .then(|| format!("it must be above 0 and at most {MAX_KI}"))
    }
}

/// Why a settings file could not be used.
#[derive(Debug, thiserror::Error)]
pub enum SettingsError {
    #[error("{path}: cannot read: {source}")]
    Read {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}:{line}:{column}: {fault}")]
    Parse {
        path: PathBuf,
        line: usize,
        column: usize,
        fault: String,
    },
    #[error("{origin}: {fault}")]
    Invalid { origin: String, fault: String },
}

impl Settings {
    /// The `--preview` preset over these settings: a quarter of the width
    /// and height, one sample a pixel, LMM1 on a coarse lattice (kI = 2.1,
    /// h·kI/R = 1.5: a point on the accuracy study's Pareto front, see
    /// STUDY.md) and PNG frames only.
    pub fn preview(self) -> Settings {
        Settings {
            width: (self.width / PREVIEW_SCALE).max(1),
            height: (self.height / PREVIEW_SCALE).max(1),
            spp: 1,
            method: Method::Lmm1,
            exr: false,
            png: true,
            aovs: Vec::new(),
            lightmesh: LightMeshSettings {
                h: None,
                ki: 2.1,
                coarseness: 1.5,
                ..self.lightmesh
            },
            ..self
        }
    }

    /// The frame's background and ambient sky as the renderer takes them.
    pub fn environment(&self) -> Environment {
        Environment {
            background: self.background.map(Vec3::from_array),
            ambient: self.ambient.map(Vec3::from_array),
        }
    }

    /// Reads and validates a RON settings file.
    pub fn load(path: &Path) -> Result<Settings, SettingsError> {
        let text = std::fs::read_to_string(path).map_err(|source| SettingsError::Read {
            path: path.to_path_buf(),
            source,
        })?;
        let settings = Settings::parse(&text, path)?;
        settings.check().map_err(|fault| SettingsError::Invalid {
            origin: path.display().to_string(),
            fault,
        })?;
        Ok(settings)
    }

    /// Parses RON text; `path` only names the source in errors.
    pub fn parse(text: &str, path: &Path) -> Result<Settings, SettingsError> {
        ron::from_str(text).map_err(|error| SettingsError::Parse {
            path: path.to_path_buf(),
            line: error.position.line,
            column: error.position.col,
            fault: error.code.to_string(),
        })
    }

    /// Rejects values no render can use, e.g. after CLI flags overrode a
    /// loaded file. The message names the field and its value.
    pub fn validate(&self) -> Result<(), SettingsError> {
        self.check().map_err(|fault| SettingsError::Invalid {
            origin: "settings".into(),
            fault,
        })
    }

    fn check(&self) -> Result<(), String> {
        for (name, value) in [("width", self.width), ("height", self.height)] {
            if value == 0 || value > MAX_DIMENSION {
                return Err(format!(
                    "{name} is {value}; it must be 1 to {MAX_DIMENSION}"
                ));
            }
        }
        if self.spp == 0 {
            return Err("spp is 0; it must be at least 1".into());
        }
        if !self.fps.is_finite() || self.fps <= 0.0 {
            return Err(format!("fps is {}; it must be a positive number", self.fps));
        }
        if self.max_depth > MAX_DEPTH {
            return Err(format!(
                "max_depth is {}; it must be at most {MAX_DEPTH}",
                self.max_depth
            ));
        }
        if !self.exposure.is_finite() || self.exposure.abs() > MAX_EXPOSURE {
            return Err(format!(
                "exposure is {} EV; it must be within ±{MAX_EXPOSURE}",
                self.exposure
            ));
        }
        if self.sheet_columns == 0 || self.sheet_columns > MAX_SHEET_COLUMNS {
            return Err(format!(
                "sheet_columns is {}; it must be 1 to {MAX_SHEET_COLUMNS}",
                self.sheet_columns
            ));
        }
        for (name, colour) in [("background", self.background), ("ambient", self.ambient)] {
            if let Some(colour) = colour.filter(|c| c.iter().any(|v| !v.is_finite() || *v < 0.0)) {
                return Err(format!(
                    "{name} is {colour:?}; it must be three finite, non-negative radiances (linear RGB)"
                ));
            }
        }
        if let Some(Err(fault)) = self.sheet_frames.as_deref().map(FrameSet::parse) {
            return Err(format!("sheet_frames: {fault}"));
        }
        if let Some(Err(fault)) = self.plan_frames.as_deref().map(FrameSet::parse) {
            return Err(format!("plan_frames: {fault}"));
        }
        if self.sheet_every == 0 {
            return Err("sheet_every is 0; it must be at least 1".into());
        }
        if let Some(width) = self
            .sheet_thumb_width
            .filter(|&w| w == 0 || w > MAX_DIMENSION)
        {
            return Err(format!(
                "sheet_thumb_width is {width}; it must be 1 to {MAX_DIMENSION}"
            ));
        }
        if self.skip_existing && self.contact_sheet.is_some() && !self.exr {
            return Err("skip_existing puts skipped frames on the contact sheet from their EXR files, and exr is false (--preview writes PNG only): leave out the contact sheet or skip_existing".into());
        }
        if !self.exr && !self.aovs.is_empty() {
            return Err("aovs go into the EXR frames, and exr is false".into());
        }
        if !self.exr && !self.png && self.contact_sheet.is_none() {
            return Err(
                "exr and png are false and there is no contact_sheet: the run would write nothing"
                    .into(),
            );
        }
        if let Some(aov) =
            (self.aovs.iter()).find(|&&aov| self.aovs.iter().filter(|&&a| a == aov).count() > 1)
        {
            return Err(format!("aovs lists {} twice", aov.name()));
        }
        if self.threads == Some(0) {
            return Err("threads is 0; leave it out to use every core".into());
        }
        let lightmesh = &self.lightmesh;
        if lightmesh.gpu_memory_mib == 0 {
            return Err("lightmesh.gpu_memory_mib is 0; it must be at least 1".into());
        }
        if let Some(fault) = LightMeshSettings::ki_fault(lightmesh.ki) {
            return Err(format!("lightmesh.ki is {}; {fault}", lightmesh.ki));
        }
        if let Some(fault) = LightMeshSettings::faint_lamps_fault(lightmesh.faint_lamps) {
            return Err(format!(
                "lightmesh.faint_lamps is {}; {fault}",
                lightmesh.faint_lamps
            ));
        }
        if !(lightmesh.coarseness > 0.0 && lightmesh.coarseness <= MAX_COARSENESS) {
            return Err(format!(
                "lightmesh.coarseness is {}; it must be above 0 and at most {MAX_COARSENESS}",
                lightmesh.coarseness
            ));
        }
        if let Some((h, fault)) =
            (lightmesh.h).and_then(|h| Some((h, LightMeshSettings::h_fault(h)?)))
        {
            return Err(format!("lightmesh.h is {h}; {fault}"));
        }
        let bad_radius = |r: f32| !r.is_finite() || r < 0.0;
        if let Some(r) = self.lamps.default_radius.filter(|&r| bad_radius(r)) {
            return Err(format!(
                "lamps.default_radius is {r}; it must be 0 or more metres"
            ));
        }
        if let Some((name, r)) = self.lamps.radius.iter().find(|(_, &r)| bad_radius(r)) {
            return Err(format!(
                "lamps.radius of light `{name}` is {r}; it must be 0 or more metres"
            ));
        }
        Ok(())
    }
}
