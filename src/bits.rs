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

#[cfg(test)]
mod tests {
    use super::*;

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
