//! The study's runs: which settings each method is tried at, and the time
//! and error each run gets.
//!
//! `whitted` runs once; `lmm` and `lmm1` at the default lattice and over a
//! grid of lattices, h·kI / R in [`LATTICE_SCALES`] (R the median lamp
//! radius: at 1 the light mesh's transition is as wide as the lamp's
//! penumbra with the occluder halfway) and kI in [`KIS`]; `area` at
//! [`AREA_SPP`] samples per pixel. The other methods render one sample at
//! each pixel centre, as a preview would.

use serde::Serialize;

use super::measure::{Errors, Flicker};
use crate::settings::{LightMeshSettings, Method, Settings};

/// The swept h·kI / R.
pub const LATTICE_SCALES: [f32; 5] = [0.5, 1.0, 1.5, 2.0, 3.0];
/// The swept interpolation radii, the paper's three.
pub const KIS: [f32; 3] = [2.1, 2.5, 3.0];
/// The swept samples per pixel of the Monte Carlo lamps.
pub const AREA_SPP: [u32; 4] = [1, 4, 16, 64];

/// One run of the sweep: a method and its settings.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RunSpec {
    pub method: Method,
    /// Lattice step; None for the default lattice (or no light mesh).
    pub h: Option<f32>,
    /// Interpolation radius in steps; None where there is no light mesh.
    pub ki: Option<f32>,
    pub spp: u32,
}

impl RunSpec {
    /// `base` with this run's method, samples and lattice.
    pub fn settings(&self, base: &Settings) -> Settings {
        let mut settings = Settings {
            method: self.method,
            spp: self.spp,
            ..base.clone()
        };
        if self.method.uses_light_mesh() {
            settings.lightmesh = LightMeshSettings {
                h: self.h,
                ki: self.ki.unwrap_or(base.lightmesh.ki),
                ..base.lightmesh.clone()
            };
        }
        settings
    }

    /// A short label for progress lines and the crops.
    pub fn label(&self) -> String {
        match (self.method, self.h, self.ki) {
            (Method::Area, ..) => format!("area {} spp", self.spp),
            (method, Some(h), Some(ki)) => format!("{method} h={h:.4} kI={ki}"),
            (method, None, Some(ki)) if method.uses_light_mesh() => {
                format!("{method} default h, kI={ki}")
            }
            (method, ..) => method.to_string(),
        }
    }
}

/// The runs for `methods` (in that order) on a scene whose median lamp
/// radius is `lamp_radius` metres, with `default_ki` the settings' kI.
pub fn plan(methods: &[Method], lamp_radius: f32, default_ki: f32) -> Vec<RunSpec> {
    let mut runs = Vec::new();
    for &method in methods {
        match method {
            Method::Whitted | Method::Auto => runs.push(RunSpec {
                method,
                h: None,
                ki: None,
                spp: 1,
            }),
            Method::Lmm | Method::Lmm1 => {
                runs.push(RunSpec {
                    method,
                    h: None,
                    ki: Some(default_ki),
                    spp: 1,
                });
                for ki in KIS {
                    for scale in LATTICE_SCALES {
                        runs.push(RunSpec {
                            method,
                            h: Some(scale * lamp_radius / ki),
                            ki: Some(ki),
                            spp: 1,
                        });
                    }
                }
            }
            Method::Area => runs.extend(AREA_SPP.map(|spp| RunSpec {
                method,
                h: None,
                ki: None,
                spp,
            })),
        }
    }
    runs
}

/// What made a run's frames: one of lmanim's methods, or a candidate
/// (`study::candidate`), by its name. In `study.json` a run has a
/// `"method"` or a `"candidate"`.
#[derive(Clone, Debug, PartialEq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Source {
    Method(Method),
    Candidate(String),
}

/// What one run measured: the row of `study.json` and `study.csv`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct RunResult {
    #[serde(flatten)]
    pub source: Source,
    /// The lattice step the light mesh used (the default one's too).
    pub h: Option<f32>,
    pub ki: Option<f32>,
    pub spp: u32,
    /// The frame's wall time, the fastest of its repeats.
    pub seconds: f64,
    #[serde(flatten)]
    pub errors: Errors,
    /// The light mesh's lattice came from the lamp radii (the default).
    pub default_lattice: bool,
    /// No other run is both as fast and as accurate (lit RMSE), and one
    /// of them strictly better.
    pub pareto: bool,
    /// Frames measured: 1 but for a candidate's still sequence, whose
    /// errors are pooled over its frames.
    pub frames: usize,
    /// How much those frames differ from one another; None for one frame.
    pub flicker: Option<Flicker>,
}

impl RunResult {
    /// The run's method, if lmanim's sweep made it.
    pub fn method(&self) -> Option<Method> {
        match self.source {
            Source::Method(method) => Some(method),
            Source::Candidate(_) => None,
        }
    }
}

/// Marks the runs on the Pareto front of time against lit RMSE.
pub fn mark_pareto_front(runs: &mut [RunResult]) {
    let points: Vec<(f64, f64)> = runs
        .iter()
        .map(|run| (run.seconds, run.errors.rmse))
        .collect();
    for (run, on_front) in runs.iter_mut().zip(pareto_front(&points)) {
        run.pareto = on_front;
    }
}

/// For each (cost, error) point, whether no other point dominates it.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<bool> {
    points
        .iter()
        .map(|point| !points.iter().any(|other| dominates(other, point)))
        .collect()
}

/// Whether the (cost, error) point `a` is at most as costly and at most
/// as wrong as `b`, and strictly better on one count.
pub fn dominates(a: &(f64, f64), b: &(f64, f64)) -> bool {
    a.0 <= b.0 && a.1 <= b.1 && (a.0 < b.0 || a.1 < b.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_plan_sweeps_each_method_as_the_study_says() {
        let runs = plan(&[Method::Whitted, Method::Lmm1, Method::Area], 0.2, 2.5);
        assert_eq!(runs.len(), 1 + 1 + 15 + 4);
        assert_eq!(runs[0].label(), "whitted");
        assert_eq!((runs[1].h, runs[1].ki), (None, Some(2.5)));
        let lattices: Vec<f32> = runs[2..17]
            .iter()
            .map(|run| run.h.unwrap() * run.ki.unwrap() / 0.2)
            .collect();
        for (scale, found) in LATTICE_SCALES.iter().cycle().zip(&lattices) {
            assert!((scale - found).abs() < 1e-5, "{lattices:?}");
        }
        let spp: Vec<u32> = runs[17..].iter().map(|run| run.spp).collect();
        assert_eq!(spp, AREA_SPP);
        let settings = runs[5].settings(&Settings::default());
        assert_eq!(settings.method, Method::Lmm1);
        assert_eq!(settings.lightmesh.h, runs[5].h);
    }

    fn run(seconds: f64, rmse: f64) -> RunResult {
        RunResult {
            source: Source::Method(Method::Whitted),
            h: None,
            ki: None,
            spp: 1,
            seconds,
            errors: Errors {
                rmse,
                penumbra_rmse: None,
                max_error: rmse,
                within_1pct: 0.0,
            },
            default_lattice: false,
            pareto: false,
            frames: 1,
            flicker: None,
        }
    }

    #[test]
    fn the_front_holds_the_runs_nothing_beats_on_both_counts() {
        let mut runs = vec![
            run(1.0, 0.5),
            run(2.0, 0.2),
            run(2.0, 0.3), // as slow as the second and worse: off
            run(3.0, 0.2), // as good as the second, slower: off
            run(0.5, 0.9),
            run(4.0, 0.05),
        ];
        mark_pareto_front(&mut runs);
        let front: Vec<bool> = runs.iter().map(|run| run.pareto).collect();
        assert_eq!(front, [true, true, false, false, true, true]);
    }
}
