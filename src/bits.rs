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
/// in one pass over the words instead of one per light. The indices are
/// counted per bit first and then placed in one list, so a brick's groups
/// cost one allocation, not a growing list per light (which the fill
/// paid in `realloc` on every brick).
pub fn holders_by_bit(words: &[u64]) -> HoldersByBit {
    let mut ends = [0; 64];
    for &word in words {
        for bit in set_bits(word) {
            ends[bit] += 1;
        }
    }
    let mut total = 0;
    for end in &mut ends {
        total += *end;
        *end = total;
    }
    // Each bit's indices fill its range from the back, so they come out
    // lowest first and the range's start is where its filling stops.
    let mut indices = vec![0; total];
    let mut starts = ends;
    for (index, &word) in words.iter().enumerate().rev() {
        for bit in set_bits(word) {
            starts[bit] -= 1;
            indices[starts[bit]] = index;
        }
    }
    HoldersByBit { ends, indices }
}

/// What [`holders_by_bit`] found: bit i's holders are
/// `indices[ends[i − 1]..ends[i]]`.
pub struct HoldersByBit {
    ends: [usize; 64],
    indices: Vec<usize>,
}

impl HoldersByBit {
    /// Each bit some word holds, lowest first, with its holders.
    pub fn iter(&self) -> impl Iterator<Item = (usize, &[usize])> {
        (0..64)
            .map(|bit| {
                let start = if bit == 0 { 0 } else { self.ends[bit - 1] };
                (bit, &self.indices[start..self.ends[bit]])
            })
            .filter(|(_, holders)| !holders.is_empty())
    }
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

    proptest::proptest! {
        /// Each bit's group is the words holding it, lowest first, and
        /// only bits some word holds have one: a scan per bit, over
        /// words as many as a brick's nodes and sparse or dense.
        #[test]
        fn holders_are_the_words_holding_each_bit(
            words in proptest::collection::vec(
                proptest::prop_oneof![proptest::num::u64::ANY, 0..4u64, proptest::strategy::Just(0)],
                0..600,
            ),
        ) {
            let holders = holders_by_bit(&words);
            let found: Vec<(usize, Vec<usize>)> =
                holders.iter().map(|(bit, group)| (bit, group.to_vec())).collect();
            let scanned: Vec<(usize, Vec<usize>)> = (0..64)
                .map(|bit| {
                    let held = (0..words.len()).filter(|&i| words[i] >> bit & 1 == 1);
                    (bit, held.collect::<Vec<usize>>())
                })
                .filter(|(_, group)| !group.is_empty())
                .collect();
            proptest::prop_assert_eq!(found, scanned);
        }
    }

    #[test]
    fn groups_the_holders_of_each_bit_in_order() {
        assert_eq!(holders_by_bit(&[0, 0]).iter().count(), 0);
        assert_eq!(holders_by_bit(&[]).iter().count(), 0);
        let words = [0b101, 0, 1 << 63 | 0b100, 0b1];
        let holders = holders_by_bit(&words);
        let groups: Vec<(usize, &[usize])> = holders.iter().collect();
        assert_eq!(groups, [(0, &[0, 3][..]), (2, &[0, 2]), (63, &[2])]);
        // Every word holding every bit: each bit's group is every index.
        let full = [u64::MAX; 5];
        let holders = holders_by_bit(&full);
        assert!((holders.iter()).all(|(_, group)| group == [0, 1, 2, 3, 4]));
        assert_eq!(holders.iter().count(), 64);
    }

    #[test]
    fn walks_the_set_bits_in_order() {
        assert_eq!(set_bits(0).count(), 0);
        assert_eq!(set_bits(0b1010_0001).collect::<Vec<_>>(), [0, 5, 7]);
        assert_eq!(set_bits(1 << 63).collect::<Vec<_>>(), [63]);
        assert_eq!(set_bits(u64::MAX).count(), 64);
    }
}
