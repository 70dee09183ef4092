//! The verdict on what a user gets without tuning: is LMM1 at its default
//! lattice worth its time against the Monte Carlo lamps (`area` at the
//! sweep's 1–64 spp), and does it stay within issue 34's share of
//! Whitted's penumbra error?
//!
//! The study's own Pareto column ranks every run, so a swept lattice can
//! push the default off that front although no `area` run beats it; the
//! question a user asks is narrower, the default against the sampler it
//! replaces, and in the penumbra as well as over the lit pixels.

use serde::Serialize;

use super::sweep::{dominates, pareto_front, RunResult};
use crate::settings::Method;

/// The share of Whitted's penumbra RMSE the default must stay at or
/// below (issue 34).
pub const WHITTED_PENUMBRA_BOUND: f64 = 0.6;

/// The default's standing, `default_verdict` in `study.json`.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct DefaultVerdict {
    pub method: Method,
    pub seconds: f64,
    pub rmse: f64,
    pub penumbra_rmse: Option<f64>,
    /// Against the `area` runs, in time and lit RMSE.
    pub lit: Front,
    /// Against the `area` runs, in time and penumbra RMSE; None where the
    /// reference has no penumbra.
    pub penumbra: Option<Front>,
    /// The default's penumbra RMSE over Whitted's; None without a Whitted
    /// run or a penumbra.
    pub over_whitted_penumbra: Option<f64>,
    /// Whether that ratio is at most [`WHITTED_PENUMBRA_BOUND`].
    pub within_whitted_bound: Option<bool>,
}

/// Whether the default is on the Pareto front of itself and the `area`
/// runs, and which of those runs beat it where it is not.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Front {
    pub on_front: bool,
    /// The `area` runs at most as slow and as wrong, one of them strictly.
    pub dominated_by: Vec<Rival>,
}

/// An `area` run that dominates the default: its samples, time and the
/// error compared.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Rival {
    pub spp: u32,
    pub seconds: f64,
    pub error: f64,
}

/// The verdict on the LMM1 run at the default lattice among `runs`; None
/// where the study has no such run or no `area` run to hold it against.
pub fn judge_default(runs: &[RunResult]) -> Option<DefaultVerdict> {
    let method = Method::Lmm1;
    let default = runs
        .iter()
        .find(|run| run.method() == Some(method) && run.default_lattice)?;
    let areas: Vec<&RunResult> = runs
        .iter()
        .filter(|run| run.method() == Some(Method::Area))
        .collect();
    if areas.is_empty() {
        return None;
    }
    let whitted = runs
        .iter()
        .find(|run| run.method() == Some(Method::Whitted));
    let over_whitted_penumbra = default
        .errors
        .penumbra_rmse
        .zip(whitted.and_then(|run| run.errors.penumbra_rmse))
        .map(|(default, whitted)| default / whitted);
    Some(DefaultVerdict {
        method,
        seconds: default.seconds,
        rmse: default.errors.rmse,
        penumbra_rmse: default.errors.penumbra_rmse,
        lit: front(default, &areas, |run| Some(run.errors.rmse))?,
        penumbra: front(default, &areas, |run| run.errors.penumbra_rmse),
        over_whitted_penumbra,
        within_whitted_bound: over_whitted_penumbra.map(|ratio| ratio <= WHITTED_PENUMBRA_BOUND),
    })
}

/// `default` against `rivals` in time and `error`; rivals without that
/// error are left out, and None where the default has none.
fn front(
    default: &RunResult,
    rivals: &[&RunResult],
    error: impl Fn(&RunResult) -> Option<f64>,
) -> Option<Front> {
    let ours = (default.seconds, error(default)?);
    let theirs: Vec<(&RunResult, (f64, f64))> = rivals
        .iter()
        .filter_map(|run| Some((*run, (run.seconds, error(run)?))))
        .collect();
    let points: Vec<(f64, f64)> = std::iter::once(ours)
        .chain(theirs.iter().map(|(_, point)| *point))
        .collect();
    Some(Front {
        on_front: pareto_front(&points)[0],
        dominated_by: (theirs.iter())
            .filter(|(_, point)| dominates(point, &ours))
            .map(|(run, (seconds, error))| Rival {
                spp: run.spp,
                seconds: *seconds,
                error: *error,
            })
            .collect(),
    })
}

impl DefaultVerdict {
    /// The verdict in words, a line each: the two fronts, then the bound.
    pub fn lines(&self) -> Vec<String> {
        let name = format!(
            "{} at the default lattice ({:.3} s)",
            self.method, self.seconds
        );
        let mut lines = vec![format!(
            "{name} against area: {}",
            self.lit.words("lit", self.rmse, self.seconds)
        )];
        if let (Some(front), Some(error)) = (&self.penumbra, self.penumbra_rmse) {
            lines.push(format!(
                "{name} against area: {}",
                front.words("penumbra", error, self.seconds)
            ));
        }
        if let (Some(ratio), Some(within)) = (self.over_whitted_penumbra, self.within_whitted_bound)
        {
            lines.push(format!(
                "{name}: penumbra RMSE {ratio:.3}× Whitted's, {} the {WHITTED_PENUMBRA_BOUND} bound",
                match within {
                    true => "within",
                    false => "above",
                }
            ));
        }
        lines
    }
}

impl Front {
    /// "on the Pareto front in time and lit RMSE (0.0469)", or off it and
    /// by which runs.
    fn words(&self, which: &str, error: f64, seconds: f64) -> String {
        let counts = format!("in time and {which} RMSE ({error:.4})");
        if self.on_front {
            return format!("on the Pareto front {counts}");
        }
        let rivals: Vec<String> = (self.dominated_by.iter())
            .map(|rival| {
                format!(
                    "area {} spp ({:.3} s, {:.4}: {:.2}× the time, {:.2}× the error)",
                    rival.spp,
                    rival.seconds,
                    rival.error,
                    rival.seconds / seconds,
                    rival.error / error
                )
            })
            .collect();
        format!(
            "off the Pareto front {counts}, beaten by {}",
            rivals.join(", ")
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::study::measure::Errors;
    use crate::study::sweep::Source;

    fn run(method: Method, spp: u32, seconds: f64, rmse: f64, penumbra: f64) -> RunResult {
        RunResult {
            source: Source::Method(method),
            h: None,
            ki: None,
            spp,
            seconds,
            errors: Errors {
                rmse,
                penumbra_rmse: Some(penumbra),
                max_error: rmse,
                within_1pct: 0.0,
            },
            default_lattice: method.uses_light_mesh(),
            pareto: false,
            frames: 1,
            flicker: None,
        }
    }

    /// Whitted, area at 1/4/16/64 spp, and `default`; a swept LMM1
    /// lattice that beats everything, which must not count.
    fn study(default: RunResult) -> Vec<RunResult> {
        vec![
            run(Method::Whitted, 1, 0.01, 0.05, 0.25),
            default,
            RunResult {
                h: Some(0.04),
                default_lattice: false,
                ..run(Method::Lmm1, 1, 0.001, 0.001, 0.001)
            },
            run(Method::Area, 1, 0.02, 0.09, 0.40),
            run(Method::Area, 4, 0.06, 0.03, 0.17),
            run(Method::Area, 16, 0.28, 0.012, 0.065),
            run(Method::Area, 64, 1.2, 0.004, 0.025),
        ]
    }

    #[test]
    fn a_default_between_area_runs_is_on_both_fronts() {
        let verdict = judge_default(&study(run(Method::Lmm1, 1, 0.05, 0.04, 0.10))).unwrap();
        assert!(verdict.lit.on_front && verdict.lit.dominated_by.is_empty());
        let penumbra = verdict.penumbra.as_ref().unwrap();
        assert!(penumbra.on_front && penumbra.dominated_by.is_empty());
        assert!((verdict.over_whitted_penumbra.unwrap() - 0.4).abs() < 1e-12);
        assert_eq!(verdict.within_whitted_bound, Some(true));
        assert!(verdict.lines()[0].contains("on the Pareto front in time and lit RMSE"));
    }

    #[test]
    fn a_default_that_area_beats_in_the_penumbra_only_says_by_which_run() {
        // Closer than area 4 spp over the lit pixels, further in the
        // penumbra, and slower: off the penumbra's front alone.
        let verdict = judge_default(&study(run(Method::Lmm1, 1, 0.07, 0.02, 0.18))).unwrap();
        assert!(verdict.lit.on_front);
        let penumbra = verdict.penumbra.as_ref().unwrap();
        assert!(!penumbra.on_front);
        assert_eq!(
            penumbra.dominated_by,
            [Rival {
                spp: 4,
                seconds: 0.06,
                error: 0.17
            }]
        );
        assert_eq!(verdict.within_whitted_bound, Some(false));
        let lines = verdict.lines();
        assert!(lines[1].contains("off the Pareto front in time and penumbra RMSE"));
        assert!(lines[1].contains("area 4 spp"), "{lines:?}");
        assert!(lines[2].contains("above the 0.6 bound"), "{lines:?}");
    }

    #[test]
    fn a_slow_wrong_default_is_beaten_by_every_faster_closer_area_run() {
        let verdict = judge_default(&study(run(Method::Lmm1, 1, 0.5, 0.02, 0.2))).unwrap();
        let spp: Vec<u32> = (verdict.lit.dominated_by.iter())
            .map(|rival| rival.spp)
            .collect();
        assert_eq!(spp, [16]);
        let penumbra = verdict.penumbra.unwrap();
        let spp: Vec<u32> = penumbra
            .dominated_by
            .iter()
            .map(|rival| rival.spp)
            .collect();
        assert_eq!(spp, [4, 16]);
        assert!(!verdict.lit.on_front && !penumbra.on_front);
    }

    #[test]
    fn no_verdict_without_a_default_or_an_area_run() {
        let default = run(Method::Lmm1, 1, 0.05, 0.04, 0.10);
        let mut runs = study(default.clone());
        runs.retain(|run| run.method() != Some(Method::Area));
        assert_eq!(judge_default(&runs), None);
        let mut runs = study(default);
        runs.retain(|run| !run.default_lattice);
        assert_eq!(judge_default(&runs), None);
    }
}
