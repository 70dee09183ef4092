//! OpenEXR frames: RGBA channels of linear radiance, and any AOV layers
//! beside them as channels of the same part (`light.Lamp.R`, `N.X`, `Z`:
//! the dot names the layer, as compositors read it), ZIP-compressed scan
//! lines (lossless, well supported by compositors, and small on noisy
//! renders), in half or single precision.

use std::path::Path;

use exr::prelude::{f16, AnyChannel, AnyChannels, Encoding, FlatSamples, SmallVec, WritableImage};

use super::{write_atomically, AovLayer, ExrPrecision, Image, OutputError};

/// Writes `image` to `path` as an RGBA EXR, atomically.
pub fn write_exr(path: &Path, image: &Image, precision: ExrPrecision) -> Result<(), OutputError> {
    write_layered_exr(path, image, &[], precision)
}

/// Writes `image` (as `R`, `G`, `B`, `A`) and the `aovs` layers to `path`
/// as one EXR, atomically.
pub fn write_layered_exr(
    path: &Path,
    image: &Image,
    aovs: &[AovLayer],
    precision: ExrPrecision,
) -> Result<(), OutputError> {
    if !image.has_consistent_size() {
        return Err(OutputError::image_size(path, image));
    }
    let pixels = image.pixels.len();
    if let Some(layer) =
        (aovs.iter()).find(|layer| layer.values.len() != pixels * layer.channels.len())
    {
        return Err(OutputError::Encode {
            path: path.to_path_buf(),
            fault: format!(
                "the layer {} holds {} values for {pixels} pixels",
                layer.channels.join(","),
                layer.values.len()
            ),
        });
    }
    let samples = |values: Vec<f32>| match precision {
        ExrPrecision::Half => FlatSamples::F16(values.into_iter().map(f16::from_f32).collect()),
        ExrPrecision::Float => FlatSamples::F32(values),
    };
    let beauty = ["R", "G", "B", "A"]
        .into_iter()
        .enumerate()
        .map(|(k, name)| {
            AnyChannel::new(name, samples(image.pixels.iter().map(|p| p[k]).collect()))
        });
    let layers = aovs.iter().flat_map(|layer| {
        let stride = layer.channels.len();
        (layer.channels.iter().enumerate()).map(move |(k, name)| {
            let values = layer
                .values
                .iter()
                .skip(k)
                .step_by(stride)
                .copied()
                .collect();
            AnyChannel::new(name.as_str(), samples(values))
        })
    });
    let channels: SmallVec<[AnyChannel<FlatSamples>; 4]> = beauty.chain(layers).collect();
    let size = (image.width as usize, image.height as usize);
    let exr_image = exr::image::Image::from_encoded_channels(
        size,
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(channels),
    );
    write_atomically(path, |writer| {
        (exr_image.write().to_buffered(writer)).map_err(|error| OutputError::Encode {
            path: path.to_path_buf(),
            fault: error.to_string(),
        })
    })
}

#[cfg(test)]
mod tests {
    use super::super::read_exr;
    use super::*;
    use glam::Vec4;

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
}
