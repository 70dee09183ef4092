//! PNG previews: a quick look at a frame, not a deliverable. Linear radiance
//! is scaled by the exposure (2^EV), tone-mapped with Reinhard's operator
//! on luminance, `L' = L / (1 + L)` (hue is kept, highlights roll off
//! instead of clipping), then sRGB-encoded into 8-bit RGBA. Alpha is
//! stored as is, clamped to [0, 1].

use std::path::Path;

use glam::{Vec3, Vec4};
use image::ImageEncoder;
use rayon::prelude::*;

use super::{write_atomically, Image, OutputError};

/// Rec.709 luminance weights, matching the linear Rec.709 colour of frames.
const LUMINANCE: Vec3 = Vec3::new(0.2126, 0.7152, 0.0722);

/// Writes a tone-mapped 8-bit sRGB preview of `image` at `exposure` stops
/// to `path`, atomically.
pub fn write_png_preview(path: &Path, image: &Image, exposure: f32) -> Result<(), OutputError> {
    if !image.has_consistent_size() {
        return Err(OutputError::image_size(path, image));
    }
    write_rgba8(
        path,
        image.width,
        image.height,
        &preview_bytes(image, exposure),
    )
}

/// `image` scaled by 2^`exposure` and tone-mapped into 8-bit sRGB RGBA,
/// rows in parallel (a 1080p frame's three `powf` per pixel took longer
/// than its EXR).
pub fn preview_bytes(image: &Image, exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    let mut bytes = vec![0; image.pixels.len() * 4];
    let row = (image.width as usize).max(1);
    (bytes.par_chunks_mut(row * 4))
        .zip(image.pixels.par_chunks(row))
        .for_each(|(out, pixels)| {
            for (out, &p) in out.chunks_exact_mut(4).zip(pixels) {
                out.copy_from_slice(&tone_map((p.truncate() * scale).extend(p.w)));
            }
        });
    bytes
}

/// Writes the 8-bit sRGB RGBA `bytes` of a `width` × `height` image (a
/// preview or a contact sheet, already display-ready) as a PNG at `path`,
/// atomically.
pub fn write_rgba8(path: &Path, width: u32, height: u32, bytes: &[u8]) -> Result<(), OutputError> {
    write_png(
        path,
        (width, height),
        bytes,
        image::ExtendedColorType::Rgba8,
    )
}

/// Writes 8-bit sRGB RGB pixels, row-major from the top (a plot, already
/// display-ready), as a PNG at `path`, atomically.
pub fn write_srgb_png(path: &Path, width: u32, height: u32, rgb: &[u8]) -> Result<(), OutputError> {
    if rgb.len() as u64 != 3 * u64::from(width) * u64::from(height) {
        return Err(OutputError::ImageSize {
            path: path.to_path_buf(),
            width,
            height,
            pixels: rgb.len() / 3,
        });
    }
    write_png(path, (width, height), rgb, image::ExtendedColorType::Rgb8)
}

fn write_png(
    path: &Path,
    (width, height): (u32, u32),
    bytes: &[u8],
    colour: image::ExtendedColorType,
) -> Result<(), OutputError> {
    write_atomically(path, |writer| {
        image::codecs::png::PngEncoder::new(writer)
            .write_image(bytes, width, height, colour)
            .map_err(|error| OutputError::Encode {
                path: path.to_path_buf(),
                fault: error.to_string(),
            })
    })
}

/// One linear RGBA pixel to display-ready 8-bit sRGB RGBA. Negative and NaN
/// values become black rather than poisoning the preview.
pub fn tone_map(pixel: Vec4) -> [u8; 4] {
    let rgb = pixel.truncate().max(Vec3::ZERO);
    let luminance = rgb.dot(LUMINANCE);
    let mapped = if luminance > 0.0 {
        rgb / (1.0 + luminance)
    } else {
        Vec3::ZERO
    };
    let [r, g, b] = mapped.to_array().map(|c| quantise(srgb_encode(c)));
    [r, g, b, quantise(pixel.w)]
}

/// The sRGB transfer function (IEC 61966-2-1) for a linear value in [0, 1].
fn srgb_encode(linear: f32) -> f32 {
    let linear = linear.clamp(0.0, 1.0);
    if linear <= 0.003_130_8 {
        linear * 12.92
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// [0, 1] to 0..=255 with rounding; NaN becomes 0 (`as` saturates).
fn quantise(value: f32) -> u8 {
    (value.clamp(0.0, 1.0) * 255.0).round() as u8
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_stop_up_doubles_the_linear_value_before_tone_mapping() {
        let dir = tempfile::tempdir().expect("tempdir");
        let pixel = Vec4::new(0.3, 0.2, 0.05, 1.0);
        let (brighter, doubled) = (dir.path().join("up.png"), dir.path().join("twice.png"));
        let image = |value: Vec4| Image::filled(2, 1, value);
        write_png_preview(&brighter, &image(pixel), 1.0).expect("write");
        write_png_preview(&doubled, &image((pixel.truncate() * 2.0).extend(1.0)), 0.0)
            .expect("write");
        let read = |path: &Path| image::open(path).expect("read").to_rgba8().into_raw();
        assert_eq!(read(&brighter), read(&doubled));
        assert_eq!(
            read(&brighter)[..4],
            tone_map(Vec4::new(0.6, 0.4, 0.1, 1.0))
        );
        assert_ne!(
            read(&brighter)[..4],
            tone_map(pixel),
            "the exposure changed nothing"
        );
    }

    #[test]
    fn tone_curve_keeps_black_and_white_points_sane() {
        assert_eq!(tone_map(Vec4::new(0.0, 0.0, 0.0, 1.0)), [0, 0, 0, 255]);
        // Luminance 1 maps to 0.5 linear, sRGB 0.735 → 188.
        assert_eq!(tone_map(Vec4::ONE), [188, 188, 188, 255]);
        // Very bright white approaches but never passes 255.
        assert_eq!(tone_map(Vec4::splat(1e6)), [255, 255, 255, 255]);
        assert_eq!(
            tone_map(Vec4::new(f32::NAN, -1.0, 0.0, f32::NAN)),
            [0, 0, 0, 0]
        );
    }

    #[test]
    fn tone_curve_is_monotonic() {
        let mut last = 0;
        for i in 0..1000 {
            let v = i as f32 * 0.05;
            let [r, ..] = tone_map(Vec4::new(v, v, v, 1.0));
            assert!(r >= last);
            last = r;
        }
    }

    #[test]
    fn preview_decodes_with_the_right_size() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("previews/frame.0001.png");
        let image = Image {
            width: 5,
            height: 3,
            pixels: (0..15)
                .map(|i| Vec4::new(i as f32, 0.5, 0.0, 1.0))
                .collect(),
        };
        write_png_preview(&path, &image, 0.0).unwrap();
        let decoded = image::open(&path).unwrap().to_rgba8();
        assert_eq!(decoded.dimensions(), (5, 3));
        // Top row first: pixel (1, 0) is the second value written.
        assert_eq!(decoded.get_pixel(1, 0).0, tone_map(image.pixels[1]));
        assert_eq!(decoded.get_pixel(4, 2).0, tone_map(image.pixels[14]));
    }
}
