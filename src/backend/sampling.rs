//! Where in a pixel each sample falls: the centre for one sample, jittered
//! strata for more. Random numbers come from a generator seeded by the
//! sample's index in the whole image, so the image does not depend on how
//! work is split across threads.

use glam::{UVec2, Vec2};
use rand_pcg::rand_core::{Rng, SeedableRng};
use rand_pcg::Pcg32;

/// Image-plane position of sample `sample` of `spp` in `pixel`.
pub fn film_position(pixel: UVec2, width: u32, sample: u32, spp: u32) -> Vec2 {
    let corner = pixel.as_vec2();
    if spp == 1 {
        return corner + Vec2::splat(0.5);
    }
    let index = (pixel.y as u64 * width as u64 + pixel.x as u64) * spp as u64 + sample as u64;
    let mut rng = Pcg32::seed_from_u64(index);
    let jitter = Vec2::new(unit_float(&mut rng), unit_float(&mut rng));
    let strata = (spp as f32).sqrt().floor() as u32;
    if sample < strata * strata {
        let stratum = Vec2::new((sample % strata) as f32, (sample / strata) as f32);
        corner + (stratum + jitter) / strata as f32
    } else {
        corner + jitter
    }
}

/// A float uniform in [0, 1) from the top 24 bits of a draw.
fn unit_float(rng: &mut Pcg32) -> f32 {
    (rng.next_u32() >> 8) as f32 * (1.0 / (1u32 << 24) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn one_sample_is_the_pixel_centre() {
        assert_eq!(
            film_position(UVec2::new(3, 4), 10, 0, 1),
            Vec2::new(3.5, 4.5)
        );
    }

    #[test]
    fn square_sample_counts_put_one_sample_in_each_stratum() {
        let spp = 9;
        let mut seen = [false; 9];
        for sample in 0..spp {
            let p = film_position(UVec2::new(7, 2), 10, sample, spp);
            let local = p - Vec2::new(7.0, 2.0);
            assert!(local.min_element() >= 0.0 && local.max_element() < 1.0);
            let cell = (local.y * 3.0) as usize * 3 + (local.x * 3.0) as usize;
            seen[cell] = true;
        }
        assert!(seen.iter().all(|&s| s));
    }

    #[test]
    fn positions_are_a_pure_function_of_pixel_and_sample() {
        let a = film_position(UVec2::new(5, 5), 64, 3, 5);
        let b = film_position(UVec2::new(5, 5), 64, 3, 5);
        assert_eq!(a, b);
        assert_ne!(a, film_position(UVec2::new(5, 6), 64, 3, 5));
    }
}
