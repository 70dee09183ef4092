//! Frames made outside the sweep and measured beside it with the same
//! reference and the same measure: another renderer's frames of the study's
//! view (STUDY.md, "Beside Blender Cycles"), or lmanim's own frames of a
//! still sequence. `--candidate NAME=SECONDS:FRAME.exr[,FRAME.exr…]` names
//! one; SECONDS is the time it took per frame, measured by whoever made it.
//!
//! A candidate of several frames is a still sequence (nothing in the scene
//! or the camera changes between them): its errors are pooled over every
//! frame, and how far its frames differ from one another is its
//! [`Flicker`](super::measure::Flicker).

use std::path::PathBuf;
use std::str::FromStr;

/// One candidate, as `--candidate` names it.
#[derive(Clone, Debug, PartialEq)]
pub struct Candidate {
    /// The row's name in the tables; one series per first word in the plot.
    pub name: String,
    /// Seconds per frame.
    pub seconds: f64,
    /// The frames, each the study's size; more than one: a still sequence.
    pub frames: Vec<PathBuf>,
}

impl Candidate {
    /// The series the candidate is drawn in: its name's first word
    /// (`cycles+oidn` for `cycles+oidn 4 spp`).
    pub fn family(name: &str) -> &str {
        name.split_whitespace().next().unwrap_or(name)
    }
}

impl FromStr for Candidate {
    type Err = String;

    /// `NAME=SECONDS:FRAME.exr[,FRAME.exr…]`: the name ends at the first
    /// `=`, the seconds at the next `:` (so frames' paths may hold `:`;
    /// they may not hold `,`).
    fn from_str(text: &str) -> Result<Candidate, String> {
        let usage = |fault: &str| {
            format!("--candidate {text:?}: {fault}; expected NAME=SECONDS:FRAME.exr[,FRAME.exr...]")
        };
        let (name, rest) = text.split_once('=').ok_or_else(|| usage("no `=`"))?;
        let (seconds, frames) = rest.split_once(':').ok_or_else(|| usage("no `:`"))?;
        let name = name.trim();
        if name.is_empty() {
            return Err(usage("the name is empty"));
        }
        let seconds: f64 = match seconds.trim().parse() {
            Ok(seconds) if f64::is_finite(seconds) && seconds > 0.0 => seconds,
            _ => {
                return Err(usage(&format!(
                    "{seconds:?} is not a positive number of seconds"
                )))
            }
        };
        let frames: Vec<PathBuf> = frames.split(',').map(PathBuf::from).collect();
        if frames.iter().any(|frame| frame.as_os_str().is_empty()) {
            return Err(usage("a frame's path is empty"));
        }
        Ok(Candidate {
            name: name.to_owned(),
            seconds,
            frames,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_candidate_is_a_name_seconds_and_frames() {
        let one: Candidate = "cycles+oidn 4 spp=0.25:out/c.exr".parse().unwrap();
        assert_eq!(one.name, "cycles+oidn 4 spp");
        assert_eq!(one.seconds, 0.25);
        assert_eq!(one.frames, [PathBuf::from("out/c.exr")]);
        assert_eq!(Candidate::family(&one.name), "cycles+oidn");
        // Paths may hold `:` and `=`; frames are split at commas.
        let sequence: Candidate = "lmm1 frames=1e-2:C:/a=b/f.0.exr,f.1.exr".parse().unwrap();
        assert_eq!(sequence.seconds, 0.01);
        assert_eq!(
            sequence.frames,
            [PathBuf::from("C:/a=b/f.0.exr"), PathBuf::from("f.1.exr")]
        );
    }

    #[test]
    fn a_malformed_candidate_says_what_is_wrong() {
        for (text, fault) in [
            ("cycles", "no `=`"),
            ("cycles=0.5", "no `:`"),
            ("=0.5:a.exr", "the name is empty"),
            ("cycles=fast:a.exr", "not a positive number"),
            ("cycles=0:a.exr", "not a positive number"),
            ("cycles=0.5:a.exr,", "a frame's path is empty"),
        ] {
            let error = text.parse::<Candidate>().unwrap_err();
            assert!(
                error.contains(fault) && error.contains("NAME=SECONDS"),
                "{error}"
            );
        }
    }
}
