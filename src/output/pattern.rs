//! Frame-name patterns: one run of `#` stands for the frame number,
//! zero-padded to the run's length (`frame.####.exr` → `frame.0007.exr`),
//! the convention of Nuke, Houdini and render farms.

use std::path::PathBuf;

/// A parsed output pattern such as `out/frame.####.exr`.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FramePattern {
    /// Text before the `#` run (the whole pattern when there is none).
    prefix: String,
    /// Length of the `#` run; 0 when the pattern has no placeholder.
    padding: usize,
    /// Text after the `#` run.
    suffix: String,
}

impl FramePattern {
    /// Parses a pattern. An empty pattern, or one with two separate runs of
    /// `#` (which would be ambiguous), is an error. A pattern without `#` is
    /// accepted; a caller rendering more than one frame must reject it (see
    /// [`FramePattern::has_placeholder`]).
    pub fn parse(pattern: &str) -> Result<FramePattern, String> {
        if pattern.is_empty() {
            return Err("the output pattern is empty".into());
        }
        let Some(start) = pattern.find('#') else {
            return Ok(FramePattern {
                prefix: pattern.to_owned(),
                padding: 0,
                suffix: String::new(),
            });
        };
        let padding = pattern[start..].bytes().take_while(|&b| b == b'#').count();
        let suffix = &pattern[start + padding..];
        if suffix.contains('#') {
            return Err(format!(
                "output pattern `{pattern}` has more than one run of `#`; \
                 use a single run such as `frame.####.exr`"
            ));
        }
        Ok(FramePattern {
            prefix: pattern[..start].to_owned(),
            padding,
            suffix: suffix.to_owned(),
        })
    }

    /// Whether the pattern holds a `#` run; without one, every frame would
    /// go to the same file.
    pub fn has_placeholder(&self) -> bool {
        self.padding > 0
    }

    /// The file of `frame`. Numbers wider than the padding are written in
    /// full, never truncated (`#` with frame 1234 gives `1234`).
    pub fn path_for(&self, frame: u32) -> PathBuf {
        PathBuf::from(self.name_for(frame, &self.suffix))
    }

    /// The PNG preview of `frame`: the same path with its extension replaced
    /// by `.png` (or `.png` appended when the pattern has no extension after
    /// the frame number).
    pub fn png_path_for(&self, frame: u32) -> PathBuf {
        // Only the text after the number can hold the extension: in
        // `frame.####` the `.0007` is the number, not an extension.
        let (tail, last_part) = match self.suffix.rfind(['/', '\\']) {
            Some(slash) => self.suffix.split_at(slash + 1),
            None if self.has_placeholder() => ("", self.suffix.as_str()),
            None => (self.prefix_dir(), self.prefix_file()),
        };
        let stem = last_part
            .rfind('.')
            .map_or(last_part, |dot| &last_part[..dot]);
        let suffix = format!("{tail}{stem}.png");
        if self.has_placeholder() {
            PathBuf::from(self.name_for(frame, &suffix))
        } else {
            PathBuf::from(suffix)
        }
    }

    fn name_for(&self, frame: u32, suffix: &str) -> String {
        if self.has_placeholder() {
            format!(
                "{}{frame:0width$}{suffix}",
                self.prefix,
                width = self.padding
            )
        } else {
            format!("{}{suffix}", self.prefix)
        }
    }

    /// Directory part of a placeholder-free pattern, with its separator.
    fn prefix_dir(&self) -> &str {
        let split = self.prefix.rfind(['/', '\\']).map_or(0, |slash| slash + 1);
        &self.prefix[..split]
    }

    /// File part of a placeholder-free pattern.
    fn prefix_file(&self) -> &str {
        &self.prefix[self.prefix_dir().len()..]
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn path(pattern: &str, frame: u32) -> String {
        let pattern = FramePattern::parse(pattern).unwrap();
        pattern.path_for(frame).to_string_lossy().into_owned()
    }

    fn png(pattern: &str, frame: u32) -> String {
        let pattern = FramePattern::parse(pattern).unwrap();
        pattern.png_path_for(frame).to_string_lossy().into_owned()
    }

    #[test]
    fn pads_to_the_run_length() {
        assert_eq!(path("frame.####.exr", 7), "frame.0007.exr");
        assert_eq!(path("frame.#.exr", 7), "frame.7.exr");
        assert_eq!(path("out/shot_##.exr", 0), "out/shot_00.exr");
        assert_eq!(path("####", 42), "0042");
    }

    #[test]
    fn wide_numbers_are_not_truncated() {
        assert_eq!(path("frame.##.exr", 12345), "frame.12345.exr");
        assert_eq!(path("f#", u32::MAX), format!("f{}", u32::MAX));
    }

    #[test]
    fn placeholder_is_reported() {
        assert!(FramePattern::parse("a.#.exr").unwrap().has_placeholder());
        let still = FramePattern::parse("still.exr").unwrap();
        assert!(!still.has_placeholder());
        assert_eq!(still.path_for(3), PathBuf::from("still.exr"));
    }

    #[test]
    fn bad_patterns_are_errors() {
        assert!(FramePattern::parse("").is_err());
        let message = FramePattern::parse("shot##/frame.####.exr").unwrap_err();
        assert!(message.contains("shot##/frame.####.exr"), "{message}");
    }

    #[test]
    fn png_path_replaces_only_the_real_extension() {
        assert_eq!(png("frame.####.exr", 7), "frame.0007.png");
        assert_eq!(png("frame.####", 7), "frame.0007.png");
        assert_eq!(png("out/f_##", 3), "out/f_03.png");
        assert_eq!(png("####/beauty.exr", 3), "0003/beauty.png");
        assert_eq!(png("renders.v2/still.exr", 3), "renders.v2/still.png");
        assert_eq!(png("renders.v2/still", 3), "renders.v2/still.png");
    }
}
