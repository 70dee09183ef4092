//! Node masks: per lattice node, one visibility bit and one validity bit per
//! light, `ceil(nL / 64)` words of each, kept in sparse 8×8×8 bricks in a
//! hash map keyed by brick coordinates. Only nodes some shading point asked
//! for ever get a brick, so the lattice has no extent and no up-front cost.
//!
//! The mask-fill stage is the only writer; the other stages read the store
//! through shared references, so the shading loop takes no locks.

use glam::IVec3;
use rustc_hash::FxHashMap;

/// Nodes along each edge of a brick.
const BRICK_EDGE: i32 = 8;
/// Nodes in a brick; a node's slot in its brick is in `0..BRICK_NODES`.
pub const BRICK_NODES: usize = (BRICK_EDGE * BRICK_EDGE * BRICK_EDGE) as usize;

#[derive(Clone, Debug, Default)]
pub struct MaskStore {
    /// Words of visibility (and as many of validity) bits per node.
    words: usize,
    bricks: FxHashMap<IVec3, Box<[u64]>>,
    /// Nodes with at least one valid bit, kept as bits are set.
    nodes: usize,
}

/// One node's bits: `visible[i / 64] >> (i % 64)` is V(i, x), meaningful
/// only where the same bit of `valid` is set.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeMask<'a> {
    pub visible: &'a [u64],
    pub valid: &'a [u64],
}

impl NodeMask<'_> {
    /// V(light, x) if it has been computed.
    pub fn get(&self, light: usize) -> Option<bool> {
        let (word, bit) = (light / 64, light % 64);
        (self.valid[word] >> bit & 1 == 1).then_some(self.visible[word] >> bit & 1 == 1)
    }
}

impl MaskStore {
    pub fn new(lights: usize) -> MaskStore {
        MaskStore {
            words: lights.div_ceil(64).max(1),
            bricks: FxHashMap::default(),
            nodes: 0,
        }
    }

    /// Words of visibility bits per node: `ceil(nL / 64)`.
    pub fn words(&self) -> usize {
        self.words
    }

    /// The node's mask, or None when no bit of it was ever computed.
    pub fn node(&self, node: IVec3) -> Option<NodeMask<'_>> {
        let (brick, slot) = split(node);
        Some(self.slot_mask(self.bricks.get(&brick)?, slot))
    }

    /// A brick's bits (per slot: `words` visibility words, then `words`
    /// validity words), or None when no node in it was ever computed.
    pub fn brick(&self, brick: IVec3) -> Option<&[u64]> {
        self.bricks.get(&brick).map(|bits| &bits[..])
    }

    /// The mask of `slot` within a brick's bits.
    pub fn slot_mask<'a>(&self, bits: &'a [u64], slot: usize) -> NodeMask<'a> {
        let start = slot * 2 * self.words;
        NodeMask {
            visible: &bits[start..start + self.words],
            valid: &bits[start + self.words..start + 2 * self.words],
        }
    }

    /// V(light, node) if it has been computed.
    pub fn get(&self, node: IVec3, light: usize) -> Option<bool> {
        self.node(node)?.get(light)
    }

    /// Records V(light, node) = `visible`.
    pub fn set(&mut self, node: IVec3, light: usize, visible: bool) {
        let bit = 1u64 << (light % 64);
        self.set_word(
            node,
            (light / 64) as u32,
            bit,
            if visible { bit } else { 0 },
        );
    }

    /// Records the lights of word `word` whose bits are set in `computed`:
    /// visible where `visible` has the bit, occluded elsewhere.
    pub fn set_word(&mut self, node: IVec3, word: u32, computed: u64, visible: u64) {
        let (brick, slot) = split(node);
        let words = self.words;
        let mut computed_words = vec![0; words];
        let mut visible_words = vec![0; words];
        computed_words[word as usize] = computed;
        visible_words[word as usize] = visible;
        self.merge_slot(brick, slot, &computed_words, &visible_words);
    }

    /// Records a whole brick's computed bits: for each slot, `words` words
    /// of `computed` say which lights were computed and `visible` their
    /// values (layout `slot * words + word`).
    pub fn merge_brick(&mut self, brick: IVec3, computed: &[u64], visible: &[u64]) {
        let words = self.words;
        for slot in 0..BRICK_NODES {
            let range = slot * words..(slot + 1) * words;
            if computed[range.clone()].iter().any(|&word| word != 0) {
                self.merge_slot(brick, slot, &computed[range.clone()], &visible[range]);
            }
        }
    }

    fn merge_slot(&mut self, brick: IVec3, slot: usize, computed: &[u64], visible: &[u64]) {
        let words = self.words;
        let bits = self
            .bricks
            .entry(brick)
            .or_insert_with(|| vec![0; BRICK_NODES * 2 * words].into_boxed_slice());
        let node_bits = &mut bits[slot * 2 * words..(slot + 1) * 2 * words];
        let was_empty = node_bits[words..].iter().all(|&valid| valid == 0);
        for word in 0..words {
            node_bits[word] =
                (node_bits[word] & !computed[word]) | (visible[word] & computed[word]);
            node_bits[words + word] |= computed[word];
        }
        if was_empty && computed.iter().any(|&word| word != 0) {
            self.nodes += 1;
        }
    }

    pub fn has_brick(&self, brick: IVec3) -> bool {
        self.bricks.contains_key(&brick)
    }

    pub fn brick_count(&self) -> usize {
        self.bricks.len()
    }

    /// Heap bytes one brick takes, for memory budgets.
    pub fn brick_bytes(lights: usize) -> usize {
        BRICK_NODES * 2 * lights.div_ceil(64).max(1) * std::mem::size_of::<u64>()
    }

    /// Nodes with at least one valid bit.
    pub fn nodes_cached(&self) -> usize {
        self.nodes
    }
}

/// The brick holding `node` and the node's slot in it.
pub fn split(node: IVec3) -> (IVec3, usize) {
    let brick = node.div_euclid(IVec3::splat(BRICK_EDGE));
    let local = node.rem_euclid(IVec3::splat(BRICK_EDGE));
    let slot = ((local.z * BRICK_EDGE + local.y) * BRICK_EDGE + local.x) as usize;
    (brick, slot)
}

/// The node in `slot` of `brick` (the inverse of [`split`]).
pub fn join(brick: IVec3, slot: usize) -> IVec3 {
    let edge = BRICK_EDGE as usize;
    let local = IVec3::new(
        (slot % edge) as i32,
        (slot / edge % edge) as i32,
        (slot / (edge * edge)) as i32,
    );
    brick * BRICK_EDGE + local
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_are_invalid_until_set_and_then_hold_their_value() {
        let mut store = MaskStore::new(130);
        let node = IVec3::new(-1, 9, -17);
        assert_eq!(store.get(node, 0), None);
        store.set(node, 129, true);
        store.set(node, 64, false);
        assert_eq!(store.get(node, 129), Some(true));
        assert_eq!(store.get(node, 64), Some(false));
        assert_eq!(store.get(node, 0), None);
        store.set(node, 129, false);
        assert_eq!(store.get(node, 129), Some(false));
        // A neighbour in the same brick is untouched.
        assert_eq!(store.get(node + IVec3::X, 129), None);
        assert_eq!(store.nodes_cached(), 1);
    }

    #[test]
    fn join_inverts_split() {
        for node in [IVec3::new(-9, 0, 17), IVec3::new(7, -8, -1), IVec3::ZERO] {
            let (brick, slot) = split(node);
            assert_eq!(join(brick, slot), node);
        }
    }

    #[test]
    fn negative_coordinates_map_to_distinct_slots() {
        let mut store = MaskStore::new(1);
        let nodes: Vec<IVec3> = (-9..9).map(|i| IVec3::new(i, -i, i * 3)).collect();
        for (index, node) in nodes.iter().enumerate() {
            store.set(*node, 0, index % 2 == 0);
        }
        for (index, node) in nodes.iter().enumerate() {
            assert_eq!(store.get(*node, 0), Some(index % 2 == 0), "{node}");
        }
        assert_eq!(store.nodes_cached(), nodes.len());
    }
}
