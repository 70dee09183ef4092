//! Where in a pixel each sample falls: the centre for one sample, jittered
//! strata for more; and, for `--method area`, which point of a lamp each
//! sample sees. Random numbers come from a generator seeded by the
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

/// The unit-square point from which pixel sample `sample` (its index in the
/// whole image, as in [`film_position`]) samples light `light` at Whitted
/// depth `depth`.
///
/// The pixel's `spp` samples are stratified over the square like its film
/// positions (jittered √spp × √spp strata, uniform leftovers), so the
/// lamp's estimate converges as spp grows. Which sample gets which stratum
/// is shuffled per (pixel, light, depth): stratum s for sample s would tie
/// a sample's lamp point to its film position and bias each pixel towards
/// the diagonal of (film × lamp).
pub fn lamp_sample(sample: u64, spp: u32, light: u32, depth: u32) -> Vec2 {
    let pixel = sample / spp as u64;
    let within = (sample % spp as u64) as u32;
    let stream = ((light as u64) << 32) | depth as u64;
    let shuffle = mix(mix(pixel) ^ stream) as u32;
    let mut rng = Pcg32::seed_from_u64(mix(mix(sample ^ LAMP_SEED) ^ stream));
    let jitter = Vec2::new(unit_float(&mut rng), unit_float(&mut rng));
    let strata = (spp as f32).sqrt().floor() as u32;
    let stratum = permute(within, spp, shuffle);
    if stratum < strata * strata {
        let cell = Vec2::new((stratum % strata) as f32, (stratum / strata) as f32);
        (cell + jitter) / strata as f32
    } else {
        jitter
    }
}

/// Keeps the lamp's generators apart from the film's, which are seeded by
/// the bare sample index.
const LAMP_SEED: u64 = 0x6c61_6d70_5f73_6d70;

/// SplitMix64's finaliser: a bijective 64-bit hash.
fn mix(mut x: u64) -> u64 {
    x = x.wrapping_add(0x9e37_79b9_7f4a_7c15);
    x = (x ^ (x >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    x = (x ^ (x >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    x ^ (x >> 31)
}

/// Element `i` of a pseudo-random permutation of `0..len` chosen by `seed`,
/// in constant expected time (Kensler, "Correlated Multi-Jittered
/// Sampling", 2013: a hash that is a bijection on the next power of two,
/// walked until it lands below `len`).
fn permute(mut i: u32, len: u32, seed: u32) -> u32 {
    let mut w = len.saturating_sub(1);
    w |= w >> 1;
    w |= w >> 2;
    w |= w >> 4;
    w |= w >> 8;
    w |= w >> 16;
    loop {
        i ^= seed;
        i = i.wrapping_mul(0xe170_893d);
        i ^= seed >> 16;
        i ^= (i & w) >> 4;
        i ^= seed >> 8;
        i = i.wrapping_mul(0x0929_eb3f);
        i ^= seed >> 23;
        i ^= (i & w) >> 1;
        i = i.wrapping_mul(1 | seed >> 27);
        i = i.wrapping_mul(0x6935_fa69);
        i ^= (i & w) >> 11;
        i = i.wrapping_mul(0x74dc_b303);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0x9e50_1cc3);
        i ^= (i & w) >> 2;
        i = i.wrapping_mul(0xc860_a3df);
        i &= w;
        i ^= i >> 5;
        if i < len {
            return (i + seed % len) % len;
        }
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
    fn permute_is_a_permutation() {
        for len in [1, 2, 3, 7, 16, 17, 100, 1024] {
            for seed in [0, 1, 0xdead_beef, u32::MAX] {
                let mut seen = vec![false; len as usize];
                for i in 0..len {
                    let p = permute(i, len, seed) as usize;
                    assert!(!seen[p], "len {len} seed {seed}: {p} twice");
                    seen[p] = true;
                }
            }
        }
    }

    #[test]
    fn a_pixels_lamp_samples_fill_every_stratum_once() {
        let spp = 16;
        for (pixel, light, depth) in [(0u64, 0, 0), (77, 0, 0), (77, 3, 0), (77, 3, 2)] {
            let mut seen = [false; 16];
            for s in 0..spp {
                let u = lamp_sample(pixel * spp as u64 + s as u64, spp, light, depth);
                assert!(u.min_element() >= 0.0 && u.max_element() < 1.0);
                let cell = (u.y * 4.0) as usize * 4 + (u.x * 4.0) as usize;
                assert!(!seen[cell], "{pixel} {light} {depth}: cell {cell} twice");
                seen[cell] = true;
            }
        }
    }

    #[test]
    fn lamp_samples_differ_between_lights_and_depths() {
        let a = lamp_sample(1234, 4, 0, 0);
        assert_eq!(a, lamp_sample(1234, 4, 0, 0));
        assert_ne!(a, lamp_sample(1234, 4, 1, 0));
        assert_ne!(a, lamp_sample(1234, 4, 0, 1));
        assert_ne!(a, lamp_sample(1235, 4, 0, 0));
    }

    #[test]
    fn positions_are_a_pure_function_of_pixel_and_sample() {
        let a = film_position(UVec2::new(5, 5), 64, 3, 5);
        let b = film_position(UVec2::new(5, 5), 64, 3, 5);
        assert_eq!(a, b);
        assert_ne!(a, film_position(UVec2::new(5, 6), 64, 3, 5));
    }
}
