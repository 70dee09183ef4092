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
const BRICK_NODES: usize = (BRICK_EDGE * BRICK_EDGE * BRICK_EDGE) as usize;

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

    /// The node's mask, or None when no bit of it was ever computed.
    pub fn node(&self, node: IVec3) -> Option<NodeMask<'_>> {
        let (brick, slot) = split(node);
        let bits = self.bricks.get(&brick)?;
        let start = slot * 2 * self.words;
        Some(NodeMask {
            visible: &bits[start..start + self.words],
            valid: &bits[start + self.words..start + 2 * self.words],
        })
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
        let bits = self
            .bricks
            .entry(brick)
            .or_insert_with(|| vec![0; BRICK_NODES * 2 * words].into_boxed_slice());
        let node_bits = &mut bits[slot * 2 * words..(slot + 1) * 2 * words];
        if computed != 0 && node_bits[words..].iter().all(|&valid| valid == 0) {
            self.nodes += 1;
        }
        let word = word as usize;
        node_bits[word] = (node_bits[word] & !computed) | (visible & computed);
        node_bits[words + word] |= computed;
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

    /// The brick holding `node`, for memory estimates before filling.
    pub fn brick_of(node: IVec3) -> IVec3 {
        split(node).0
    }
}

fn split(node: IVec3) -> (IVec3, usize) {
    let brick = node.div_euclid(IVec3::splat(BRICK_EDGE));
    let local = node.rem_euclid(IVec3::splat(BRICK_EDGE));
    let slot = ((local.z * BRICK_EDGE + local.y) * BRICK_EDGE + local.x) as usize;
    (brick, slot)
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
