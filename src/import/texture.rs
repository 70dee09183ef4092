//! Decoding the images that colour textures use into linear RGBA texels.
//!
//! Only base-colour and emissive textures are imported, and the glTF spec
//! stores both sRGB-encoded, so every texel's RGB is decoded to linear here
//! (alpha is linear already). Image sizes are checked before decoding, so a
//! header that claims a gigapixel cannot make import allocate it.

use std::io::Cursor;
use std::path::Path;

use glam::Vec4;
use gltf::texture::WrappingMode;

use super::error::Fault;
use super::uri;
use crate::scene::{Texture, Wrap};

/// The largest texture accepted, in texels (1 GiB as linear `Vec4`s).
const MAX_TEXELS: u64 = 1 << 26;

/// Decodes `texture`'s image and takes its sampler's wrap modes.
pub fn import(texture: &gltf::Texture, buffers: &[Vec<u8>], base: &Path) -> Result<Texture, Fault> {
    let image = texture.source();
    let fault = |reason: String| Fault::Image {
        image: image.index(),
        reason,
    };
    let encoded = match image.source() {
        gltf::image::Source::View { view, .. } => {
            // Buffer views were checked against their buffers at load.
            let start = view.offset();
            buffers[view.buffer().index()][start..start + view.length()].to_vec()
        }
        gltf::image::Source::Uri { uri, .. } => {
            uri::read(uri, base, uri::Resource::Image).map_err(fault)?
        }
    };
    let decoded = decode(&encoded).map_err(fault)?;
    let sampler = texture.sampler();
    Ok(Texture {
        width: decoded.width(),
        height: decoded.height(),
        texels: decoded
            .pixels()
            .map(|texel| {
                let [r, g, b, a] = texel.0;
                Vec4::new(srgb_to_linear(r), srgb_to_linear(g), srgb_to_linear(b), a)
            })
            .collect(),
        wrap_s: wrap(sampler.wrap_s()),
        wrap_t: wrap(sampler.wrap_t()),
    })
}

fn decode(encoded: &[u8]) -> Result<image::Rgba32FImage, String> {
    let reader = || {
        image::ImageReader::new(Cursor::new(encoded))
            .with_guessed_format()
            .map_err(|error| error.to_string())
    };
    let (width, height) = reader()?
        .into_dimensions()
        .map_err(|error| error.to_string())?;
    if u64::from(width) * u64::from(height) > MAX_TEXELS {
        return Err(format!(
            "{width}×{height} texels is more than the {MAX_TEXELS} accepted"
        ));
    }
    let image = reader()?.decode().map_err(|error| error.to_string())?;
    Ok(image.to_rgba32f())
}

/// The sRGB transfer function's inverse (IEC 61966-2-1).
fn srgb_to_linear(encoded: f32) -> f32 {
    if encoded <= 0.04045 {
        encoded / 12.92
    } else {
        ((encoded + 0.055) / 1.055).powf(2.4)
    }
}

fn wrap(mode: WrappingMode) -> Wrap {
    match mode {
        WrappingMode::Repeat => Wrap::Repeat,
        WrappingMode::MirroredRepeat => Wrap::MirroredRepeat,
        WrappingMode::ClampToEdge => Wrap::ClampToEdge,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn srgb_decoding_fixes_black_white_and_mid_grey() {
        assert_eq!(srgb_to_linear(0.0), 0.0);
        assert!((srgb_to_linear(1.0) - 1.0).abs() < 1e-6);
        // sRGB 188/255 is the usual "middle grey" of linear 0.5.
        assert!((srgb_to_linear(188.0 / 255.0) - 0.5).abs() < 0.005);
    }
}
