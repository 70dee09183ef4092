//! The study's error measure: how far a frame is from the reference, in
//! units of the light each pixel would get without shadows.
//!
//! Per pixel, with Y the Rec.709 luminance, R the reference, U the
//! unshadowed frame (every light visible, lmanim's own) and I the frame
//! measured, the error is `e = (Y(I) − Y(R)) / max(Y(U), Y(R))`: the share
//! of the pixel's available direct light that the frame gets wrong. That
//! makes a dark corner and a lit floor count alike, and a shadow wrong by
//! a tenth of its lamp the same everywhere. The reference is in the
//! denominator too because a spherical lamp can light a surface that its
//! point light only grazes (a lamp post's side beside its lamp): there the
//! point light's U is near 0, and the error is a share of what the lamp
//! gives instead of a multiple of nothing.
//!
//! Pixels taken into account ("lit"): U is at least [`LIT_FLOOR`] of the
//! brightest unshadowed pixel, the reference's mask (if any) is not above
//! 0 there (see [`Mask`]), and
//! the pixel is not on a geometric edge, where the frame's pixel centre
//! and the reference's pixel area see different surfaces: the error there
//! is anti-aliasing, which no shadow method changes. A pixel is on an
//! edge when U at its centre and U averaged over its area differ by more
//! than [`EDGE_TOLERANCE`]. Penumbra pixels are the lit ones where the
//! reference lies strictly between [`PENUMBRA`]'s bounds of U.

use glam::Vec4;
use serde::Serialize;

use crate::output::{ExrPicture, Image};

/// Unshadowed luminance, as a share of the frame's brightest, below which
/// a pixel is left out (its relative error would only measure noise).
pub const LIT_FLOOR: f64 = 1e-3;
/// Relative difference between the unshadowed pixel centre and pixel area
/// above which a pixel counts as a geometric edge.
pub const EDGE_TOLERANCE: f64 = 0.01;
/// A penumbra pixel's reference lies within these shares of its
/// unshadowed value.
pub const PENUMBRA: (f64, f64) = (0.02, 0.98);
/// An error counts as "within 1%" up to this.
pub const WITHIN: f64 = 0.01;

/// Rec.709 luminance of a linear RGB pixel.
pub fn luminance(pixel: Vec4) -> f64 {
    0.2126 * f64::from(pixel.x) + 0.7152 * f64::from(pixel.y) + 0.0722 * f64::from(pixel.z)
}

/// Whether a pixel whose reference is `reference` and whose unshadowed
/// value is `unshadowed` (luminances, `unshadowed > 0`) lies in a penumbra.
pub fn is_penumbra(reference: f64, unshadowed: f64) -> bool {
    let share = reference / unshadowed;
    PENUMBRA.0 < share && share < PENUMBRA.1
}

/// Why images cannot be compared.
#[derive(Debug, thiserror::Error, PartialEq, Eq)]
#[error("{what} is {found_width}x{found_height}, the study renders {width}x{height}")]
pub struct SizeMismatch {
    pub what: String,
    pub found_width: u32,
    pub found_height: u32,
    pub width: u32,
    pub height: u32,
}

/// The pixels a reference's mask leaves out: those whose matte is above
/// 0, the matte being the mask file's alpha where it has one, else its
/// luminance (a one-channel `Y` file) or its largest colour channel
/// ([`ExrPicture::matte`]).
#[derive(Clone, Debug, PartialEq)]
pub struct Mask {
    pub width: u32,
    pub height: u32,
    /// Per pixel, row-major: left out.
    pub left_out: Vec<bool>,
}

impl Mask {
    pub fn of(picture: &ExrPicture) -> Mask {
        Mask {
            width: picture.image.width,
            height: picture.image.height,
            left_out: picture.matte().iter().map(|&matte| matte > 0.0).collect(),
        }
    }
}

/// The reference with what the measure needs per pixel.
#[derive(Clone, Debug)]
pub struct Reference {
    pub image: Image,
    /// Per pixel, the light the error is a share of: the larger of the
    /// unshadowed luminance at its centre and the reference's.
    available: Vec<f64>,
    /// Pixels taken into account.
    lit: Vec<bool>,
    penumbra: Vec<bool>,
    pub census: Census,
}

/// How the reference's pixels were classified.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Census {
    pub pixels: usize,
    pub lit_pixels: usize,
    pub penumbra_pixels: usize,
    /// Left out as geometric edges.
    pub edge_pixels: usize,
    /// Left out by the reference's mask.
    pub masked_pixels: usize,
}

impl Census {
    /// Why a reference so classified gives the study nothing to rank, if
    /// it does: no lit pixel (every error would be over nothing), or no
    /// penumbra pixel (soft shadows, what the methods differ in, are
    /// nowhere in view).
    pub fn nothing_to_measure(&self) -> Option<String> {
        let why = match (self.lit_pixels, self.penumbra_pixels) {
            (0, _) => "no lit pixel",
            (_, 0) => "no penumbra pixel",
            _ => return None,
        };
        Some(format!(
            "the reference leaves {why} to measure (of {} pixels: {} lit, {} left out by the mask, {} on geometric edges, the rest unlit)",
            self.pixels, self.lit_pixels, self.masked_pixels, self.edge_pixels
        ))
    }
}

impl Reference {
    /// `image` measured against `unshadowed_centre` (one sample at each
    /// pixel centre, as the frames measured are rendered) and
    /// `unshadowed_area` (several samples over each pixel, as the
    /// reference is); the pixels `mask` leaves out are left out.
    pub fn new(
        image: Image,
        unshadowed_centre: &Image,
        unshadowed_area: &Image,
        mask: Option<&Mask>,
    ) -> Result<Reference, SizeMismatch> {
        let size = |image: &Image| (image.width, image.height);
        same_size("the unshadowed frame", size(unshadowed_centre), &image)?;
        same_size("the unshadowed frame", size(unshadowed_area), &image)?;
        if let Some(mask) = mask {
            same_size("the reference mask", (mask.width, mask.height), &image)?;
        }
        let unshadowed: Vec<f64> = unshadowed_centre
            .pixels
            .iter()
            .map(|&p| luminance(p))
            .collect();
        let brightest = unshadowed.iter().copied().fold(0.0, f64::max);
        let mut census = Census {
            pixels: image.pixels.len(),
            ..Census::default()
        };
        let mut lit = vec![false; image.pixels.len()];
        let mut penumbra = vec![false; image.pixels.len()];
        for (i, &u) in unshadowed.iter().enumerate() {
            if u <= 0.0 || u < LIT_FLOOR * brightest {
                continue;
            }
            if mask.is_some_and(|mask| mask.left_out[i]) {
                census.masked_pixels += 1;
                continue;
            }
            let area = luminance(unshadowed_area.pixels[i]);
            if (u - area).abs() > EDGE_TOLERANCE * u.max(area) {
                census.edge_pixels += 1;
                continue;
            }
            lit[i] = true;
            census.lit_pixels += 1;
            if is_penumbra(luminance(image.pixels[i]), u) {
                penumbra[i] = true;
                census.penumbra_pixels += 1;
            }
        }
        let available = (unshadowed.iter().zip(&image.pixels))
            .map(|(&u, &r)| u.max(luminance(r)))
            .collect();
        Ok(Reference {
            image,
            available,
            lit,
            penumbra,
            census,
        })
    }

    /// Whether pixel `index` is a penumbra pixel that the measure takes.
    pub fn is_penumbra_pixel(&self, index: usize) -> bool {
        self.penumbra[index]
    }

    /// How far `image` is from the reference.
    pub fn errors(&self, image: &Image) -> Result<Errors, SizeMismatch> {
        let (errors, _) = self.sequence_errors(std::slice::from_ref(image))?;
        Ok(errors)
    }

    /// How far the frames of a still sequence are from the reference,
    /// every pixel of every frame counted once (for one frame, that
    /// frame's errors), and how much they flicker (None for fewer than
    /// two frames).
    pub fn sequence_errors(
        &self,
        frames: &[Image],
    ) -> Result<(Errors, Option<Flicker>), SizeMismatch> {
        for frame in frames {
            same_size(
                "the frame measured",
                (frame.width, frame.height),
                &self.image,
            )?;
        }
        let mut lit = Accumulator::default();
        let mut penumbra = Accumulator::default();
        // Per pixel, the variance of its error over the frames, summed.
        let (mut lit_variance, mut penumbra_variance) = (0.0, 0.0);
        let mut errors = Vec::with_capacity(frames.len());
        for (i, reference) in self.image.pixels.iter().enumerate() {
            if !self.lit[i] {
                continue;
            }
            let reference = luminance(*reference);
            errors.clear();
            errors.extend(
                frames
                    .iter()
                    .map(|frame| (luminance(frame.pixels[i]) - reference) / self.available[i]),
            );
            for &error in &errors {
                lit.add(error);
                if self.penumbra[i] {
                    penumbra.add(error);
                }
            }
            let variance = sample_variance(&errors);
            lit_variance += variance;
            if self.penumbra[i] {
                penumbra_variance += variance;
            }
        }
        let errors = Errors {
            rmse: lit.rms().unwrap_or(0.0),
            penumbra_rmse: penumbra.rms(),
            max_error: lit.largest,
            within_1pct: lit.within_share().unwrap_or(1.0),
        };
        let pixels = |count: usize| (count / frames.len().max(1)) as f64;
        let flicker = (frames.len() > 1).then(|| Flicker {
            lit: (lit_variance / pixels(lit.count).max(1.0)).sqrt(),
            penumbra: (penumbra.count > 0)
                .then(|| (penumbra_variance / pixels(penumbra.count)).sqrt()),
        });
        Ok((errors, flicker))
    }
}

/// The unbiased variance of `values` (0 for fewer than two), taken about
/// the first value so that equal values give exactly 0.
fn sample_variance(values: &[f64]) -> f64 {
    let [first, ..] = values else {
        return 0.0;
    };
    if values.len() < 2 {
        return 0.0;
    }
    let n = values.len() as f64;
    let mean = values.iter().map(|v| v - first).sum::<f64>() / n;
    let squares: f64 = values.iter().map(|v| (v - first - mean).powi(2)).sum();
    squares / (n - 1.0)
}

fn same_size(
    what: &str,
    (width, height): (u32, u32),
    reference: &Image,
) -> Result<(), SizeMismatch> {
    if (width, height) == (reference.width, reference.height) {
        return Ok(());
    }
    Err(SizeMismatch {
        what: what.into(),
        found_width: width,
        found_height: height,
        width: reference.width,
        height: reference.height,
    })
}

/// One frame's errors against the reference (see the module doc).
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Errors {
    /// Root mean square of the relative error over lit pixels.
    pub rmse: f64,
    /// The same over penumbra pixels; None when the reference has none.
    pub penumbra_rmse: Option<f64>,
    /// The largest relative error (in magnitude) over lit pixels.
    pub max_error: f64,
    /// Share of lit pixels whose error is at most 1%.
    pub within_1pct: f64,
}

/// How much the frames of a still sequence differ from one another where
/// nothing changes: per pixel, the standard deviation over the frames of
/// its error (its luminance as a share of the light available there, the
/// error's units), root mean square over the lit pixels and over the
/// penumbra. 0 for a method that renders the same frame every time; a
/// Monte Carlo renderer whose noise a new seed redraws each frame shows
/// it here even where a denoiser smooths every single frame.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct Flicker {
    pub lit: f64,
    /// None when the reference has no penumbra pixel.
    pub penumbra: Option<f64>,
}

#[derive(Default)]
struct Accumulator {
    count: usize,
    squares: f64,
    largest: f64,
    within: usize,
}

impl Accumulator {
    fn add(&mut self, error: f64) {
        self.count += 1;
        self.squares += error * error;
        self.largest = self.largest.max(error.abs());
        self.within += usize::from(error.abs() <= WITHIN);
    }

    fn rms(&self) -> Option<f64> {
        (self.count > 0).then(|| (self.squares / self.count as f64).sqrt())
    }

    fn within_share(&self) -> Option<f64> {
        (self.count > 0).then(|| self.within as f64 / self.count as f64)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn grey(width: u32, height: u32, level: impl Fn(u32, u32) -> f32) -> Image {
        let pixels = (0..height)
            .flat_map(|y| (0..width).map(move |x| (x, y)))
            .map(|(x, y)| Vec4::new(1.0, 1.0, 1.0, 1.0) * level(x, y))
            .collect();
        Image {
            width,
            height,
            pixels,
        }
    }

    /// A floor under a lamp, 2 at the left falling to 1 at the right, half
    /// of it (the left) in a shadow ramp from 0 to the full value.
    fn scene() -> (Image, Image) {
        let unshadowed = grey(10, 4, |x, _| 2.0 - x as f32 / 9.0);
        let reference = grey(10, 4, |x, _| {
            let u = 2.0 - x as f32 / 9.0;
            u * (x as f32 / 5.0).min(1.0)
        });
        (reference, unshadowed)
    }

    #[test]
    fn an_identical_frame_has_no_error() {
        let (reference, unshadowed) = scene();
        let measure = Reference::new(reference.clone(), &unshadowed, &unshadowed, None).unwrap();
        let errors = measure.errors(&reference).unwrap();
        assert_eq!(errors.rmse, 0.0);
        assert_eq!(errors.penumbra_rmse, Some(0.0));
        assert_eq!(errors.max_error, 0.0);
        assert_eq!(errors.within_1pct, 1.0);
    }

    #[test]
    fn an_offset_of_a_share_of_the_unshadowed_light_is_that_share() {
        let (reference, unshadowed) = scene();
        let measure = Reference::new(reference.clone(), &unshadowed, &unshadowed, None).unwrap();
        // Darker frames: the reference never exceeds U here, so U is the
        // light the error is a share of.
        for offset in [-0.005f32, -0.03, -0.2] {
            let mut frame = reference.clone();
            for (p, u) in frame.pixels.iter_mut().zip(&unshadowed.pixels) {
                *p += *u * offset;
            }
            let errors = measure.errors(&frame).unwrap();
            let expected = f64::from(offset.abs());
            assert!((errors.rmse - expected).abs() < 1e-6, "{errors:?}");
            assert!((errors.penumbra_rmse.unwrap() - expected).abs() < 1e-6);
            assert!((errors.max_error - expected).abs() < 1e-6);
            let within = if offset.abs() <= 0.01 { 1.0 } else { 0.0 };
            assert_eq!(errors.within_1pct, within, "{offset}");
        }
    }

    #[test]
    fn where_the_reference_outshines_the_unshadowed_light_it_is_the_scale() {
        let (reference, unshadowed) = scene();
        // A pixel the lamp lights at 4 where the point light gives 1 (a
        // surface the point light grazes): a frame of 0 there is 100% off.
        let mut bright = reference.clone();
        bright.pixels[9] = Vec4::splat(4.0);
        let mut grazed = unshadowed.clone();
        grazed.pixels[9] = Vec4::splat(1.0);
        let measure = Reference::new(bright.clone(), &grazed, &grazed, None).unwrap();
        let mut frame = bright;
        frame.pixels[9] = Vec4::ZERO;
        let errors = measure.errors(&frame).unwrap();
        assert!((errors.max_error - 1.0).abs() < 1e-9, "{errors:?}");
    }

    #[test]
    fn a_still_sequence_pools_its_errors_and_measures_its_flicker() {
        let (reference, unshadowed) = scene();
        let measure = Reference::new(reference.clone(), &unshadowed, &unshadowed, None).unwrap();
        // Frames alternately brighter and darker by a tenth of U: each
        // pixel's error is ±0.1, its standard deviation over the four
        // frames √(4·0.01 / 3).
        let shifted = |offset: f32| {
            let mut frame = reference.clone();
            for (p, u) in frame.pixels.iter_mut().zip(&unshadowed.pixels) {
                *p += *u * offset;
            }
            frame
        };
        let frames = [shifted(0.1), shifted(-0.1), shifted(0.1), shifted(-0.1)];
        let (errors, flicker) = measure.sequence_errors(&frames).unwrap();
        assert!((errors.rmse - 0.1).abs() < 1e-6, "{errors:?}");
        assert!((errors.penumbra_rmse.unwrap() - 0.1).abs() < 1e-6);
        let flicker = flicker.unwrap();
        let expected = (4.0 * 0.01f64 / 3.0).sqrt();
        assert!((flicker.lit - expected).abs() < 1e-6, "{flicker:?}");
        assert!((flicker.penumbra.unwrap() - expected).abs() < 1e-6);
        // The same frame every time: the one frame's errors (up to the
        // order of the sums), no flicker.
        let still = [shifted(0.1), shifted(0.1), shifted(0.1)];
        let (pooled, flicker) = measure.sequence_errors(&still).unwrap();
        let one = measure.errors(&still[0]).unwrap();
        assert!((pooled.rmse - one.rmse).abs() < 1e-12);
        assert!((pooled.penumbra_rmse.unwrap() - one.penumbra_rmse.unwrap()).abs() < 1e-12);
        assert_eq!(
            (pooled.max_error, pooled.within_1pct),
            (one.max_error, one.within_1pct)
        );
        assert_eq!(flicker.unwrap().lit, 0.0);
        // One frame is no sequence.
        assert_eq!(measure.sequence_errors(&still[..1]).unwrap().1, None);
        // A frame of another size anywhere in the sequence is refused.
        let small = grey(5, 4, |_, _| 1.0);
        assert!(measure.sequence_errors(&[reference, small]).is_err());
    }

    #[test]
    fn an_error_in_one_pixel_counts_once() {
        let (reference, unshadowed) = scene();
        let measure = Reference::new(reference.clone(), &unshadowed, &unshadowed, None).unwrap();
        let mut frame = reference.clone();
        // Pixel (7, 0) is fully lit: U = 2 − 7/9.
        let u = 2.0 - 7.0 / 9.0;
        frame.pixels[7] += Vec4::splat(0.5 * u);
        let errors = measure.errors(&frame).unwrap();
        assert!((errors.max_error - 0.5).abs() < 1e-6);
        assert!((errors.rmse - (0.25f64 / 40.0).sqrt()).abs() < 1e-6);
        assert_eq!(errors.within_1pct, 39.0 / 40.0);
        // Not a penumbra pixel: the penumbra's error stays 0.
        assert_eq!(errors.penumbra_rmse, Some(0.0));
    }

    #[test]
    fn the_penumbra_is_where_the_reference_is_partly_lit() {
        let (reference, unshadowed) = scene();
        let measure = Reference::new(reference, &unshadowed, &unshadowed, None).unwrap();
        // Columns 1–4 are 1/5 … 4/5 lit; column 0 is in umbra (0%) and
        // columns 5 on are fully lit.
        for y in 0..4 {
            for x in 0..10 {
                let expected = (1..=4).contains(&x);
                assert_eq!(
                    measure.is_penumbra_pixel((y * 10 + x) as usize),
                    expected,
                    "{x}"
                );
            }
        }
        assert_eq!(measure.census.penumbra_pixels, 16);
        assert!(is_penumbra(0.5, 1.0));
        assert!(!is_penumbra(0.01, 1.0) && !is_penumbra(0.99, 1.0));
    }

    #[test]
    fn masked_edge_and_dark_pixels_are_left_out() {
        let (reference, unshadowed) = scene();
        let mut area = unshadowed.clone();
        area.pixels[3] *= 1.5; // an edge: centre and area disagree
        let mut dark = unshadowed.clone();
        dark.pixels[9] = Vec4::ZERO; // no light reaches it
        let mask = Mask {
            width: 10,
            height: 4,
            left_out: (0..40).map(|i| i == 18).collect(),
        };
        let measure = Reference::new(reference.clone(), &dark, &area, Some(&mask)).unwrap();
        let census = measure.census;
        assert_eq!(
            (census.lit_pixels, census.edge_pixels, census.masked_pixels),
            (37, 1, 1)
        );
        let mut frame = reference.clone();
        for i in [3, 9, 18] {
            frame.pixels[i] += Vec4::splat(10.0);
        }
        assert_eq!(measure.errors(&frame).unwrap().max_error, 0.0);
    }

    #[test]
    fn a_census_without_lit_or_penumbra_pixels_is_nothing_to_measure() {
        let (reference, unshadowed) = scene();
        let measure = Reference::new(reference.clone(), &unshadowed, &unshadowed, None).unwrap();
        assert_eq!(measure.census.nothing_to_measure(), None);
        // A fully lit frame: no penumbra.
        let lit = Reference::new(unshadowed.clone(), &unshadowed, &unshadowed, None).unwrap();
        let fault = lit.census.nothing_to_measure().unwrap();
        assert!(
            fault.contains("no penumbra pixel") && fault.contains("40 lit"),
            "{fault}"
        );
        // A mask over everything: nothing lit.
        let all = Mask {
            width: 10,
            height: 4,
            left_out: vec![true; 40],
        };
        let masked = Reference::new(reference, &unshadowed, &unshadowed, Some(&all)).unwrap();
        let fault = masked.census.nothing_to_measure().unwrap();
        assert!(
            fault.contains("no lit pixel") && fault.contains("40 left out by the mask"),
            "{fault}"
        );
    }

    #[test]
    fn images_of_another_size_are_refused() {
        let (reference, unshadowed) = scene();
        let small = grey(5, 4, |_, _| 1.0);
        let error = Reference::new(reference.clone(), &small, &unshadowed, None).unwrap_err();
        assert_eq!((error.found_width, error.width), (5, 10));
        let measure = Reference::new(reference, &unshadowed, &unshadowed, None).unwrap();
        assert!(measure.errors(&small).is_err());
    }
}
