//! What both backends do the same way around their stages: splitting the
//! image into bands of whole tile rows, so memory stays bounded at any
//! resolution and sample count; and the resolve stage that turns a band's
//! shaded points into pixels, which the GPU's film (`accumulate.wgsl`,
//! `resolve.wgsl`) repeats sum for sum.

use std::ops::Range;

use glam::{Vec3, Vec4};

use crate::render::surface::ShadingPoint;
use crate::render::FrameJob;

/// Square tiles of the primary stage, in pixels.
pub const TILE: u32 = 16;
/// Samples per band: bounds the shading-point buffers to a few hundred MB.
const SAMPLES_PER_BAND: u64 = 1 << 20;

/// Rows of the image split into bands of whole tile rows.
pub fn bands(job: &FrameJob) -> impl Iterator<Item = Range<u32>> {
    let samples_per_row = job.width as u64 * job.spp as u64;
    let tile_rows = (SAMPLES_PER_BAND / (samples_per_row * TILE as u64)).max(1) as u32;
    let band_height = tile_rows * TILE;
    let height = job.height;
    (0..height.div_ceil(band_height))
        .map(move |band| band * band_height..((band + 1) * band_height).min(height))
}

/// The last stage: each sample's radiance is the sum of its points'
/// `shaded` values in point order (or the frame's background where its
/// camera ray met nothing), each pixel the mean of its samples, with
/// coverage (the share of samples whose camera ray hit something) as
/// alpha, or 1 behind a background. `primary` is how many of `points` are
/// camera hits (they come first).
pub fn resolve(
    job: &FrameJob,
    band_samples: usize,
    points: &[ShadingPoint],
    primary: usize,
    shaded: &[Vec3],
) -> Vec<Vec4> {
    let mut covered = vec![false; band_samples];
    for point in &points[..primary] {
        covered[point.sample as usize] = true;
    }
    let mut radiance = vec![Vec3::ZERO; band_samples];
    for (point, value) in points.iter().zip(shaded) {
        radiance[point.sample as usize] += *value;
    }
    let spp = job.spp as usize;
    radiance
        .chunks(spp)
        .zip(covered.chunks(spp))
        .map(|(samples, hits)| {
            let environment = &job.environment;
            let colour = (samples.iter().zip(hits))
                .map(|(&sent, &hit)| environment.sample_radiance(sent, hit))
                .sum::<Vec3>()
                / spp as f32;
            let coverage = hits.iter().filter(|&&hit| hit).count() as f32 / spp as f32;
            colour.extend(environment.alpha(coverage))
        })
        .collect()
}
