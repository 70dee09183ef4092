//! How a disk cache file (`super::cache`) writes the bricks of a section:
//! compactly, since a fly-through's file holds millions of them.
//!
//! On the 64-lamp city's 1080p fly-through (frames 0–2; 2.56 M bricks in
//! 64 sections) most valid words are neither empty nor full, since the
//! nodes demanded lie in shells along surfaces, but 95% of those equal the
//! same word of the same brick in the section before (a node is demanded
//! for every light that reaches it), and visible words are mostly empty or
//! equal to their valid word. So each word is a 2-bit tag ([`Word`]), and
//! only a literal takes its 8 bytes: a valid word's reference is the same
//! brick's word in the previous section (zero where that section lacks the
//! brick), a visible word's is its own valid word. Coordinates are deltas
//! from the previous brick's (bricks come in ascending order), as zigzag
//! LEB128 varints. The file shrank from 358 MB to 25 MB (BENCHMARKS.md,
//! "The disk cache's size").
//!
//! ```text
//! brick  Δx · Δy · Δz (zigzag varints; from (0, 0, 0) for the first)
//!        · tags u32 (word w's in bits 2w, 2w + 1; valid words 0–7, then
//!          visible words 0–7) · each literal word, u64, in that order
//! ```

use std::collections::BTreeMap;
use std::iter::Peekable;

use super::lattice::MAX_NODE_COORDINATE;
use super::masks::{BrickLightBits, BRICK_WORDS};

/// One section's bits by brick coordinates.
pub type Bricks = BTreeMap<[i32; 3], BrickLightBits>;

/// Brick coordinates beyond this cannot come from a lattice that
/// `Lattice::covers` the scene; a file holding them is not ours.
const MAX_BRICK_COORDINATE: i32 = (MAX_NODE_COORDINATE as i32) / 8 + 1;
/// The fewest bytes a brick takes: one per coordinate, and its tags.
const MIN_BRICK_BYTES: usize = 3 + 4;
/// Words per brick: valid, then visible.
const WORDS: usize = 2 * BRICK_WORDS;

/// What a word's tag says it is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Word {
    Zero = 0,
    Ones = 1,
    /// Equal to its reference.
    Reference = 2,
    /// The next 8 bytes.
    Literal = 3,
}

impl Word {
    fn of(word: u64, reference: u64) -> Word {
        match word {
            0 => Word::Zero,
            u64::MAX => Word::Ones,
            _ if word == reference => Word::Reference,
            _ => Word::Literal,
        }
    }
}

/// Why a section's bytes were refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Malformed(pub &'static str);

/// Appends `bricks`, in ascending order, each valid word against the same
/// brick's in `previous` (the section written before, if any).
pub fn encode(bricks: &Bricks, previous: Option<&Bricks>, out: &mut Vec<u8>) {
    let mut references = References::new(previous);
    let mut last = [0; 3];
    for (brick, bits) in bricks {
        for (&coordinate, &before) in brick.iter().zip(&last) {
            put_varint(out, zigzag(coordinate.wrapping_sub(before)));
        }
        last = *brick;
        let valid_references = references.valid(brick);
        let words = bits.valid.iter().chain(&bits.visible);
        let word_references = valid_references.iter().chain(&bits.valid);
        let mut tags = 0u32;
        let tags_at = out.len();
        out.extend_from_slice(&tags.to_le_bytes());
        for (index, (&word, &reference)) in words.zip(word_references).enumerate() {
            let tag = Word::of(word, reference);
            tags |= (tag as u32) << (2 * index);
            if tag == Word::Literal {
                out.extend_from_slice(&word.to_le_bytes());
            }
        }
        out[tags_at..tags_at + 4].copy_from_slice(&tags.to_le_bytes());
    }
}

/// Reads `count` bricks written by [`encode`] against `previous`.
pub fn decode(
    reader: &mut Reader,
    count: usize,
    previous: Option<&Bricks>,
) -> Result<Bricks, Malformed> {
    if count.saturating_mul(MIN_BRICK_BYTES) > reader.remaining() {
        return Err(Malformed("more bricks than bytes"));
    }
    let mut references = References::new(previous);
    // Collected in order, then built at once: a map made from a sorted
    // list is built in one pass, where inserting searches for each.
    let mut bricks = Vec::with_capacity(count);
    let mut last: Option<[i32; 3]> = None;
    for _ in 0..count {
        let mut brick = [0; 3];
        let base = last.unwrap_or_default();
        for (coordinate, before) in brick.iter_mut().zip(base) {
            *coordinate = before
                .checked_add(unzigzag(reader.varint()?))
                .filter(|c| c.abs() <= MAX_BRICK_COORDINATE)
                .ok_or(Malformed("brick outside any lattice"))?;
        }
        if last.is_some_and(|last| last >= brick) {
            return Err(Malformed("bricks out of order"));
        }
        last = Some(brick);
        let valid_references = references.valid(&brick);
        let tags = reader.u32()?;
        let mut words = [0u64; WORDS];
        for index in 0..WORDS {
            let reference = match index < BRICK_WORDS {
                true => valid_references[index],
                false => words[index - BRICK_WORDS],
            };
            words[index] = match tags >> (2 * index) & 0b11 {
                0 => 0,
                1 => u64::MAX,
                2 => reference,
                _ => reader.u64()?,
            };
        }
        let mut bits = BrickLightBits::default();
        bits.valid.copy_from_slice(&words[..BRICK_WORDS]);
        bits.visible.copy_from_slice(&words[BRICK_WORDS..]);
        if (bits.visible.iter().zip(&bits.valid)).any(|(visible, valid)| visible & !valid != 0) {
            return Err(Malformed("a visible bit that is not valid"));
        }
        bricks.push((brick, bits));
    }
    Ok(Bricks::from_iter(bricks))
}

/// The previous section's valid words, brick by brick in ascending order.
struct References<'a> {
    bricks: Option<Peekable<std::collections::btree_map::Iter<'a, [i32; 3], BrickLightBits>>>,
}

impl<'a> References<'a> {
    fn new(previous: Option<&'a Bricks>) -> References<'a> {
        References {
            bricks: previous.map(|bricks| bricks.iter().peekable()),
        }
    }

    /// The valid words of `brick` in the previous section, zero where it
    /// has none; `brick` must ascend from call to call.
    fn valid(&mut self, brick: &[i32; 3]) -> [u64; BRICK_WORDS] {
        let Some(bricks) = &mut self.bricks else {
            return [0; BRICK_WORDS];
        };
        while bricks.next_if(|(at, _)| *at < brick).is_some() {}
        match bricks.peek() {
            Some((at, bits)) if *at == brick => bits.valid,
            _ => [0; BRICK_WORDS],
        }
    }
}

fn zigzag(value: i32) -> u32 {
    ((value << 1) ^ (value >> 31)) as u32
}

fn unzigzag(value: u32) -> i32 {
    (value >> 1) as i32 ^ -((value & 1) as i32)
}

/// LEB128: seven bits a byte, low first, the high bit set on all but the
/// last.
fn put_varint(out: &mut Vec<u8>, mut value: u32) {
    while value >= 0x80 {
        out.push(value as u8 | 0x80);
        value >>= 7;
    }
    out.push(value as u8);
}

/// Reads little-endian values off a byte slice, failing on truncation.
pub struct Reader<'a> {
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Reader<'a> {
    pub fn new(bytes: &'a [u8]) -> Reader<'a> {
        Reader { bytes, at: 0 }
    }

    pub fn take(&mut self, n: usize) -> Result<&'a [u8], Malformed> {
        let end = self
            .at
            .checked_add(n)
            .filter(|&end| end <= self.bytes.len())
            .ok_or(Malformed("ends in the middle of a value"))?;
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    pub fn array<const N: usize>(&mut self) -> Result<[u8; N], Malformed> {
        let mut array = [0; N];
        array.copy_from_slice(self.take(N)?);
        Ok(array)
    }

    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.at
    }

    pub fn u8(&mut self) -> Result<u8, Malformed> {
        Ok(self.take(1)?[0])
    }

    pub fn u32(&mut self) -> Result<u32, Malformed> {
        Ok(u32::from_le_bytes(self.array()?))
    }

    pub fn u64(&mut self) -> Result<u64, Malformed> {
        Ok(u64::from_le_bytes(self.array()?))
    }

    /// A varint of at most five bytes whose value fits 32 bits.
    fn varint(&mut self) -> Result<u32, Malformed> {
        let mut value = 0u32;
        for byte_index in 0..5 {
            let byte = self.u8()?;
            let bits = u32::from(byte & 0x7f);
            if byte_index == 4 && bits > 0x0f {
                return Err(Malformed("a varint beyond 32 bits"));
            }
            value |= bits << (7 * byte_index);
            if byte & 0x80 == 0 {
                return Ok(value);
            }
        }
        Err(Malformed("a varint beyond 32 bits"))
    }
}

#[cfg(test)]
mod tests {
    use proptest::prelude::*;

    use super::*;

    #[test]
    fn zigzag_varints_round_trip_at_the_extremes() {
        for value in [0, 1, -1, 63, -64, 64, i32::MAX, i32::MIN] {
            let mut bytes = Vec::new();
            put_varint(&mut bytes, zigzag(value));
            assert!(bytes.len() <= 5);
            assert_eq!(unzigzag(Reader::new(&bytes).varint().unwrap()), value);
        }
        let too_long = [0xff, 0xff, 0xff, 0xff, 0x1f];
        assert!(Reader::new(&too_long).varint().is_err());
    }

    /// A word that is mostly one of the tags' cases.
    fn word() -> impl Strategy<Value = u64> {
        prop_oneof![Just(0), Just(u64::MAX), any::<u64>(), Just(0x00ff_0f00)]
    }

    /// Sections of bricks near each other, visible bits within valid ones;
    /// later sections often repeat an earlier one's valid words.
    fn sections() -> impl Strategy<Value = Vec<Bricks>> {
        let brick = (
            prop::array::uniform3(-3i32..3),
            prop::array::uniform8(word()),
            prop::array::uniform8(word()),
            any::<bool>(),
        );
        let far = prop::array::uniform3(-MAX_BRICK_COORDINATE..=MAX_BRICK_COORDINATE);
        prop::collection::vec((prop::collection::vec(brick, 0..12), far), 1..5).prop_map(
            |sections| {
                let mut out: Vec<Bricks> = Vec::new();
                for (bricks, far) in sections {
                    let mut section = Bricks::new();
                    for (brick, valid, visible, copy) in bricks {
                        let mut bits = BrickLightBits { valid, visible };
                        if let Some(before) = out.last().and_then(|last| last.get(&brick)) {
                            if copy {
                                bits.valid = before.valid;
                            }
                        }
                        for (visible, valid) in bits.visible.iter_mut().zip(&bits.valid) {
                            *visible &= valid;
                        }
                        section.insert(brick, bits);
                    }
                    section.insert(far, BrickLightBits::default());
                    out.push(section);
                }
                out
            },
        )
    }

    fn encode_all(sections: &[Bricks]) -> Vec<u8> {
        let mut bytes = Vec::new();
        for (index, section) in sections.iter().enumerate() {
            let previous = index.checked_sub(1).map(|before| &sections[before]);
            encode(section, previous, &mut bytes);
        }
        bytes
    }

    proptest! {
        /// Every section reads back as it was written, each against the
        /// one before, including bricks at the lattice's far corners.
        #[test]
        fn sections_round_trip(sections in sections()) {
            let bytes = encode_all(&sections);
            let mut reader = Reader::new(&bytes);
            let mut decoded: Vec<Bricks> = Vec::new();
            for section in &sections {
                let bricks = decode(&mut reader, section.len(), decoded.last()).unwrap();
                decoded.push(bricks);
            }
            prop_assert_eq!(reader.remaining(), 0);
            prop_assert_eq!(decoded, sections);
        }

        /// Damaged bytes give bricks or an error, never a panic, and never
        /// a visible bit that is not valid.
        #[test]
        fn damaged_bytes_never_panic(
            sections in sections(),
            flips in prop::collection::vec((any::<prop::sample::Index>(), 1u8..), 1..4),
        ) {
            let mut bytes = encode_all(&sections);
            for (at, mask) in flips {
                let at = at.index(bytes.len());
                bytes[at] ^= mask;
            }
            let mut reader = Reader::new(&bytes);
            let mut previous: Option<Bricks> = None;
            for section in &sections {
                match decode(&mut reader, section.len(), previous.as_ref()) {
                    Ok(bricks) => {
                        for bits in bricks.values() {
                            let mut within = bits.visible.iter().zip(&bits.valid);
                            prop_assert!(within.all(|(v, ok)| v & !ok == 0));
                        }
                        previous = Some(bricks);
                    }
                    Err(_) => break,
                }
            }
        }
    }

    #[test]
    fn words_equal_to_their_reference_take_no_bytes() {
        let bits = BrickLightBits {
            valid: [0x0f0f; BRICK_WORDS],
            visible: [0x0f0f; BRICK_WORDS],
        };
        let first = Bricks::from([([1, 2, 3], bits)]);
        let mut bytes = Vec::new();
        encode(&first, None, &mut bytes);
        assert_eq!(bytes.len(), 3 + 4 + 8 * 8, "the valid words are literal");
        bytes.clear();
        encode(&first, Some(&first), &mut bytes);
        assert_eq!(bytes.len(), 3 + 4, "every word is its reference");
    }
}
