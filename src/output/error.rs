//! The one error type of the output boundary; every message names the file.

use std::path::PathBuf;

/// Why a frame, preview or contact sheet could not be written or read.
#[derive(Debug, thiserror::Error)]
pub enum OutputError {
    #[error("{path}: cannot create the directory: {source}")]
    CreateDir {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot write: {source}")]
    Write {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error("{path}: cannot encode: {fault}")]
    Encode { path: PathBuf, fault: String },
    #[error("{path}: cannot read EXR: {fault}")]
    ReadExr { path: PathBuf, fault: String },
    #[error("{path}: the image is {width}x{height} but holds {pixels} pixels")]
    ImageSize {
        path: PathBuf,
        width: u32,
        height: u32,
        pixels: usize,
    },
}

impl OutputError {
    /// The error for an image whose pixel count does not match its size.
    pub(crate) fn image_size(path: &std::path::Path, image: &super::Image) -> OutputError {
        OutputError::ImageSize {
            path: path.to_path_buf(),
            width: image.width,
            height: image.height,
            pixels: image.pixels.len(),
        }
    }
}
