//! OpenEXR frames: RGBA channels of linear radiance, ZIP-compressed scan
//! lines (lossless, well supported by compositors, and small on noisy
//! renders), in half or single precision.

use std::path::Path;

use exr::prelude::{f16, Encoding, ReadChannels, ReadLayers, SpecificChannels, WritableImage};
use glam::Vec4;

use super::{write_atomically, ExrPrecision, Image, OutputError};

/// Writes `image` to `path` as an RGBA EXR, atomically.
pub fn write_exr(path: &Path, image: &Image, precision: ExrPrecision) -> Result<(), OutputError> {
    if !image.has_consistent_size() {
        return Err(OutputError::image_size(path, image));
    }
    let size = (image.width as usize, image.height as usize);
    let at = |x: usize, y: usize| image.pixels[y * size.0 + x];
    let encode_error = |error: exr::error::Error| OutputError::Encode {
        path: path.to_path_buf(),
        fault: error.to_string(),
    };
    write_atomically(path, |writer| match precision {
        ExrPrecision::Half => {
            let channels = SpecificChannels::rgba(|exr::math::Vec2(x, y)| {
                let p = at(x, y);
                (
                    f16::from_f32(p.x),
                    f16::from_f32(p.y),
                    f16::from_f32(p.z),
                    f16::from_f32(p.w),
                )
            });
            exr::image::Image::from_encoded_channels(size, Encoding::SMALL_LOSSLESS, channels)
                .write()
                .to_buffered(writer)
                .map_err(encode_error)
        }
        ExrPrecision::Float => {
            let channels = SpecificChannels::rgba(|exr::math::Vec2(x, y)| {
                let p = at(x, y);
                (p.x, p.y, p.z, p.w)
            });
            exr::image::Image::from_encoded_channels(size, Encoding::SMALL_LOSSLESS, channels)
                .write()
                .to_buffered(writer)
                .map_err(encode_error)
        }
    })
}

/// Reads the first RGBA layer of an EXR (alpha 1 where the file has none),
/// e.g. a reference frame for a test.
pub fn read_exr(path: &Path) -> Result<Image, OutputError> {
    let read_error = |fault: String| OutputError::ReadExr {
        path: path.to_path_buf(),
        fault,
    };
    let read = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .rgba_channels(
            |resolution, _| {
                Image::filled(
                    resolution.width() as u32,
                    resolution.height() as u32,
                    Vec4::ZERO,
                )
            },
            |image: &mut Image, position, (r, g, b, a): (f32, f32, f32, f32)| {
                let index = position.y() * image.width as usize + position.x();
                image.pixels[index] = Vec4::new(r, g, b, a);
            },
        )
        .first_valid_layer()
        .all_attributes()
        .from_file(path)
        .map_err(|error| read_error(error.to_string()))?;
    let image = read.layer_data.channel_data.pixels;
    if image.width == 0 || image.height == 0 {
        return Err(read_error("the image is empty".into()));
    }
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A gradient with values a render produces: dark, bright, above 1.
    fn sample_image() -> Image {
        let (width, height) = (7, 5);
        let pixels = (0..width * height)
            .map(|i| {
                let t = i as f32 / (width * height) as f32;
                Vec4::new(t * 100.0, 1.0 - t, 0.001 + t * 0.37, 0.5 + t * 0.5)
            })
            .collect();
        Image {
            width,
            height,
            pixels,
        }
    }

    #[test]
    fn float_round_trip_is_exact() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("f.exr");
        let image = sample_image();
        write_exr(&path, &image, ExrPrecision::Float).unwrap();
        assert_eq!(read_exr(&path).unwrap(), image);
    }

    #[test]
    fn half_round_trip_is_within_half_precision() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("h.exr");
        let image = sample_image();
        write_exr(&path, &image, ExrPrecision::Half).unwrap();
        let back = read_exr(&path).unwrap();
        assert_eq!((back.width, back.height), (image.width, image.height));
        for (a, b) in image.pixels.iter().zip(&back.pixels) {
            for (x, y) in a.to_array().into_iter().zip(b.to_array()) {
                // 11 significant bits: relative error at most 2^-11.
                assert!((x - y).abs() <= x.abs() * 2f32.powi(-11), "{x} vs {y}");
            }
        }
        let float = dir.path().join("f.exr");
        write_exr(&float, &image, ExrPrecision::Float).unwrap();
        let half_bytes = std::fs::metadata(&path).unwrap().len();
        let float_bytes = std::fs::metadata(&float).unwrap().len();
        assert!(half_bytes < float_bytes, "{half_bytes} vs {float_bytes}");
    }

    #[test]
    fn a_wrong_pixel_count_is_an_error_naming_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("bad.exr");
        let mut image = sample_image();
        image.pixels.pop();
        let message = write_exr(&path, &image, ExrPrecision::Half)
            .unwrap_err()
            .to_string();
        assert!(
            message.contains("bad.exr") && message.contains("7x5"),
            "{message}"
        );
        assert!(!path.exists());
    }

    #[test]
    fn reading_garbage_names_the_file() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("junk.exr");
        std::fs::write(&path, b"not an exr").unwrap();
        let message = read_exr(&path).unwrap_err().to_string();
        assert!(message.contains("junk.exr"), "{message}");
    }
}
