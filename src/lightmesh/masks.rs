//! Node masks: per lattice node and light, visibility in two layers, as
//! ARCHITECTURE.md has it ("The light mesh"): a *static* layer (does the
//! segment from the node to the light miss the static geometry?) and a
//! *dynamic* layer (does a dynamic object block it?), each with its own
//! validity bits; the node sees the
//! light when the static bit is set and no dynamic object blocks it. Moving
//! objects invalidate only dynamic bits, so re-testing them costs short
//! traversals of the small dynamic structure; only a moved light touches the
//! static layer (which is what a disk cache can keep).
//!
//! Each layer holds `ceil(nL / 64)` words of bits and as many of validity per
//! node, in sparse 8×8×8 bricks in a hash map keyed by brick coordinates.
//! Only nodes some shading point asked for ever get a brick, so the lattice
//! has no extent and no up-front cost.
//!
//! The store is the [`LightMesh`](super::LightMesh)'s own field, so it is
//! written only through `&mut LightMesh`, by one stage at a time, never
//! while a point is shaded; shading reads through shared references and
//! takes no locks. Four stages write it:
//! - invalidation (`super::invalidate`, before a frame) only clears
//!   validity bits;
//! - the disk cache's import (`super::cache`, when the mesh is made) sets
//!   static bits and enclosure flags an earlier run computed;
//! - the fill sets the bits the frame demanded: on the CPU
//!   (`super::fill`), or for the GPU's fill (`super::segments`) in two
//!   steps, the bits its shafts and walls settle before the GPU traces
//!   the rest (with the bricks it will write made, [`MaskStore::hold`])
//!   and the GPU's answers when they come back;
//! - LMM1's enclosure stage (`super::enclosure`: the CPU's probes, or the
//!   GPU's merged when they come back) sets enclosure flags, never a
//!   visibility bit.
//!
//! A bit set by any of them has the value the fill would compute, which
//! is what keeps reuse exact. The GPU's mask pool mirrors the store; the
//! GPU's fill writes its bits there first, by the rule the store folds
//! them by (`super::segments::Segment::sees`), and the store takes the
//! same bits at the CPU's next wait, before anything reads it.

use glam::IVec3;
use rustc_hash::FxHashMap;

use crate::bits::{set_bits, transpose64};

/// Nodes along each edge of a brick.
pub const BRICK_EDGE: i32 = 8;
/// Nodes in a brick; a node's slot in its brick is in `0..BRICK_NODES`.
pub const BRICK_NODES: usize = (BRICK_EDGE * BRICK_EDGE * BRICK_EDGE) as usize;

#[derive(Debug)]
pub struct MaskStore {
    lights: usize,
    /// Words of visibility (and as many of validity) bits per node.
    words: usize,
    bricks: FxHashMap<IVec3, Brick>,
    /// Nodes with at least one valid bit, kept as bits are set.
    nodes: usize,
    /// Per light, the nodes whose bit of it is valid, kept as bits are
    /// set and cleared: a frame's statistics read them without passing
    /// over the whole store, which grows with every frame of a fly-through.
    known: KnownCounts,
    /// Static bits the fill set valid since the store was made (the disk
    /// cache's imports not counted): none, and the store holds nothing its
    /// cache file lacks.
    static_found: u64,
    /// Enclosure flags LMM1's probes settled since the store was made (the
    /// disk cache's imports not counted).
    enclosure_found: u64,
    /// Which store this is, and how many edits it has had: a copy of its
    /// bricks elsewhere (the GPU backend's pool) knows by these whether a
    /// brick it holds is still current, without comparing bits.
    id: u64,
    revision: u64,
}

/// A store's copies are stores of their own: their edits diverge.
impl Clone for MaskStore {
    fn clone(&self) -> MaskStore {
        MaskStore {
            lights: self.lights,
            words: self.words,
            bricks: self.bricks.clone(),
            nodes: self.nodes,
            static_found: self.static_found,
            enclosure_found: self.enclosure_found,
            known: self.known.clone(),
            id: next_store_id(),
            revision: self.revision,
        }
    }
}

fn next_store_id() -> u64 {
    use std::sync::atomic::{AtomicU64, Ordering};
    static NEXT_ID: AtomicU64 = AtomicU64::new(0);
    NEXT_ID.fetch_add(1, Ordering::Relaxed)
}

/// One brick's bits, and which lights have a valid dynamic bit in it.
#[derive(Clone, Debug)]
pub struct Brick {
    /// Per node slot, [`GROUPS`] groups of `words` words.
    nodes: Box<[u64]>,
    /// Per word, the lights of which some node holds a valid dynamic bit:
    /// exactly those, kept as bits are set and cleared, so invalidation
    /// passes over a light's bricks that hold nothing of it without
    /// reading their 512 nodes.
    dynamic_lights: Box<[u64]>,
    /// Per node slot, one bit each: whether the node lies inside closed
    /// static geometry ([`super::enclosure`]), and whether that is known.
    /// It depends on the static geometry alone, so nothing invalidates it.
    enclosure: BrickEnclosure,
    /// The store's revision at the brick's last edit.
    revision: u64,
}

impl Brick {
    fn new(words: usize) -> Brick {
        Brick {
            nodes: vec![0; BRICK_NODES * GROUPS * words].into_boxed_slice(),
            dynamic_lights: vec![0; words].into_boxed_slice(),
            enclosure: BrickEnclosure::default(),
            revision: 0,
        }
    }
}

/// Which nodes of a brick lie inside closed geometry, one bit per slot
/// (bit `slot % 64` of word `slot / 64`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BrickEnclosure {
    pub known: [u64; BRICK_WORDS],
    /// Set only where `known` is.
    pub enclosed: [u64; BRICK_WORDS],
}

/// Groups of `words` words per node, in this order.
const STATIC_VISIBLE: usize = 0;
const STATIC_VALID: usize = 1;
const DYNAMIC_OCCLUDED: usize = 2;
const DYNAMIC_VALID: usize = 3;
const GROUPS: usize = 4;

/// One node's bits in both layers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct NodeMask<'a> {
    bits: &'a [u64],
    words: usize,
}

impl<'a> NodeMask<'a> {
    /// The mask of `slot` within a brick's bits.
    fn of_slot(bits: &'a [u64], slot: usize, words: usize) -> NodeMask<'a> {
        let stride = GROUPS * words;
        NodeMask {
            bits: &bits[slot * stride..(slot + 1) * stride],
            words,
        }
    }

    fn group(&self, group: usize, word: usize) -> u64 {
        self.bits[group * self.words + word]
    }

    /// Lights `64·word ..` that the node sees: static bit set, no dynamic
    /// blocker. Meaningful where [`NodeMask::valid`] has the bit.
    pub fn visible(&self, word: usize) -> u64 {
        self.group(STATIC_VISIBLE, word) & !self.group(DYNAMIC_OCCLUDED, word)
    }

    /// Lights whose visibility is known: the static bit is valid, and the
    /// dynamic bit too unless the static layer already blocks the light.
    pub fn valid(&self, word: usize) -> u64 {
        let static_visible = self.group(STATIC_VISIBLE, word);
        self.group(STATIC_VALID, word) & (!static_visible | self.group(DYNAMIC_VALID, word))
    }

    /// Static-layer bits: (visible, valid).
    pub fn static_layer(&self, word: usize) -> (u64, u64) {
        (
            self.group(STATIC_VISIBLE, word),
            self.group(STATIC_VALID, word),
        )
    }

    /// Dynamic-layer bits: (occluded, valid).
    pub fn dynamic_layer(&self, word: usize) -> (u64, u64) {
        (
            self.group(DYNAMIC_OCCLUDED, word),
            self.group(DYNAMIC_VALID, word),
        )
    }

    /// V(light, x) if it is known.
    pub fn get(&self, light: usize) -> Option<bool> {
        let (word, bit) = (light / 64, light % 64);
        (self.valid(word) >> bit & 1 == 1).then_some(self.visible(word) >> bit & 1 == 1)
    }
}

/// Bits computed for a node (or, laid out `slot * words + word`, a brick):
/// which lights were tested in each layer and what was found.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct LayerUpdate {
    pub static_computed: Vec<u64>,
    pub static_visible: Vec<u64>,
    pub dynamic_computed: Vec<u64>,
    pub dynamic_occluded: Vec<u64>,
}

impl LayerUpdate {
    pub fn zeroed(len: usize) -> LayerUpdate {
        LayerUpdate {
            static_computed: vec![0; len],
            static_visible: vec![0; len],
            dynamic_computed: vec![0; len],
            dynamic_occluded: vec![0; len],
        }
    }
}

/// Which slots of a brick an update holds bits for, in order, and in
/// which of its rows (a row is `words` words of each layer).
#[derive(Clone, Copy, Debug)]
pub enum UpdateRows<'a> {
    /// A whole brick's update: row `slot` is slot `slot`; these slots
    /// have bits.
    EverySlot(&'a [usize]),
    /// Row `i` is slot `slots[i]`.
    Named(&'a [usize]),
}

impl UpdateRows<'_> {
    fn slots(&self) -> &[usize] {
        match self {
            UpdateRows::EverySlot(slots) | UpdateRows::Named(slots) => slots,
        }
    }

    /// The row of the `index`-th slot, `slot`.
    fn row(&self, index: usize, slot: usize) -> usize {
        match self {
            UpdateRows::EverySlot(_) => slot,
            UpdateRows::Named(_) => index,
        }
    }
}

impl MaskStore {
    pub fn new(lights: usize) -> MaskStore {
        MaskStore {
            lights,
            words: lights.div_ceil(64).max(1),
            bricks: FxHashMap::default(),
            nodes: 0,
            known: KnownCounts::new(lights),
            static_found: 0,
            enclosure_found: 0,
            id: next_store_id(),
            revision: 0,
        }
    }

    /// This store's identity: no other store, copies included, has it.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// The store's revision at the last edit of `brick` (None when the
    /// store holds no such brick): it changes whenever any of the brick's
    /// bits or flags may have.
    pub fn brick_revision(&self, brick: IVec3) -> Option<u64> {
        self.bricks.get(&brick).map(|stored| stored.revision)
    }

    /// Makes `brick` if the store has none yet: its bits are about to be
    /// written where the store's copies are (the GPU's pool), and come
    /// back to it later.
    pub fn hold(&mut self, brick: IVec3) {
        if !self.bricks.contains_key(&brick) {
            self.edit(brick);
        }
    }

    /// `brick`, made if the store has none yet, stamped as edited now, and
    /// the counts of valid bits its edit must keep.
    fn edit(&mut self, brick: IVec3) -> (&mut Brick, &mut KnownCounts) {
        self.revision += 1;
        let words = self.words;
        let stored = self
            .bricks
            .entry(brick)
            .or_insert_with(|| Brick::new(words));
        stored.revision = self.revision;
        (stored, &mut self.known)
    }

    /// The lights nL whose bits the store holds.
    pub fn lights(&self) -> usize {
        self.lights
    }

    /// Words of visibility bits per node: `ceil(nL / 64)`.
    pub fn words(&self) -> usize {
        self.words
    }

    /// The node's mask, or None when no bit of it was ever computed.
    pub fn node(&self, node: IVec3) -> Option<NodeMask<'_>> {
        let (brick, slot) = split(node);
        Some(self.slot_mask(&self.bricks.get(&brick)?.nodes, slot))
    }

    /// A brick's bits (per slot, [`GROUPS`] groups of `words` words), or
    /// None when no node in it was ever computed.
    pub fn brick(&self, brick: IVec3) -> Option<&[u64]> {
        self.bricks.get(&brick).map(|stored| &stored.nodes[..])
    }

    /// The mask of `slot` within a brick's bits.
    pub fn slot_mask<'a>(&self, bits: &'a [u64], slot: usize) -> NodeMask<'a> {
        NodeMask::of_slot(bits, slot, self.words)
    }

    /// V(light, node) if it is known.
    pub fn get(&self, node: IVec3, light: usize) -> Option<bool> {
        self.node(node)?.get(light)
    }

    /// Records one light's bits at one node: the static layer, and the
    /// dynamic one where given.
    pub fn set(
        &mut self,
        node: IVec3,
        light: usize,
        static_visible: bool,
        dynamic_occluded: Option<bool>,
    ) {
        let (brick, slot) = split(node);
        let (word, bit) = (light / 64, 1u64 << (light % 64));
        let mut update = LayerUpdate::zeroed(self.words);
        update.static_computed[word] = bit;
        update.static_visible[word] = if static_visible { bit } else { 0 };
        if let Some(occluded) = dynamic_occluded {
            update.dynamic_computed[word] = bit;
            update.dynamic_occluded[word] = if occluded { bit } else { 0 };
        }
        let words = self.words;
        let (stored, known) = self.edit(brick);
        let merged = merge_slot(stored, known, words, slot, &update, 0);
        self.nodes += merged.became_a_node as usize;
        self.static_found += merged.found;
    }

    /// Records a whole brick's computed bits (layout `slot * words + word`).
    pub fn merge_brick(&mut self, brick: IVec3, update: &LayerUpdate) {
        self.merge_bricks(&[(brick, update)]);
    }

    /// Records whole bricks' computed bits, each brick named once: the
    /// store ends as [`MaskStore::merge_brick`] called for each in turn
    /// leaves it, revisions included, while the bricks are merged in
    /// parallel (taken out of the map, stamped in order, put back).
    pub fn merge_bricks(&mut self, updates: &[(IVec3, &LayerUpdate)]) {
        use rayon::prelude::*;
        let words = self.words;
        let slots: Vec<Vec<usize>> = (updates.par_iter())
            .map(|(_, update)| computed_slots(update, words))
            .collect();
        let updates: Vec<_> = (updates.iter().zip(&slots))
            .map(|(&(brick, update), slots)| (brick, update, UpdateRows::EverySlot(slots)))
            .collect();
        self.merge_bricks_at(&updates);
    }

    /// [`MaskStore::merge_bricks`] for updates that say which slots
    /// they hold bits for ([`UpdateRows`]), so that a fill that touched a
    /// few of a brick's [`BRICK_NODES`] pays for those alone. A brick with
    /// no slot is left alone; a row with no computed bit changes nothing.
    pub fn merge_bricks_at(&mut self, updates: &[(IVec3, &LayerUpdate, UpdateRows)]) {
        use rayon::prelude::*;
        let (words, lights) = (self.words, self.lights);
        let mut taken = Vec::new();
        for &(brick, update, rows) in updates {
            if rows.slots().is_empty() {
                continue;
            }
            self.revision += 1;
            let mut stored = (self.bricks.remove(&brick)).unwrap_or_else(|| Brick::new(words));
            stored.revision = self.revision;
            taken.push((brick, stored, update, rows));
        }
        let (new_nodes, found, known) = (taken.par_iter_mut())
            .fold(
                || (0, 0, KnownCounts::new(lights)),
                |(mut new_nodes, mut found, mut known), (_, stored, update, rows)| {
                    for (index, &slot) in rows.slots().iter().enumerate() {
                        let row = rows.row(index, slot);
                        let merged =
                            merge_slot(stored, &mut known, words, slot, update, row * words);
                        new_nodes += merged.became_a_node as usize;
                        found += merged.found;
                    }
                    (new_nodes, found, known)
                },
            )
            .reduce(
                || (0, 0, KnownCounts::new(lights)),
                |(nodes_a, found_a, mut known), (nodes_b, found_b, other)| {
                    known.add(&other);
                    (nodes_a + nodes_b, found_a + found_b, known)
                },
            );
        self.nodes += new_nodes;
        self.static_found += found;
        self.known.add(&known);
        (self.bricks).extend(taken.into_iter().map(|(brick, stored, ..)| (brick, stored)));
    }

    /// Clears validity bits, brick by brick in parallel: `clear` gets each
    /// brick's coordinates and a node-slot view of its bits and returns how
    /// many bits it cleared. Only validity may be cleared.
    pub fn invalidate<F>(&mut self, clear: F) -> u64
    where
        F: Fn(IVec3, &mut BrickValidity) -> u64 + Send + Sync,
    {
        use rayon::prelude::*;
        let (words, lights) = (self.words, self.lights);
        self.revision += 1;
        let revision = self.revision;
        let (cleared, lost) = self
            .bricks
            .par_iter_mut()
            .fold(
                || (0, KnownCounts::new(lights)),
                |(cleared, mut lost), (brick, stored)| {
                    let validity = &mut BrickValidity {
                        bits: &mut stored.nodes,
                        dynamic_lights: &mut stored.dynamic_lights,
                        words,
                        lost: &mut lost,
                    };
                    let brick_cleared = clear(*brick, validity);
                    if brick_cleared > 0 {
                        stored.revision = revision;
                    }
                    (cleared + brick_cleared, lost)
                },
            )
            .reduce(
                || (0, KnownCounts::new(lights)),
                |(a, mut lost), (b, other)| {
                    lost.add(&other);
                    (a + b, lost)
                },
            );
        self.known.subtract(&lost);
        cleared
    }

    /// The coordinates of every brick held, in no particular order.
    pub fn brick_keys(&self) -> impl Iterator<Item = IVec3> + '_ {
        self.bricks.keys().copied()
    }

    pub fn has_brick(&self, brick: IVec3) -> bool {
        self.bricks.contains_key(&brick)
    }

    pub fn brick_count(&self) -> usize {
        self.bricks.len()
    }

    /// Heap bytes one brick takes, for memory budgets.
    pub fn brick_bytes(lights: usize) -> usize {
        (BRICK_NODES * GROUPS + 1) * lights.div_ceil(64).max(1) * std::mem::size_of::<u64>()
    }

    /// (node, light) pairs whose static bit is known: every pair the fill
    /// stage ever computed and no moved light has dropped since.
    pub fn static_bits(&self) -> u64 {
        let stride = GROUPS * self.words;
        let valid = STATIC_VALID * self.words..(STATIC_VALID + 1) * self.words;
        self.bricks
            .values()
            .flat_map(|stored| stored.nodes.chunks(stride))
            .map(|node| {
                node[valid.clone()]
                    .iter()
                    .map(|w| w.count_ones() as u64)
                    .sum::<u64>()
            })
            .sum()
    }

    /// Static bits the fill found since the store was made; those the
    /// disk cache imported are not counted.
    pub fn static_bits_found(&self) -> u64 {
        self.static_found
    }

    /// (node, light) pairs whose visibility is known (see
    /// [`NodeMask::valid`]): what the next frame can reuse.
    pub fn known_bits(&self) -> u64 {
        self.known.per_light.iter().sum()
    }

    /// (node, light) pairs whose visibility is known for the lights whose
    /// bits `lights` sets (64 lights a word, as the masks hold them).
    pub fn known_bits_of(&self, lights: &[u64]) -> u64 {
        (lights.iter().enumerate().take(self.words))
            .flat_map(|(word, &wanted)| set_bits(wanted).map(move |bit| 64 * word + bit))
            .filter_map(|light| self.known.per_light.get(light))
            .sum()
    }

    /// Nodes with at least one valid bit.
    pub fn nodes_cached(&self) -> usize {
        self.nodes
    }

    /// The enclosure flags of a brick's nodes (none known for a brick the
    /// store does not hold).
    pub fn enclosure(&self, brick: IVec3) -> BrickEnclosure {
        self.bricks
            .get(&brick)
            .map_or_else(BrickEnclosure::default, |stored| stored.enclosure)
    }

    /// Records the enclosure flags settled for the `known` slots of a brick.
    pub fn merge_enclosure(&mut self, brick: IVec3, settled: &BrickEnclosure) {
        self.enclosure_found += self.add_enclosure(brick, settled);
    }

    /// Takes the enclosure flags the disk cache holds for a brick the
    /// store has (it creates none): they come from no probe of this run.
    /// Returns how many flags it did not know.
    pub fn import_enclosure(&mut self, brick: IVec3, flags: &BrickEnclosure) -> u64 {
        match self.has_brick(brick) {
            true => self.add_enclosure(brick, flags),
            false => 0,
        }
    }

    /// Flags settled since the store was made; those the disk cache
    /// imported are not counted.
    pub fn enclosure_flags_found(&self) -> u64 {
        self.enclosure_found
    }

    /// The flags of every brick where some node has one, in no order.
    pub fn known_enclosures(&self) -> impl Iterator<Item = (IVec3, &BrickEnclosure)> {
        (self.bricks.iter())
            .filter(|(_, stored)| stored.enclosure.known.iter().any(|&word| word != 0))
            .map(|(&brick, stored)| (brick, &stored.enclosure))
    }

    /// ORs `settled`'s known flags into the brick's; returns how many it
    /// did not know.
    fn add_enclosure(&mut self, brick: IVec3, settled: &BrickEnclosure) -> u64 {
        let stored = &mut self.edit(brick).0.enclosure;
        let mut newly_known = 0;
        for word in 0..BRICK_WORDS {
            let known = settled.known[word];
            newly_known += u64::from((known & !stored.known[word]).count_ones());
            stored.enclosed[word] =
                (stored.enclosed[word] & !known) | (settled.enclosed[word] & known);
            stored.known[word] |= known;
        }
        newly_known
    }

    /// The static-layer bits of the lights `wanted` sets (64 lights a
    /// word), brick by brick, as the disk cache keeps them: `visit(brick,
    /// light, bits)` for each light with a valid bit in the brick, the
    /// bricks in ascending order of coordinates (so a map keyed by them
    /// grows at its end, where its nodes are in the processor's cache).
    /// One pass over the store serves every light (at 64 lamps a brick
    /// takes 16 KiB, and a pass per light took a city's save seconds), and
    /// each 64 nodes' words turn into the lights' words by one transpose.
    pub fn for_each_static_brick(
        &self,
        wanted: &[u64],
        mut visit: impl FnMut(IVec3, usize, &BrickLightBits),
    ) {
        let words = self.words;
        let stride = GROUPS * words;
        let mut by_light = vec![BrickLightBits::default(); self.lights];
        let (mut valid, mut visible) = ([0u64; 64], [0u64; 64]);
        let mut bricks: Vec<_> = self.bricks.iter().collect();
        bricks.sort_unstable_by_key(|(brick, _)| brick.to_array());
        for (&brick, stored) in bricks {
            for (word, &wanted) in wanted.iter().enumerate().take(words) {
                let mut held = 0;
                for (at, nodes) in stored.nodes.chunks(64 * stride).enumerate() {
                    for (slot, node) in nodes.chunks(stride).enumerate() {
                        valid[slot] = node[STATIC_VALID * words + word] & wanted;
                        visible[slot] = node[STATIC_VISIBLE * words + word] & valid[slot];
                    }
                    let lights = valid.iter().fold(0, |any, &lights| any | lights);
                    held |= lights;
                    if lights == 0 {
                        continue;
                    }
                    transpose64(&mut valid);
                    transpose64(&mut visible);
                    for light in set_bits(lights) {
                        by_light[64 * word + light].valid[at] = valid[light];
                        by_light[64 * word + light].visible[at] = visible[light];
                    }
                }
                for light in set_bits(held) {
                    let bits = &mut by_light[64 * word + light];
                    visit(brick, 64 * word + light, bits);
                    *bits = BrickLightBits::default();
                }
            }
        }
    }

    /// Records the static bits the disk cache holds for `brick`, each of
    /// `lights` with its number, where the store has none yet; returns how
    /// many became valid. The dynamic layer is left invalid, so the fill
    /// stage still tests dynamic objects. A brick's lights go in together,
    /// 64 nodes at a time: the lights' words turn into the nodes' words
    /// by one transpose, as [`Self::for_each_static_brick`] turns them back.
    pub fn import_static(&mut self, brick: IVec3, lights: &[(usize, &BrickLightBits)]) -> u64 {
        let words = self.words;
        let stride = GROUPS * words;
        let (stored, known) = self.edit(brick);
        let unset_before = unset_static_slots(&stored.nodes, words);
        // The slots that gained a static bit, a bit each.
        let mut filled = [0u64; BRICK_WORDS];
        let mut imported = 0;
        for word in 0..words {
            let in_word = || lights.iter().filter(move |(light, _)| light / 64 == word);
            for (at, nodes) in stored.nodes.chunks_mut(64 * stride).enumerate() {
                let (mut valid, mut visible) = ([0u64; 64], [0u64; 64]);
                for &(light, bits) in in_word() {
                    valid[light % 64] = bits.valid[at];
                    visible[light % 64] = bits.visible[at] & bits.valid[at];
                }
                if valid.iter().all(|&slots| slots == 0) {
                    continue;
                }
                transpose64(&mut valid);
                transpose64(&mut visible);
                // Per node, the lights whose bit became valid.
                let mut gained = [0u64; 64];
                for (slot, node) in nodes.chunks_mut(stride).enumerate() {
                    let new = valid[slot] & !node[STATIC_VALID * words + word];
                    if new == 0 {
                        continue;
                    }
                    let valid_before = (NodeMask { bits: node, words }).valid(word);
                    let at_visible = STATIC_VISIBLE * words + word;
                    node[at_visible] = (node[at_visible] & !new) | (visible[slot] & new);
                    node[STATIC_VALID * words + word] |= new;
                    let valid_after = (NodeMask { bits: node, words }).valid(word);
                    gained[slot] = valid_after & !valid_before;
                    filled[at] |= 1 << slot;
                    imported += u64::from(new.count_ones());
                }
                // Per light, the nodes that gained it.
                transpose64(&mut gained);
                for (bit, nodes) in gained.iter().enumerate().filter(|(_, &nodes)| nodes != 0) {
                    known.gain_nodes(64 * word + bit, nodes.count_ones().into());
                }
            }
        }
        let new_nodes: u32 = (unset_before.iter().zip(&filled))
            .map(|(unset, filled)| (unset & filled).count_ones())
            .sum();
        self.nodes += new_nodes as usize;
        imported
    }
}

/// The slots of a brick's `nodes` without a valid static bit, a bit each.
fn unset_static_slots(nodes: &[u64], words: usize) -> [u64; BRICK_WORDS] {
    let mut unset = [0; BRICK_WORDS];
    for (slot, node) in nodes.chunks(GROUPS * words).enumerate() {
        let valid = &node[STATIC_VALID * words..(STATIC_VALID + 1) * words];
        if valid.iter().all(|&word| word == 0) {
            unset[slot / 64] |= 1 << (slot % 64);
        }
    }
    unset
}

/// Words holding one bit per node slot of a brick.
pub const BRICK_WORDS: usize = BRICK_NODES / 64;

/// One light's static-layer bits over a brick, bit `slot % 64` of word
/// `slot / 64` per node: the unit the disk cache stores.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct BrickLightBits {
    pub valid: [u64; BRICK_WORDS],
    /// Set only where `valid` is.
    pub visible: [u64; BRICK_WORDS],
}

/// Mutable access to one brick's validity bits, for invalidation.
pub struct BrickValidity<'a> {
    bits: &'a mut [u64],
    dynamic_lights: &'a mut [u64],
    words: usize,
    /// Per light, the valid bits cleared: the store's counts lose them.
    lost: &'a mut KnownCounts,
}

impl BrickValidity<'_> {
    /// Lights (word `word`) of which some node of the brick holds a valid
    /// dynamic bit.
    pub fn dynamic_lights(&self, word: usize) -> u64 {
        self.dynamic_lights[word]
    }

    /// Where word `word` of `group` of the node at `slot` is.
    fn index(&self, slot: usize, group: usize, word: usize) -> usize {
        (slot * GROUPS + group) * self.words + word
    }

    /// [`NodeMask::valid`] of the node at `slot`.
    fn valid(&self, slot: usize, word: usize) -> u64 {
        NodeMask::of_slot(self.bits, slot, self.words).valid(word)
    }

    /// Clears the dynamic-layer validity of light `64·word + bit` at each
    /// slot that holds it and `changed(slot)` takes; returns how many bits
    /// were cleared.
    pub fn clear_dynamic_where(
        &mut self,
        word: usize,
        bit: u32,
        mut changed: impl FnMut(usize) -> bool,
    ) -> u64 {
        let light = 1u64 << bit;
        let mut cleared = 0;
        let mut kept = 0;
        for slot in 0..BRICK_NODES {
            let at = self.index(slot, DYNAMIC_VALID, word);
            if self.bits[at] & light == 0 {
                continue;
            }
            if changed(slot) {
                let valid_before = self.valid(slot, word);
                self.bits[at] &= !light;
                self.lost.gain(word, valid_before & !self.valid(slot, word));
                cleared += 1;
            } else {
                kept += 1;
            }
        }
        if kept == 0 {
            self.dynamic_lights[word] &= !light;
        }
        cleared
    }

    /// Clears both layers' validity of `lights` (word `word`) at every
    /// slot (moved lights); returns how many valid bits were cleared.
    pub fn clear_lights(&mut self, word: usize, lights: u64) -> u64 {
        let mut cleared = 0;
        for slot in 0..BRICK_NODES {
            self.lost.gain(word, self.valid(slot, word) & lights);
            for group in [STATIC_VALID, DYNAMIC_VALID] {
                let at = self.index(slot, group, word);
                let bits = &mut self.bits[at];
                cleared += (*bits & lights).count_ones() as u64;
                *bits &= !lights;
            }
        }
        self.dynamic_lights[word] &= !lights;
        cleared
    }
}

/// Per light, how many nodes hold a valid bit of it. The counts are kept
/// modulo 2^64, so a part of a tally (one thread's share of
/// [`MaskStore::merge_bricks`], which may lose more than it gains) adds up
/// with the others to the true count.
#[derive(Clone, Debug)]
struct KnownCounts {
    per_light: Box<[u64]>,
}

impl KnownCounts {
    fn new(lights: usize) -> KnownCounts {
        KnownCounts {
            per_light: vec![0; lights].into_boxed_slice(),
        }
    }

    /// One more node for each light `64·word + bit` that `bits` sets.
    fn gain(&mut self, word: usize, bits: u64) {
        for bit in set_bits(bits) {
            self.per_light[64 * word + bit] = self.per_light[64 * word + bit].wrapping_add(1);
        }
    }

    /// `nodes` more nodes for light `light`.
    fn gain_nodes(&mut self, light: usize, nodes: u64) {
        self.per_light[light] += nodes;
    }

    /// One node fewer for each light `64·word + bit` that `bits` sets.
    fn lose(&mut self, word: usize, bits: u64) {
        for bit in set_bits(bits) {
            self.per_light[64 * word + bit] = self.per_light[64 * word + bit].wrapping_sub(1);
        }
    }

    fn add(&mut self, other: &KnownCounts) {
        for (count, more) in self.per_light.iter_mut().zip(&other.per_light) {
            *count = count.wrapping_add(*more);
        }
    }

    fn subtract(&mut self, other: &KnownCounts) {
        for (count, fewer) in self.per_light.iter_mut().zip(&other.per_light) {
            *count = count.wrapping_sub(*fewer);
        }
    }
}

/// The brick holding `node` and the node's slot in it.
pub fn split(node: IVec3) -> (IVec3, usize) {
    // Floor division and remainder by the power-of-two edge, negative
    // coordinates included (an arithmetic shift rounds towards −∞).
    let brick = node >> BRICK_EDGE.trailing_zeros() as i32;
    let local = node & (BRICK_EDGE - 1);
    let slot = ((local.z * BRICK_EDGE + local.y) * BRICK_EDGE + local.x) as usize;
    (brick, slot)
}

/// Reads node masks through a small cache of brick lookups. A half-ball
/// spans at most two bricks per axis at the usual kI, and neighbouring
/// shading points share them, so entries are kept by the parity of the
/// brick coordinates: the bricks of any 2×2×2 block never evict each other.
pub struct BrickCache<'a> {
    store: &'a MaskStore,
    entries: [Option<CachedBrick<'a>>; 8],
}

/// A brick's coordinates and the brick, None when the store has none.
type CachedBrick<'a> = (IVec3, Option<&'a Brick>);

impl<'a> BrickCache<'a> {
    pub fn new(store: &'a MaskStore) -> BrickCache<'a> {
        BrickCache {
            store,
            entries: [None; 8],
        }
    }

    /// The identity of the store read ([`MaskStore::id`]).
    pub fn store_id(&self) -> u64 {
        self.store.id
    }

    /// The node's mask, or None when no bit of its brick was ever computed.
    pub fn mask(&mut self, node: IVec3) -> Option<NodeMask<'a>> {
        let (brick, slot) = split(node);
        Some(self.view(brick)?.mask(slot))
    }

    /// Whether the node is known to lie inside closed geometry.
    pub fn is_enclosed(&mut self, node: IVec3) -> bool {
        let (brick, slot) = split(node);
        self.view(brick).is_some_and(|view| view.is_enclosed(slot))
    }

    /// The brick, read slot by slot, or None when no bit of it was ever
    /// computed: one lookup for any number of its nodes.
    pub fn view(&mut self, brick: IVec3) -> Option<BrickView<'a>> {
        let stored = self.brick(brick)?;
        Some(BrickView {
            stored,
            words: self.store.words,
        })
    }

    fn brick(&mut self, brick: IVec3) -> Option<&'a Brick> {
        let entry = parity(brick);
        match self.entries[entry] {
            Some((cached, stored)) if cached == brick => stored,
            _ => {
                let stored = self.store.bricks.get(&brick);
                self.entries[entry] = Some((brick, stored));
                stored
            }
        }
    }
}

/// One stored brick's nodes, by slot ([`split`]).
#[derive(Clone, Copy)]
pub struct BrickView<'a> {
    stored: &'a Brick,
    words: usize,
}

impl<'a> BrickView<'a> {
    pub fn mask(&self, slot: usize) -> NodeMask<'a> {
        NodeMask::of_slot(&self.stored.nodes, slot, self.words)
    }

    /// Whether the node in `slot` is known to lie inside closed geometry.
    pub fn is_enclosed(&self, slot: usize) -> bool {
        self.stored.enclosure.enclosed[slot / 64] & 1 << (slot % 64) != 0
    }

    /// The store's revision at the brick's last edit
    /// ([`MaskStore::brick_revision`]).
    pub fn revision(&self) -> u64 {
        self.stored.revision
    }
}

/// Which of 8 cache entries a brick takes: the parities of its
/// coordinates, distinct for the 8 bricks of any 2×2×2 block.
pub fn parity(brick: IVec3) -> usize {
    (brick.x & 1 | (brick.y & 1) << 1 | (brick.z & 1) << 2) as usize
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

/// The slots of a whole brick's `update` (layout `slot * words + word`)
/// with a computed bit in either layer.
fn computed_slots(update: &LayerUpdate, words: usize) -> Vec<usize> {
    (0..BRICK_NODES)
        .filter(|&slot| {
            let range = slot * words..(slot + 1) * words;
            update.static_computed[range.clone()]
                .iter()
                .chain(&update.dynamic_computed[range])
                .any(|&word| word != 0)
        })
        .collect()
}

/// What merging one slot changed beyond its bits.
struct SlotMerged {
    /// The node had no valid static bit before and has one now.
    became_a_node: bool,
    /// Static bits valid now that were not.
    found: u64,
}

/// Records `update`'s bits (from `offset`) in `slot` of `stored`, keeping
/// `known`'s counts of valid bits.
fn merge_slot(
    stored: &mut Brick,
    known: &mut KnownCounts,
    words: usize,
    slot: usize,
    update: &LayerUpdate,
    offset: usize,
) -> SlotMerged {
    let node = &mut stored.nodes[slot * GROUPS * words..(slot + 1) * GROUPS * words];
    let was_empty = node[STATIC_VALID * words..(STATIC_VALID + 1) * words]
        .iter()
        .all(|&valid| valid == 0);
    let (mut now_valid, mut found) = (false, 0);
    for word in 0..words {
        let valid_before = (NodeMask { bits: node, words }).valid(word);
        let at = |group: usize| group * words + word;
        let (computed, value) = (
            update.static_computed[offset + word],
            update.static_visible[offset + word],
        );
        node[at(STATIC_VISIBLE)] = (node[at(STATIC_VISIBLE)] & !computed) | (value & computed);
        found += (computed & !node[at(STATIC_VALID)]).count_ones() as u64;
        node[at(STATIC_VALID)] |= computed;
        let (computed, value) = (
            update.dynamic_computed[offset + word],
            update.dynamic_occluded[offset + word],
        );
        node[at(DYNAMIC_OCCLUDED)] = (node[at(DYNAMIC_OCCLUDED)] & !computed) | (value & computed);
        node[at(DYNAMIC_VALID)] |= computed;
        stored.dynamic_lights[word] |= computed;
        now_valid |= node[at(STATIC_VALID)] != 0;
        let valid_after = (NodeMask { bits: node, words }).valid(word);
        known.gain(word, valid_after & !valid_before);
        known.lose(word, valid_before & !valid_after);
    }
    SlotMerged {
        became_a_node: was_empty && now_valid,
        found,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bits_are_invalid_until_set_and_then_hold_their_value() {
        let mut store = MaskStore::new(130);
        let node = IVec3::new(-1, 9, -17);
        assert_eq!(store.get(node, 0), None);
        store.set(node, 129, true, Some(false));
        store.set(node, 64, false, None);
        assert_eq!(store.get(node, 129), Some(true));
        assert_eq!(
            store.get(node, 64),
            Some(false),
            "a static blocker needs no dynamic bit"
        );
        assert_eq!(store.get(node, 0), None);
        store.set(node, 129, true, Some(true));
        assert_eq!(
            store.get(node, 129),
            Some(false),
            "a dynamic blocker hides the light"
        );
        store.set(node, 1, true, None);
        assert_eq!(
            store.get(node, 1),
            None,
            "statically visible: the dynamic bit decides"
        );
        // A neighbour in the same brick is untouched.
        assert_eq!(store.get(node + IVec3::X, 129), None);
        assert_eq!(store.nodes_cached(), 1);
    }

    /// The lights a brick says it holds dynamic bits of, after `clear`.
    fn dynamic_lights_after(
        store: &mut MaskStore,
        clear: impl Fn(&mut BrickValidity) -> u64 + Send + Sync,
    ) -> (u64, [u64; 2]) {
        let seen = std::sync::Mutex::new([0; 2]);
        let cleared = store.invalidate(|_, validity| {
            let cleared = clear(validity);
            *seen.lock().unwrap() = [0, 1].map(|word| validity.dynamic_lights(word));
            cleared
        });
        (cleared, seen.into_inner().unwrap())
    }

    #[test]
    fn a_brick_knows_exactly_which_lights_it_holds_dynamic_bits_of() {
        let mut store = MaskStore::new(70);
        let (a, b) = (IVec3::new(1, 2, 3), IVec3::new(4, 5, 6));
        store.set(a, 3, true, Some(false));
        store.set(b, 3, true, Some(true));
        store.set(a, 65, true, Some(false));
        store.set(b, 7, false, None);
        let (slot_a, slot_b) = (split(a).1, split(b).1);
        let (cleared, lights) = dynamic_lights_after(&mut store, |_| 0);
        assert_eq!(
            (cleared, lights),
            (0, [1 << 3, 1 << 1]),
            "light 7 is static only"
        );

        // Clearing one of light 3's two nodes keeps it; the other drops it.
        let (cleared, lights) =
            dynamic_lights_after(&mut store, |v| v.clear_dynamic_where(0, 3, |s| s == slot_a));
        assert_eq!((cleared, lights), (1, [1 << 3, 1 << 1]));
        assert_eq!(store.get(a, 3), None);
        assert_eq!(store.get(b, 3), Some(false));
        let (cleared, lights) = dynamic_lights_after(&mut store, |v| {
            v.clear_dynamic_where(0, 3, |s| {
                assert_eq!(s, slot_b, "only slots holding the bit are asked");
                true
            })
        });
        assert_eq!((cleared, lights), (1, [0, 1 << 1]));

        // A moved light drops both layers everywhere.
        store.set(b, 3, true, Some(false));
        let (cleared, lights) = dynamic_lights_after(&mut store, |v| v.clear_lights(0, 1 << 3));
        assert_eq!(
            (cleared, lights),
            (3, [0, 1 << 1]),
            "both of b's bits and a's static one"
        );
        assert_eq!(store.get(b, 3), None);
        assert_eq!(store.get(b, 7), Some(false), "other lights stay");
    }

    #[test]
    fn the_brick_cache_reads_what_the_store_holds() {
        let mut store = MaskStore::new(1);
        // Bricks 0 and 2 along x share a cache entry; negative bricks too.
        let nodes: Vec<IVec3> = [-17, -9, -1, 0, 5, 8, 16, 17, 23]
            .iter()
            .flat_map(|&i| [IVec3::new(i, 0, 0), IVec3::new(i, -i, 3)])
            .collect();
        for (index, node) in nodes.iter().enumerate() {
            store.set(*node, 0, index % 3 != 0, Some(index % 5 == 0));
        }
        let mut cache = BrickCache::new(&store);
        for round in 0..2 {
            for (index, node) in nodes.iter().enumerate() {
                let expected = index % 3 != 0 && index % 5 != 0;
                let mask = cache.mask(*node).expect("a stored node");
                assert_eq!(mask.get(0), Some(expected), "node {node} round {round}");
            }
        }
        assert!(cache.mask(IVec3::new(100, 0, 0)).is_none());
    }

    /// A copy of the store elsewhere (the GPU's pool) trusts a brick
    /// while its revision holds: every edit must move it, and nothing
    /// else may.
    #[test]
    fn a_brick_revision_moves_with_every_edit_of_the_brick_and_only_then() {
        let mut store = MaskStore::new(3);
        let (a, b) = (IVec3::new(1, 2, 3), IVec3::new(40, 0, 0));
        assert_eq!(store.brick_revision(split(a).0), None);
        store.set(a, 0, true, Some(false));
        store.set(b, 1, true, Some(true));
        let revision = |store: &MaskStore, node| store.brick_revision(split(node).0).unwrap();
        let (before_a, before_b) = (revision(&store, a), revision(&store, b));
        assert_ne!(before_a, before_b);

        // Invalidation that clears nothing in a brick leaves it alone.
        store.invalidate(|brick, validity| {
            if brick == split(b).0 {
                validity.clear_lights(0, 1 << 1)
            } else {
                0
            }
        });
        assert_eq!(revision(&store, a), before_a);
        let after_b = revision(&store, b);
        assert_ne!(after_b, before_b);

        store.merge_enclosure(split(a).0, &BrickEnclosure::default());
        assert_ne!(revision(&store, a), before_a);
        assert_eq!(revision(&store, b), after_b);

        let bits = BrickLightBits {
            valid: [1; BRICK_WORDS],
            visible: [0; BRICK_WORDS],
        };
        let before_import = revision(&store, b);
        store.import_static(split(b).0, &[(2, &bits)]);
        assert_ne!(revision(&store, b), before_import);

        // A copy is another store: its edits cannot pass for the original's.
        assert_ne!(store.clone().id(), store.id());
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
            store.set(*node, 0, index % 2 == 0, Some(false));
        }
        for (index, node) in nodes.iter().enumerate() {
            assert_eq!(store.get(*node, 0), Some(index % 2 == 0), "{node}");
        }
        assert_eq!(store.nodes_cached(), nodes.len());
    }
}

#[cfg(test)]
mod known_count_tests {
    use proptest::prelude::*;

    use super::*;

    /// Per light, the nodes holding a valid bit of it, read from every
    /// node of the store: what the kept counts must equal.
    fn recounted(store: &MaskStore) -> Vec<u64> {
        let mut counts = vec![0; store.lights()];
        for brick in store.brick_keys().collect::<Vec<_>>() {
            let bits = store.brick(brick).unwrap();
            for slot in 0..BRICK_NODES {
                let mask = store.slot_mask(bits, slot);
                for (light, count) in counts.iter_mut().enumerate() {
                    *count += mask.valid(light / 64) >> (light % 64) & 1;
                }
            }
        }
        counts
    }

    /// One edit of a store of 70 lights, on nodes of two neighbouring
    /// bricks.
    #[derive(Clone, Debug)]
    enum Edit {
        Set {
            node: [i32; 3],
            light: usize,
            visible: bool,
            occluded: Option<bool>,
        },
        ClearDynamic {
            light: usize,
            slot_parity: usize,
        },
        ClearLights {
            word: usize,
            lights: u64,
        },
        Import {
            brick: i32,
            light: usize,
            valid: u64,
            visible: u64,
        },
    }

    fn edit() -> impl Strategy<Value = Edit> {
        let light = 0..70usize;
        prop_oneof![
            4 => (proptest::array::uniform3(-3..3), light.clone(), any::<bool>(), any::<Option<bool>>())
                .prop_map(|(node, light, visible, occluded)| Edit::Set { node, light, visible, occluded }),
            1 => (light.clone(), 0..2usize)
                .prop_map(|(light, slot_parity)| Edit::ClearDynamic { light, slot_parity }),
            1 => (0..2usize, any::<u64>()).prop_map(|(word, lights)| Edit::ClearLights { word, lights }),
            1 => (-1..1, light, any::<u64>(), any::<u64>())
                .prop_map(|(brick, light, valid, visible)| Edit::Import { brick, light, valid, visible }),
        ]
    }

    /// Applies `edit` to `store`; returns the static bits it found (a set
    /// of a static bit that was not valid yet: what `static_bits_found`
    /// must count).
    fn apply(store: &mut MaskStore, edit: Edit) -> u64 {
        match edit {
            Edit::Set {
                node,
                light,
                visible,
                occluded,
            } => {
                let node = IVec3::from(node);
                let was_valid = store
                    .node(node)
                    .is_some_and(|mask| mask.static_layer(light / 64).1 >> (light % 64) & 1 == 1);
                store.set(node, light, visible, occluded);
                return u64::from(!was_valid);
            }
            Edit::ClearDynamic { light, slot_parity } => {
                store.invalidate(|_, validity| {
                    validity.clear_dynamic_where(light / 64, (light % 64) as u32, |slot| {
                        slot % 2 == slot_parity
                    })
                });
            }
            Edit::ClearLights { word, lights } => {
                store.invalidate(|_, validity| validity.clear_lights(word, lights));
            }
            Edit::Import {
                brick,
                light,
                valid,
                visible,
            } => {
                let bits = BrickLightBits {
                    valid: [valid; BRICK_WORDS],
                    visible: [visible & valid; BRICK_WORDS],
                };
                let brick = IVec3::splat(brick);
                let (word, bit) = (light / 64, light % 64);
                let static_bit = |store: &MaskStore, slot: usize| {
                    let (visible, valid) = store.node(join(brick, slot))?.static_layer(word);
                    (valid >> bit & 1 == 1).then_some(visible >> bit & 1 == 1)
                };
                let before: Vec<_> = (0..BRICK_NODES)
                    .map(|slot| static_bit(store, slot))
                    .collect();
                store.import_static(brick, &[(light, &bits)]);
                // A bit the store held stays; the file gives the others.
                for (slot, before) in before.into_iter().enumerate() {
                    let in_file =
                        (valid >> (slot % 64) & 1 == 1).then_some(visible >> (slot % 64) & 1 == 1);
                    assert_eq!(static_bit(store, slot), before.or(in_file), "slot {slot}");
                }
            }
        }
        0
    }

    proptest! {
        /// Whatever sets or clears bits (the fill's merges, the disk
        /// cache's import, both kinds of invalidation), the counts the
        /// store keeps equal a count over every node, and the static bits
        /// it found are those the fill's sets made valid.
        #[test]
        fn kept_counts_equal_a_recount(edits in proptest::collection::vec(edit(), 1..60)) {
            let mut store = MaskStore::new(70);
            let mut found = 0;
            for edit in edits {
                found += apply(&mut store, edit);
                let counts = recounted(&store);
                prop_assert_eq!(&store.known.per_light[..], &counts[..]);
                prop_assert_eq!(store.known_bits(), counts.iter().sum::<u64>());
                let odd_lights = [0xaaaa_aaaa_aaaa_aaaa, 0xaaaa_aaaa_aaaa_aaaa];
                let odd: u64 = counts.iter().skip(1).step_by(2).sum();
                prop_assert_eq!(store.known_bits_of(&odd_lights), odd);
                prop_assert_eq!(store.static_bits_found(), found);
            }
        }

        /// Bricks merged together, in parallel, leave the store as
        /// merging them one after another does: every bit, each brick's
        /// revision and dynamic lights, and the counts the store keeps
        /// (which a thread's share of the merge may take below zero).
        #[test]
        fn bricks_merged_together_equal_bricks_merged_in_turn(
            edits in proptest::collection::vec(edit(), 0..40),
            bits in proptest::collection::vec(
                (-1..3i32, 0..BRICK_NODES, 0..2usize, proptest::array::uniform4(any::<u64>())),
                0..200,
            ),
        ) {
            let mut store = MaskStore::new(70);
            for edit in edits {
                apply(&mut store, edit);
            }
            let words = store.words();
            let mut updates: Vec<(IVec3, LayerUpdate)> = (-1..3)
                .map(|brick| (IVec3::splat(brick), LayerUpdate::zeroed(BRICK_NODES * words)))
                .collect();
            for (brick, slot, word, [static_computed, visible, dynamic_computed, occluded]) in bits {
                let update = &mut updates[(brick + 1) as usize].1;
                let at = slot * words + word;
                // Lights 0..70 only.
                let lights = if word == 0 { u64::MAX } else { (1 << (70 - 64)) - 1 };
                let (static_computed, dynamic_computed) = (static_computed & lights, dynamic_computed & lights);
                update.static_computed[at] |= static_computed;
                update.static_visible[at] |= visible & static_computed;
                update.dynamic_computed[at] |= dynamic_computed;
                update.dynamic_occluded[at] |= occluded & dynamic_computed;
            }
            let mut in_turn = store.clone();
            for (brick, update) in &updates {
                in_turn.merge_bricks(&[(*brick, update)]);
            }
            let together = {
                let named: Vec<_> = updates.iter().map(|(brick, update)| (*brick, update)).collect();
                store.merge_bricks(&named);
                store
            };
            prop_assert_eq!(&together.known.per_light, &in_turn.known.per_light);
            prop_assert_eq!(&recounted(&together)[..], &together.known.per_light[..]);
            prop_assert_eq!(together.nodes_cached(), in_turn.nodes_cached());
            prop_assert_eq!(together.static_bits_found(), in_turn.static_bits_found());
            prop_assert_eq!(together.revision, in_turn.revision);
            prop_assert_eq!(together.bricks.len(), in_turn.bricks.len());
            for (brick, stored) in &together.bricks {
                let other = &in_turn.bricks[brick];
                prop_assert_eq!(&stored.nodes, &other.nodes);
                prop_assert_eq!(&stored.dynamic_lights, &other.dynamic_lights);
                prop_assert_eq!(stored.revision, other.revision);
            }
        }

        /// The one pass over the store that the disk cache saves from
        /// hands out each wanted light's static bits once per brick that
        /// holds a valid one, as every node's static layer has them.
        #[test]
        fn static_bricks_equal_every_nodes_static_layer(
            edits in proptest::collection::vec(edit(), 1..60),
            wanted in proptest::array::uniform2(any::<u64>()),
        ) {
            let mut store = MaskStore::new(70);
            for edit in edits {
                apply(&mut store, edit);
            }
            let mut handed = FxHashMap::default();
            let mut repeated = false;
            store.for_each_static_brick(&wanted, |brick, light, bits| {
                repeated |= handed.insert((brick, light), *bits).is_some();
            });
            prop_assert!(!repeated);
            for brick in store.brick_keys() {
                let nodes = store.brick(brick).unwrap();
                for light in 0..70 {
                    let (word, bit) = (light / 64, light % 64);
                    let mut expected = BrickLightBits::default();
                    for slot in 0..BRICK_NODES {
                        let (visible, valid) = store.slot_mask(nodes, slot).static_layer(word);
                        expected.valid[slot / 64] |= (valid >> bit & 1) << (slot % 64);
                        expected.visible[slot / 64] |= ((visible & valid) >> bit & 1) << (slot % 64);
                    }
                    let held = wanted[word] >> bit & 1 == 1 && expected.valid != [0; BRICK_WORDS];
                    prop_assert_eq!(handed.remove(&(brick, light)), held.then_some(expected));
                }
            }
            prop_assert!(handed.is_empty());
        }
    }
}
