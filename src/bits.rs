//! Bit words: light sets (bit i for light i, 64 per word) and SIMD lane
//! masks are walked one set bit at a time in the fill, invalidation,
//! half-ball and shading loops.

/// The indices of the set bits of `word`, lowest first.
#[inline]
pub fn set_bits(mut word: u64) -> impl Iterator<Item = usize> {
    std::iter::from_fn(move || {
        (word != 0).then(|| {
            let bit = word.trailing_zeros() as usize;
            word &= word - 1;
            bit
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn walks_the_set_bits_in_order() {
        assert_eq!(set_bits(0).count(), 0);
        assert_eq!(set_bits(0b1010_0001).collect::<Vec<_>>(), [0, 5, 7]);
        assert_eq!(set_bits(1 << 63).collect::<Vec<_>>(), [63]);
        assert_eq!(set_bits(u64::MAX).count(), 64);
    }
}
