//! Reading EXRs back: lmanim's own frames (the contact sheet over frames
//! on disk) and other renderers' references and masks (`lmanim study`).
//! One reader for both, so a file one accepts the other accepts too.
//!
//! Any common layout is read: the channels `R`, `G`, `B` (with or without
//! `A`), `Y` (with or without `A`), or `A` alone, in half, float or uint
//! samples, from a single-part or a multi-part file. Which channels are
//! the picture:
//!
//! - no layer named: the beauty, the first part with channels of its own
//!   (a name without a layer prefix, such as `R` or, in a part named
//!   `rgba`, `rgba.R`): lmanim's frames (beauty beside `light.Lamp.R`,
//!   `N.X`…) and the usual multi-part files (the beauty first) alike;
//! - a layer `L` named: the channels `L.R`, `L.G`… of the first part that
//!   holds them, either as prefixed names in one part (Blender's
//!   `ViewLayer.Combined.R`) or as a part named `L`.
//!
//! A file with none of those is refused in one line naming the channels
//! it holds, so the user sees which layer to name.

use std::path::Path;

use exr::prelude::{AnyChannel, AnyChannels, FlatSamples, Layer, ReadChannels, ReadLayers};
use glam::{Vec3, Vec4};

use super::{Image, OutputError};

/// Which channels a picture was read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExrChannels {
    /// Luminance alone: read as grey, opaque.
    Y,
    /// Luminance and alpha: grey.
    YA,
    /// Alpha alone: read as grey of that level, as viewers show it.
    A,
    /// Colour without alpha: opaque.
    Rgb,
    Rgba,
}

impl ExrChannels {
    pub fn has_alpha(self) -> bool {
        matches!(self, ExrChannels::YA | ExrChannels::A | ExrChannels::Rgba)
    }

    /// The layout of a part holding the channels `has` says it holds, or
    /// why it has none lmanim reads.
    fn of(has: impl Fn(&str) -> bool) -> Result<ExrChannels, String> {
        let colour = ["R", "G", "B"].map(&has);
        let alpha = has("A");
        if has("RY") || has("BY") {
            return Err("luminance-chroma channels (RY, BY) are not read".into());
        }
        Ok(match (colour, has("Y"), alpha) {
            ([true, true, true], _, false) => ExrChannels::Rgb,
            ([true, true, true], _, true) => ExrChannels::Rgba,
            ([false, false, false], true, false) => ExrChannels::Y,
            ([false, false, false], true, true) => ExrChannels::YA,
            ([false, false, false], false, true) => ExrChannels::A,
            ([false, false, false], false, false) => {
                return Err("no R, G, B, Y or A channel".into())
            }
            _ => return Err("R, G and B are not all there".into()),
        })
    }
}

/// A picture read from an EXR, with the channels it came from.
#[derive(Clone, Debug, PartialEq)]
pub struct ExrPicture {
    /// Linear RGBA: Y as grey, alpha 1 where the file has none.
    pub image: Image,
    pub channels: ExrChannels,
}

impl ExrPicture {
    /// Per pixel, the one value a mask is read from: alpha where the file
    /// has it (a matte's usual channel), else the largest of R, G and B
    /// (which is Y in a one-channel file): never the alpha of 1 the
    /// reader fills in, which would make every pixel part of the mask.
    pub fn matte(&self) -> Vec<f32> {
        let alpha = self.channels.has_alpha();
        (self.image.pixels.iter())
            .map(|p| {
                if alpha {
                    p.w
                } else {
                    p.truncate().max_element()
                }
            })
            .collect()
    }
}

/// Reads the beauty of an EXR as RGBA (see the module doc for the
/// layouts read), e.g. a frame back from disk.
pub fn read_exr(path: &Path) -> Result<Image, OutputError> {
    read_exr_picture(path, None).map(|picture| picture.image)
}

/// Reads the picture of `layer` (the beauty when None) from an EXR.
pub fn read_exr_picture(path: &Path, layer: Option<&str>) -> Result<ExrPicture, OutputError> {
    let read_error = |fault: String| OutputError::ReadExr {
        path: path.to_path_buf(),
        fault,
    };
    let file = exr::prelude::read()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .all_layers()
        .all_attributes()
        .from_file(path)
        .map_err(|error| read_error(error.to_string()))?;
    let parts = &file.layer_data;
    let chosen = (parts.iter())
        .map(|part| picture_channels(part, layer))
        .find(|chosen| !chosen.channels.is_empty());
    let Some(chosen) = chosen else {
        let wanted = layer.map_or(
            "no beauty (R, G, B, Y or A without a layer prefix)".into(),
            |name| format!("no layer '{name}'"),
        );
        return Err(read_error(format!("{wanted}; found {}", found(parts))));
    };
    picture(&chosen).map_err(|fault| read_error(format!("{fault}; found {}", found(parts))))
}

/// The channels of one part that make a picture, by their names within
/// the layer (`R`, `Y`…), and the part's size.
struct Chosen<'a> {
    channels: Vec<(String, &'a AnyChannel<FlatSamples>)>,
    width: usize,
    height: usize,
}

/// The channels of `part` that are the picture of `layer` (the beauty
/// when None).
fn picture_channels<'a>(
    part: &'a Layer<AnyChannels<FlatSamples>>,
    layer: Option<&str>,
) -> Chosen<'a> {
    let part_name = part_name(part);
    let prefix = layer.or(part_name.as_deref());
    let channels = (part.channel_data.list.iter())
        .filter_map(|channel| {
            let full = full_name(part_name.as_deref(), channel);
            let own = match prefix {
                Some(prefix) => full.strip_prefix(prefix)?.strip_prefix('.')?,
                None => full.as_str(),
            };
            let read = ["R", "G", "B", "A", "Y", "RY", "BY"].contains(&own);
            read.then(|| (own.to_owned(), channel))
        })
        .collect();
    Chosen {
        channels,
        width: part.size.width(),
        height: part.size.height(),
    }
}

fn part_name(part: &Layer<AnyChannels<FlatSamples>>) -> Option<String> {
    (part.attributes.layer_name.as_ref()).map(|name| name.to_string())
}

/// A channel's name with its part's name in front (`diffuse.R`), as
/// compositors show a multi-part file's channels; a name that already
/// starts with it is kept.
fn full_name(part_name: Option<&str>, channel: &AnyChannel<FlatSamples>) -> String {
    let name = channel.name.to_string();
    match part_name {
        Some(part) if !name.starts_with(&format!("{part}.")) => format!("{part}.{name}"),
        _ => name,
    }
}

/// The picture the chosen channels of one part make.
fn picture(chosen: &Chosen) -> Result<ExrPicture, String> {
    let find = |own: &str| chosen.channels.iter().find(|(name, _)| name == own);
    let layout = ExrChannels::of(|own| find(own).is_some())?;
    let pixel_count = chosen.width * chosen.height;
    if pixel_count == 0 {
        return Err("the image is empty".into());
    }
    let values = |own: &str| -> Result<Option<Vec<f32>>, String> {
        let Some((_, channel)) = find(own) else {
            return Ok(None);
        };
        let values: Vec<f32> = channel.sample_data.values_as_f32().collect();
        match values.len() == pixel_count {
            true => Ok(Some(values)),
            false => Err(format!("channel {own} is subsampled, which is not read")),
        }
    };
    let [r, g, b, y, a] = ["R", "G", "B", "Y", "A"].map(values);
    let (r, g, b, y, a) = (r?, g?, b?, y?, a?);
    let at = |values: &Option<Vec<f32>>, i: usize, otherwise: f32| {
        values.as_ref().map_or(otherwise, |values| values[i])
    };
    let pixels = (0..pixel_count)
        .map(|i| {
            let alpha = at(&a, i, 1.0);
            match layout {
                ExrChannels::Rgb | ExrChannels::Rgba => {
                    Vec4::new(at(&r, i, 0.0), at(&g, i, 0.0), at(&b, i, 0.0), alpha)
                }
                ExrChannels::Y | ExrChannels::YA => Vec3::splat(at(&y, i, 0.0)).extend(alpha),
                ExrChannels::A => Vec4::splat(alpha),
            }
        })
        .collect();
    Ok(ExrPicture {
        image: Image {
            width: chosen.width as u32,
            height: chosen.height as u32,
            pixels,
        },
        channels: layout,
    })
}

/// Every channel of the file by its full name (`layer.channel`), for a
/// refusal to show what the file holds.
fn found(parts: &[Layer<AnyChannels<FlatSamples>>]) -> String {
    let names: Vec<String> = parts
        .iter()
        .flat_map(|part| {
            let part_name = part_name(part);
            (part.channel_data.list.iter())
                .map(move |channel| full_name(part_name.as_deref(), channel))
        })
        .collect();
    match names.is_empty() {
        true => "no channels".into(),
        false => format!("channels {}", names.join(", ")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use exr::prelude::{Encoding, ImageAttributes, LayerAttributes, SmallVec, WritableImage};

    const SIZE: (usize, usize) = (3, 2);

    /// A channel's name and the base of its [`value`]s.
    type Channel<'a> = (&'a str, f32);
    /// A part's name, if any, and its channels.
    type Part<'a> = (Option<&'a str>, &'a [Channel<'a>]);

    /// Channel `base`'s value at pixel `i`: distinct for every channel
    /// and pixel, so a swapped channel or pixel shows.
    fn value(base: f32, i: usize) -> f32 {
        base + i as f32 * 0.25
    }

    /// Writes an EXR of 3×2 pixels with one part per `(name, channels)`,
    /// each channel `(name, base)` holding [`value`]s, as another tool
    /// would lay it out.
    fn write_parts(path: &Path, parts: &[Part]) {
        let layers: Vec<_> = parts
            .iter()
            .map(|(name, channels)| {
                let list: SmallVec<[AnyChannel<FlatSamples>; 4]> = (channels.iter())
                    .map(|&(channel, base)| {
                        let values = (0..SIZE.0 * SIZE.1).map(|i| value(base, i)).collect();
                        AnyChannel::new(channel, FlatSamples::F32(values))
                    })
                    .collect();
                let attributes = name.map_or_else(LayerAttributes::default, LayerAttributes::named);
                Layer::new(
                    SIZE,
                    attributes,
                    Encoding::UNCOMPRESSED,
                    AnyChannels::sort(list),
                )
            })
            .collect();
        exr::image::Image::from_layers(ImageAttributes::with_size(SIZE), layers)
            .write()
            .to_file(path)
            .unwrap();
    }

    fn read(parts: &[Part], layer: Option<&str>) -> ExrPicture {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("in.exr");
        write_parts(&path, parts);
        read_exr_picture(&path, layer).unwrap()
    }

    fn refusal(parts: &[Part], layer: Option<&str>) -> String {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("odd.exr");
        write_parts(&path, parts);
        let message = read_exr_picture(&path, layer).unwrap_err().to_string();
        assert!(
            message.contains("odd.exr") && !message.contains('\n'),
            "{message}"
        );
        message
    }

    #[test]
    fn each_common_layout_is_read_as_rgba() {
        // The channels written, the layout read, the first pixel read and
        // its change from one pixel to the next.
        type Case<'a> = (&'a [Channel<'a>], ExrChannels, [f32; 4], [f32; 4]);
        let rgba: &[Channel] = &[("R", 1.0), ("G", 2.0), ("B", 3.0), ("A", 4.0)];
        let cases: [Case; 5] = [
            (rgba, ExrChannels::Rgba, [1.0, 2.0, 3.0, 4.0], [0.25; 4]),
            (
                &rgba[..3],
                ExrChannels::Rgb,
                [1.0, 2.0, 3.0, 1.0],
                [0.25, 0.25, 0.25, 0.0],
            ),
            (
                &[("Y", 5.0)],
                ExrChannels::Y,
                [5.0, 5.0, 5.0, 1.0],
                [0.25, 0.25, 0.25, 0.0],
            ),
            (
                &[("Y", 5.0), ("A", 6.0)],
                ExrChannels::YA,
                [5.0, 5.0, 5.0, 6.0],
                [0.25; 4],
            ),
            (&[("A", 7.0)], ExrChannels::A, [7.0; 4], [0.25; 4]),
        ];
        for (channels, layout, first, step) in cases {
            let picture = read(&[(None, channels)], None);
            assert_eq!(picture.channels, layout);
            assert_eq!((picture.image.width, picture.image.height), (3, 2));
            for (i, pixel) in picture.image.pixels.iter().enumerate() {
                let expected = Vec4::from(first) + Vec4::from(step) * i as f32;
                assert_eq!(*pixel, expected, "{layout:?} pixel {i}");
            }
        }
    }

    #[test]
    fn the_beauty_is_the_channels_without_a_layer_prefix() {
        // lmanim's own frames: the beauty beside AOV layers in one part.
        let picture = read(
            &[(
                None,
                &[
                    ("R", 1.0),
                    ("G", 2.0),
                    ("B", 3.0),
                    ("A", 4.0),
                    ("Z", 9.0),
                    ("N.X", 8.0),
                    ("light.Lamp.R", 7.0),
                ],
            )],
            None,
        );
        assert_eq!(picture.image.pixels[0], Vec4::new(1.0, 2.0, 3.0, 4.0));
        // Multi-part: the first part with channels of its own.
        let parts: &[Part] = &[
            (Some("depth"), &[("Z", 9.0)]),
            (Some("rgba"), &[("R", 1.0), ("G", 2.0), ("B", 3.0)]),
            (
                Some("diffuse"),
                &[("diffuse.R", 4.0), ("diffuse.G", 5.0), ("diffuse.B", 6.0)],
            ),
        ];
        let picture = read(parts, None);
        assert_eq!(picture.image.pixels[0], Vec4::new(1.0, 2.0, 3.0, 1.0));
        // A layer named: by its part's name, with or without the prefix.
        let picture = read(parts, Some("diffuse"));
        assert_eq!(picture.image.pixels[0], Vec4::new(4.0, 5.0, 6.0, 1.0));
        let picture = read(parts, Some("rgba"));
        assert_eq!(picture.image.pixels[0], Vec4::new(1.0, 2.0, 3.0, 1.0));
    }

    #[test]
    fn a_layer_is_found_by_its_prefix_in_one_part() {
        let part: &[(&str, f32)] = &[
            ("ViewLayer.Combined.R", 1.0),
            ("ViewLayer.Combined.G", 2.0),
            ("ViewLayer.Combined.B", 3.0),
            ("ViewLayer.Combined.A", 4.0),
            ("ViewLayer.Mask.Y", 5.0),
        ];
        let picture = read(&[(None, part)], Some("ViewLayer.Combined"));
        assert_eq!(picture.channels, ExrChannels::Rgba);
        assert_eq!(picture.image.pixels[1], Vec4::new(1.25, 2.25, 3.25, 4.25));
        let mask = read(&[(None, part)], Some("ViewLayer.Mask"));
        assert_eq!(mask.channels, ExrChannels::Y);
        // No beauty of its own: the refusal lists what the file holds.
        let message = refusal(&[(None, part)], None);
        assert!(message.contains("no beauty"), "{message}");
        assert!(message.contains("ViewLayer.Combined.R, "), "{message}");
    }

    #[test]
    fn a_refusal_names_the_channels_found() {
        let message = refusal(&[(None, &[("R", 1.0), ("G", 2.0)])], None);
        assert!(
            message.contains("R, G and B are not all there"),
            "{message}"
        );
        assert!(message.contains("found channels G, R"), "{message}");
        let message = refusal(
            &[(Some("rgba"), &[("R", 1.0), ("G", 2.0), ("B", 3.0)])],
            Some("spec"),
        );
        assert!(
            message.contains("no layer 'spec'; found channels rgba.B, rgba.G, rgba.R"),
            "{message}"
        );
        let message = refusal(&[(None, &[("Y", 1.0), ("RY", 2.0), ("BY", 3.0)])], None);
        assert!(message.contains("luminance-chroma"), "{message}");
    }

    #[test]
    fn a_matte_is_alpha_else_the_largest_colour_channel() {
        let matte = |channels: &[(&str, f32)]| read(&[(None, channels)], None).matte();
        let alpha = matte(&[("R", 0.0), ("G", 0.0), ("B", 0.0), ("A", -0.25)]);
        assert_eq!(alpha, [-0.25, 0.0, 0.25, 0.5, 0.75, 1.0]);
        let luminance = matte(&[("Y", -0.5)]);
        assert_eq!(luminance, [-0.5, -0.25, 0.0, 0.25, 0.5, 0.75]);
        let colour = matte(&[("R", -1.0), ("G", -0.5), ("B", -2.0)]);
        assert_eq!(colour, [-0.5, -0.25, 0.0, 0.25, 0.5, 0.75]);
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
