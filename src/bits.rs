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

/// For each bit set in some of `words`, lowest first, the indices of the
/// words that hold it, lowest first: a brick's nodes grouped by light,
/// in one pass over the words instead of one per light.
pub fn holders_by_bit(words: &[u64]) -> Vec<(usize, Vec<usize>)> {
    let mut holders: [Vec<usize>; 64] = std::array::from_fn(|_| Vec::new());
    for (index, &word) in words.iter().enumerate() {
        for bit in set_bits(word) {
            holders[bit].push(index);
        }
    }
    (holders.into_iter().enumerate())
        .filter(|(_, indices)| !indices.is_empty())
        .collect()
}

/// Transposes a 64×64 matrix of bits in place: bit j of word i moves to
/// bit i of word j. A brick's nodes hold their lights' bits a word per
/// node, the disk cache a word per light over 64 nodes; this turns one
/// into the other in six rounds of block swaps instead of a step per bit.
pub fn transpose64(m: &mut [u64; 64]) {
    let mut width = 32;
    // The low `width` columns of each block of 2·width.
    let mut low_columns: u64 = 0x0000_0000_ffff_ffff;
    while width != 0 {
        for block in (0..64).step_by(2 * width) {
            for row in block..block + width {
                // Row `row`'s high columns swap with row `row + width`'s
                // low ones.
                let (upper, lower) = (m[row], m[row + width]);
                let swapped = ((upper >> width) ^ lower) & low_columns;
                m[row] = upper ^ (swapped << width);
                m[row + width] = lower ^ swapped;
            }
        }
        width /= 2;
        low_columns ^= low_columns << width;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn transposes_bit_matrices() {
        // Words of a fixed pseudo-random sequence, and the corners.
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut m = [0u64; 64];
        for word in &mut m {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            *word = state;
        }
        m[0] |= 1;
        m[63] |= 1 << 63;
        m[1] &= !(1 << 62);
        let original = m;
        transpose64(&mut m);
        for (i, &row) in original.iter().enumerate() {
            for (j, &column) in m.iter().enumerate() {
                assert_eq!(row >> j & 1, column >> i & 1, "bit {j} of word {i}");
            }
        }
        transpose64(&mut m);
        assert_eq!(m, original, "twice is the identity");
    }

    #[test]
    fn groups_the_holders_of_each_bit_in_order() {
        assert!(holders_by_bit(&[0, 0]).is_empty());
        let words = [0b101, 0, 1 << 63 | 0b100, 0b1];
        assert_eq!(
            holders_by_bit(&words),
            [(0, vec![0, 3]), (2, vec![0, 2]), (63, vec![2])]
        );
    }

    #[test]
    fn walks_the_set_bits_in_order() {
        assert_eq!(set_bits(0).count(), 0);
        assert_eq!(set_bits(0b1010_0001).collect::<Vec<_>>(), [0, 5, 7]);
        assert_eq!(set_bits(1 << 63).collect::<Vec<_>>(), [63]);
        assert_eq!(set_bits(u64::MAX).count(), 64);
    }
}
