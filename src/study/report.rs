//! The study's tables: `study.json` (the reference, every run and the
//! default's verdict) and `study.csv` (the runs, one row each, for a
//! spreadsheet), both written atomically.

use std::io::Write;
use std::path::Path;

use serde::Serialize;

use super::measure::Census;
use super::sweep::{RunResult, Source};
use super::verdict::DefaultVerdict;
use crate::output::{write_atomically, OutputError};

/// Where the reference came from and how it was classified.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ReferenceReport {
    /// `"area"` (rendered by lmanim) or the EXR file given.
    pub source: String,
    /// Samples per pixel of a rendered reference.
    pub spp: Option<u32>,
    pub seconds: Option<f64>,
    /// The reference's own noise, estimated from the densest `area` run
    /// of the sweep (Monte Carlo error falls as 1/√spp, see STUDY.md), as
    /// a lit RMSE; None for a reference from a file.
    pub estimated_noise: Option<f64>,
    pub scene: String,
    pub frame: u32,
    pub width: u32,
    pub height: u32,
    /// The median lamp radius R that the lattice sweep is scaled by.
    pub lamp_radius: f32,
    #[serde(flatten)]
    pub census: Census,
}

/// The whole study, as `study.json` holds it.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct StudyReport {
    pub reference: ReferenceReport,
    pub runs: Vec<RunResult>,
    /// LMM1's default against `area`, and against Whitted's penumbra
    /// error; None where the study ran neither.
    pub default_verdict: Option<DefaultVerdict>,
}

impl StudyReport {
    pub fn write_json(&self, path: &Path) -> Result<(), OutputError> {
        let json = serde_json::to_vec_pretty(self).map_err(|error| OutputError::Encode {
            path: path.to_path_buf(),
            fault: error.to_string(),
        })?;
        write_atomically(path, |file| {
            file.write_all(&json).map_err(|source| OutputError::Write {
                path: path.to_path_buf(),
                source,
            })
        })
    }

    pub fn write_csv(&self, path: &Path) -> Result<(), OutputError> {
        write_atomically(path, |file| {
            file.write_all(self.csv().as_bytes())
                .map_err(|source| OutputError::Write {
                    path: path.to_path_buf(),
                    source,
                })
        })
    }

    /// The runs as CSV, a header line first; cells that do not apply are
    /// empty. A candidate's row has its name under `candidate` (quoted
    /// where it must be) and no `method`; the columns after `pareto` came
    /// with candidates, so older readers of the first eleven still work.
    pub fn csv(&self) -> String {
        let mut text = String::from(
            "method,h,ki,spp,seconds,rmse,penumbra_rmse,max_error,within_1pct,default_lattice,pareto,candidate,frames,flicker_lit,flicker_penumbra\n",
        );
        let cell = |value: Option<String>| value.unwrap_or_default();
        for run in &self.runs {
            let errors = &run.errors;
            let (method, candidate) = match &run.source {
                Source::Method(method) => (method.to_string(), String::new()),
                Source::Candidate(name) => (String::new(), csv_field(name)),
            };
            let flicker = run.flicker.as_ref();
            text += &format!(
                "{method},{},{},{},{:.6},{:.6},{},{:.6},{:.6},{},{},{candidate},{},{},{}\n",
                cell(run.h.map(|h| format!("{h:.6}"))),
                cell(run.ki.map(|ki| ki.to_string())),
                run.spp,
                run.seconds,
                errors.rmse,
                cell(errors.penumbra_rmse.map(|e| format!("{e:.6}"))),
                errors.max_error,
                errors.within_1pct,
                run.default_lattice,
                run.pareto,
                run.frames,
                cell(flicker.map(|f| format!("{:.6}", f.lit))),
                cell(flicker.and_then(|f| f.penumbra).map(|e| format!("{e:.6}"))),
            );
        }
        text
    }
}

/// `text` as one CSV field: quoted, quotes doubled, where it holds a
/// comma, a quote or a line break (RFC 4180).
fn csv_field(text: &str) -> String {
    match text.contains([',', '"', '\n', '\r']) {
        true => format!("\"{}\"", text.replace('"', "\"\"")),
        false => text.to_owned(),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::settings::Method;
    use crate::study::measure::{Errors, Flicker};

    fn report() -> StudyReport {
        let run = |method, h, ki, penumbra| RunResult {
            source: Source::Method(method),
            h,
            ki,
            spp: 1,
            seconds: 0.25,
            errors: Errors {
                rmse: 0.125,
                penumbra_rmse: penumbra,
                max_error: 0.5,
                within_1pct: 0.75,
            },
            default_lattice: h.is_some(),
            pareto: true,
            frames: 1,
            flicker: None,
        };
        StudyReport {
            reference: ReferenceReport {
                source: "area".into(),
                spp: Some(1024),
                seconds: Some(3.0),
                estimated_noise: Some(0.001),
                scene: "box.gltf".into(),
                frame: 0,
                width: 8,
                height: 4,
                lamp_radius: 0.2,
                census: Census::default(),
            },
            runs: vec![
                run(Method::Whitted, None, None, None),
                run(Method::Lmm1, Some(0.08), Some(2.5), Some(0.25)),
                RunResult {
                    source: Source::Candidate("cycles+oidn 1 spp, 16 seeds".into()),
                    frames: 16,
                    flicker: Some(Flicker {
                        lit: 0.0625,
                        penumbra: Some(0.5),
                    }),
                    ..run(Method::Area, None, None, Some(0.375))
                },
            ],
            default_verdict: None,
        }
    }

    #[test]
    fn json_has_the_issue_schema_with_nulls_where_nothing_applies() {
        let json = serde_json::to_value(report()).unwrap();
        let whitted = &json["runs"][0];
        for key in [
            "method",
            "h",
            "ki",
            "spp",
            "seconds",
            "rmse",
            "penumbra_rmse",
            "max_error",
            "within_1pct",
        ] {
            assert!(whitted.get(key).is_some(), "{key} in {whitted}");
        }
        assert!(whitted["h"].is_null() && whitted["ki"].is_null());
        assert_eq!(json["runs"][1]["method"], "lmm1");
        assert_eq!(json["runs"][1]["penumbra_rmse"], 0.25);
        assert!(whitted["flicker"].is_null() && whitted.get("candidate").is_none());
        let candidate = &json["runs"][2];
        assert!(candidate.get("method").is_none(), "{candidate}");
        assert_eq!(candidate["candidate"], "cycles+oidn 1 spp, 16 seeds");
        assert_eq!(candidate["frames"], 16);
        assert_eq!(candidate["flicker"]["penumbra"], 0.5);
        assert_eq!(json["reference"]["spp"], 1024);
        assert!(json["default_verdict"].is_null(), "no area run, no verdict");
    }

    #[test]
    fn csv_has_a_row_per_run_and_empty_cells_for_nothing() {
        let csv = report().csv();
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines.len(), 4);
        assert!(
            lines[1].starts_with("whitted,,,1,0.250000,0.125000,,0.5"),
            "{}",
            lines[1]
        );
        assert!(lines[2].starts_with("lmm1,0.080000,2.5,1,"), "{}", lines[2]);
        assert!(lines[2].ends_with(",true,true,,1,,"), "{}", lines[2]);
        assert_eq!(lines[0].split(',').count(), lines[2].split(',').count());
        // The candidate's name is quoted: it holds a comma.
        assert!(lines[3].starts_with(",,,1,"), "{}", lines[3]);
        assert!(
            lines[3].ends_with(",\"cycles+oidn 1 spp, 16 seeds\",16,0.062500,0.500000"),
            "{}",
            lines[3]
        );
    }
}
