//! The contact sheet of a run: the frames of the shot it shows
//! (`--sheet-frames`, else the run's own), the ones the run renders taken
//! as they come, and the others read back from their EXR files at the
//! end. So a farm whose workers render parts of a shot, or a run that
//! re-renders a few frames, still ends with the sheet of the whole shot.

use std::path::{Path, PathBuf};

use super::{read_exr, ContactSheet, FramePattern, Image, OutputError};

/// A run's contact sheet being filled.
pub struct ShotSheet {
    path: PathBuf,
    /// The shot's frames the sheet is over, ascending.
    frames: Vec<u32>,
    /// Which of them this run rendered.
    rendered: Vec<bool>,
    sheet: ContactSheet,
}

impl ShotSheet {
    /// `sheet` at `path` over `frames` (ascending).
    pub fn new(path: &Path, frames: &[u32], sheet: ContactSheet) -> ShotSheet {
        ShotSheet {
            path: path.to_path_buf(),
            frames: frames.to_vec(),
            rendered: vec![false; frames.len()],
            sheet,
        }
    }

    /// Takes rendered frame `frame`, if the sheet is over it.
    pub fn add_rendered(&mut self, frame: u32, image: &Image) {
        if let Ok(index) = self.frames.binary_search(&frame) {
            self.rendered[index] = true;
            self.sheet.add(index, frame, image);
        }
    }

    /// Reads the frames the sheet shows that the run did not render from
    /// their EXR files (named by `pattern`), then writes the sheet at
    /// `exposure` stops. Returns the files that could not be read (a frame
    /// not rendered yet): their cells are left out.
    pub fn finish(
        mut self,
        pattern: &FramePattern,
        exposure: f32,
    ) -> Result<Vec<OutputError>, OutputError> {
        let mut unread = Vec::new();
        for (index, &frame) in self.frames.iter().enumerate() {
            if self.rendered[index] || !self.sheet.shows(index) {
                continue;
            }
            match read_exr(&pattern.path_for(frame)) {
                Ok(image) => self.sheet.add(index, frame, &image),
                Err(error) => unread.push(error),
            }
        }
        self.sheet.write(&self.path, exposure)?;
        Ok(unread)
    }
}
