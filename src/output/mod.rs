//! STUB: EXR frames, PNG previews, frame-name patterns, atomic writes.

use std::path::{Path, PathBuf};

use glam::Vec4;

/// A rendered frame: linear Rec.709 RGBA, row-major, top row first.
#[derive(Clone, Debug, PartialEq)]
pub struct Image {
    pub width: u32,
    pub height: u32,
    pub pixels: Vec<Vec4>,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum ExrPrecision {
    #[default]
    Half,
    Float,
}

#[derive(Debug, thiserror::Error)]
#[error("{path}: {fault}")]
pub struct OutputError {
    pub path: PathBuf,
    pub fault: String,
}

pub fn write_exr(
    _path: &Path,
    _image: &Image,
    _precision: ExrPrecision,
) -> Result<(), OutputError> {
    todo!()
}

pub fn write_png_preview(_path: &Path, _image: &Image) -> Result<(), OutputError> {
    todo!()
}

pub fn read_exr(_path: &Path) -> Result<Image, OutputError> {
    todo!()
}

#[derive(Clone, Debug, PartialEq, Eq)]
pub struct FramePattern {}

impl FramePattern {
    pub fn parse(_pattern: &str) -> Result<FramePattern, String> {
        todo!()
    }
    pub fn path_for(&self, _frame: u32) -> PathBuf {
        todo!()
    }
}
