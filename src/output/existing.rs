//! Frames already on disk, for `--skip-existing`: a stopped shot resumes
//! by rendering only the frames whose files are missing or damaged.

use std::path::Path;

use super::read_exr;

/// Whether each file a frame writes (its EXR and its PNG preview; None
/// where the run writes none) is on disk and reads back whole, at
/// `size`: a file cut short by a full disk or a copy, or left by a run of
/// another size, is not the frame. Files are written atomically, so a
/// frame a run was writing when it stopped is simply absent. False when
/// the frame writes neither file (nothing on disk could stand for it).
pub fn frame_on_disk(exr: Option<&Path>, png: Option<&Path>, size: (u32, u32)) -> bool {
    if exr.is_none() && png.is_none() {
        return false;
    }
    let exr_whole =
        |path: &Path| read_exr(path).is_ok_and(|image| (image.width, image.height) == size);
    let png_whole =
        |path: &Path| image::open(path).is_ok_and(|png| (png.width(), png.height()) == size);
    exr.is_none_or(exr_whole) && png.is_none_or(png_whole)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::output::{write_exr, write_png_preview, ExrPrecision, Image};
    use glam::Vec4;

    /// Writes a 6×4 frame's EXR and PNG into `dir`, returning their paths.
    fn frame(dir: &Path) -> (std::path::PathBuf, std::path::PathBuf) {
        let image = Image::filled(6, 4, Vec4::new(0.5, 0.25, 0.125, 1.0));
        let (exr, png) = (dir.join("f.exr"), dir.join("f.png"));
        write_exr(&exr, &image, ExrPrecision::Half).unwrap();
        write_png_preview(&png, &image, 0.0).unwrap();
        (exr, png)
    }

    fn truncate(path: &Path) {
        let bytes = std::fs::read(path).unwrap();
        std::fs::write(path, &bytes[..bytes.len() - 7]).unwrap();
    }

    #[test]
    fn whole_files_of_the_size_are_the_frame() {
        let dir = tempfile::tempdir().unwrap();
        let (exr, png) = frame(dir.path());
        assert!(frame_on_disk(Some(&exr), Some(&png), (6, 4)));
        assert!(frame_on_disk(Some(&exr), None, (6, 4)));
        assert!(frame_on_disk(None, Some(&png), (6, 4)));
        assert!(
            !frame_on_disk(Some(&exr), Some(&png), (12, 8)),
            "another size"
        );
        assert!(
            !frame_on_disk(None, None, (6, 4)),
            "nothing written, nothing to skip"
        );
        let missing = dir.path().join("missing.png");
        assert!(!frame_on_disk(Some(&exr), Some(&missing), (6, 4)));
    }

    #[test]
    fn a_truncated_file_is_not_the_frame() {
        for which in ["exr", "png"] {
            let dir = tempfile::tempdir().unwrap();
            let (exr, png) = frame(dir.path());
            truncate(if which == "exr" { &exr } else { &png });
            assert!(!frame_on_disk(Some(&exr), Some(&png), (6, 4)), "{which}");
        }
    }
}
