//! Where every node near a shading point agrees on every light, formula
//! (2) needs no half-ball. Most of a frame's points lie far from any shadow
//! edge: each light is seen by all of their nodes or by none, so formula
//! (2) gives the light's whole Omega or nothing. Walking the half-ball and
//! reading its ~32 masks only to learn that costs a light-mesh frame about
//! a third of its shading stage.
//!
//! So the lattice is cut into tiles of 4×4×4 nodes, and for the tile that
//! holds a point's cell, a summary of the nodes *around* it (every node
//! the half-ball of a point in one of the tile's cells can hold) says
//! which lights all of them see and which none of them does. Where each
//! light the point asks for is one or the other, the point takes formula
//! (2)'s value from the summary: every node of its set sees the light
//! (share 1) or none does (share 0), which is what the walk would find, to
//! the bit. Anywhere else the point walks its half-ball as before.
//!
//! Only bits the fill computed count (a node's set holds only such bits for
//! the point's lights), so a summary may see other points' bits: it can
//! only make a point walk, never change what the point gets. Summaries are
//! made as shading meets tiles, per thread and per frame. A tile's own
//! summary reads its 64 nodes' masks, the most of a summary's cost, and on
//! a frame that reuses masks the same tiles are summarised again from the
//! same bits. So those are remembered across frames and threads
//! ([`TileMemo`]), each with the revision of the brick it was read from
//! ([`MaskStore::brick_revision`]), which any edit of the brick's bits or
//! flags changes: a remembered summary is the one the brick's masks give
//! now, and cached frames stay equal to cold ones.
//!
//! [`MaskStore::brick_revision`]: super::masks::MaskStore::brick_revision
//!
//! A summary reads the masks of 27 tiles' nodes at the default kI (more
//! for wider half-balls), a hundred times what one walk reads, so it pays
//! only where many points share a tile. Seen from above, a street's points
//! are sparse: few share a tile, and summaries made for every point cost a
//! fly-through's shading more than the walks they saved (BENCHMARKS.md,
//! "Frames that reuse masks: a count that grew with the store, summaries
//! where points are sparse"). So a tile's summary is made for the
//! [`POINTS_BEFORE_SUMMARY`]th point a thread meets in it; the ones before
//! walk. Which points settle then depends on how threads share the frame,
//! but not what any point gets.

use std::hash::BuildHasher;
use std::sync::{Arc, RwLock, RwLockReadGuard, RwLockWriteGuard};

use glam::{IVec3, Vec3};
use rustc_hash::{FxBuildHasher, FxHashMap};

use super::lattice::{self, Lattice, MAX_NODE_COORDINATE};
use super::masks::{split, BrickCache, BRICK_EDGE};

/// Nodes along each edge of a tile: a divisor of [`BRICK_EDGE`], so a
/// tile lies in one brick.
pub const TILE_EDGE: i32 = 4;
const TILE_SHIFT: i32 = TILE_EDGE.trailing_zeros() as i32;
/// The most mesh steps per step of a summarised lattice (the wide set's):
/// a tile's nodes then still lie in one brick.
const MAX_STEPS: i32 = 2;
const _: () = assert!(BRICK_EDGE % (TILE_EDGE * MAX_STEPS) == 0);

/// The smallest kI for which a half-ball always holds a node of positive
/// weight: its inner ball of radius r/2 (centred r/2 along the normal)
/// holds a node within √3/2·h of its centre, so at least 0.13·h in front
/// of the tangent plane and at most 0.94·r from the point (a smooth weight
/// of 4095·(1 − 0.94²)² ≥ 68). Below it a set may be empty, which formula
/// (1) answers instead; the summary cannot tell, so it is not used there.
pub const SMALLEST_KI: f32 = 2.0;

/// The points that meet a tile before its summary is made, the last of
/// them included: 4 keeps a street seen from the pavement as fast as
/// making every summary at once, and spares a fly-through most of its
/// summaries.
const POINTS_BEFORE_SUMMARY: u32 = 4;

/// Tiles summarised per thread before the summaries are dropped and made
/// again: bounds the memory of a frame's thread.
const CAPACITY: usize = 1 << 14;

/// Per-thread summaries of what tiles, and the nodes around them, agree on.
pub struct Agreement {
    lattice: Lattice,
    /// Mesh steps per step of `lattice`: its node n is the mesh's n·steps.
    steps: i32,
    /// Nodes beyond a point's cell that its half-ball may hold, per side:
    /// the radius in steps rounded down, and one more for the rounding of
    /// the half-ball's bounds.
    margin: i32,
    usable: bool,
    /// Each tile's own 64 nodes.
    own: Summaries,
    /// The nodes around each tile.
    around: Summaries,
    /// Tiles points have met whose summary is not made yet, and how many.
    met: FxHashMap<IVec3, u32>,
    /// Tiles' own summaries from earlier frames and other threads.
    memo: Arc<TileMemo>,
}

impl Agreement {
    /// Summaries for half-balls of `radius` on `lattice`, a lattice of
    /// `steps` mesh steps with the mesh's origin (1: the mesh's own), with
    /// `words` words of light bits, remembering tiles' own summaries in
    /// `memo` (the mesh's, [`LightMesh::tile_memo`]).
    ///
    /// [`LightMesh::tile_memo`]: super::LightMesh::tile_memo
    pub fn new(
        (lattice, radius, steps): (Lattice, f32, i32),
        words: usize,
        memo: Arc<TileMemo>,
    ) -> Agreement {
        assert!(
            (1..=MAX_STEPS).contains(&steps) && MAX_STEPS % steps == 0,
            "a tile of {steps}-step nodes would straddle bricks"
        );
        // In steps, as `Lattice::half_ball` rounds it.
        let reach = radius / lattice.h;
        Agreement {
            lattice,
            steps,
            margin: reach.floor() as i32 + 1,
            usable: reach >= SMALLEST_KI,
            own: Summaries::new(words),
            around: Summaries::new(words),
            met: FxHashMap::default(),
            memo,
        }
    }

    /// Whether every node of the set of the point at `p` agrees on every
    /// light of `reach`, by the summary of the nodes around it; if so,
    /// `seen` gets the lights of `reach` that they all see (the others
    /// none of them sees). The masks are read through `bricks`. A point
    /// that asks for no light needs no summary: every light it asks for
    /// (none) is seen by all of its nodes or by none, and its set is not
    /// empty where summaries are usable.
    pub fn settle(
        &mut self,
        p: Vec3,
        reach: &[u64],
        bricks: &mut BrickCache,
        seen: &mut [u64],
    ) -> bool {
        if !self.usable {
            return false;
        }
        if reach.iter().all(|&asked| asked == 0) {
            seen.fill(0);
            return true;
        }
        let cell = lattice::floor(self.lattice.local(p));
        if !cell.is_finite() || cell.abs().max_element() >= MAX_NODE_COORDINATE {
            return false; // too far out for node coordinates
        }
        let tile = cell.as_ivec3() >> TILE_SHIFT;
        let Some(around) = self.around(tile, bricks) else {
            return false;
        };
        let summary = self.around.get(around);
        for (word, &asked) in reach.iter().enumerate() {
            let all = summary.seen_by_all(word);
            // A node inside closed geometry that hides a light leaves the
            // set (see `interpolate`), which a light hidden from every node
            // cannot tell from the summary: a set of such nodes alone would
            // be empty. Lights every node sees keep every node in it.
            let none = match summary.enclosed {
                true => 0,
                false => summary.seen_by_none(word),
            };
            if asked & !(all | none) != 0 {
                return false;
            }
            seen[word] = asked & all;
        }
        true
    }

    /// Where the summary of the nodes around `tile` is, made first if
    /// enough points met the tile (None before): those of the tiles
    /// holding every node a half-ball of a point in one of the tile's cells
    /// may hold.
    fn around(&mut self, tile: IVec3, bricks: &mut BrickCache) -> Option<usize> {
        if let Some(at) = self.around.find(tile) {
            return Some(at);
        }
        if self.met.len() >= CAPACITY {
            self.met.clear();
        }
        let met = self.met.entry(tile).or_default();
        *met += 1;
        if *met < POINTS_BEFORE_SUMMARY {
            return None;
        }
        self.met.remove(&tile);
        if self.around.len() >= CAPACITY || self.own.len() >= CAPACITY {
            self.around.clear();
            self.own.clear();
        }
        let first = (tile * TILE_EDGE - IVec3::splat(self.margin)) >> TILE_SHIFT;
        let last = ((tile + IVec3::ONE) * TILE_EDGE + IVec3::splat(self.margin)) >> TILE_SHIFT;
        let at = self.around.insert(tile);
        for z in first.z..=last.z {
            for y in first.y..=last.y {
                for x in first.x..=last.x {
                    let near = self.own(IVec3::new(x, y, z), bricks);
                    self.around.absorb(at, &self.own, near);
                }
            }
        }
        Some(at)
    }

    /// Where the summary of `tile`'s own nodes is, made first if need be:
    /// recalled from the memo where it holds the summary of the brick's
    /// current revision, else read. They lie in one brick, read with one
    /// lookup.
    fn own(&mut self, tile: IVec3, bricks: &mut BrickCache) -> usize {
        if let Some(at) = self.own.find(tile) {
            return at;
        }
        let at = self.own.insert(tile);
        let (brick, first) = split(tile * TILE_EDGE * self.steps);
        let Some(view) = bricks.view(brick) else {
            return at;
        };
        let key = MemoKey {
            tile,
            steps: self.steps,
            store: bricks.store_id(),
            revision: view.revision(),
        };
        if self.memo.recall(&key, &mut self.own, at) {
            return at;
        }
        let step = self.steps as usize;
        let edge = BRICK_EDGE as usize;
        for z in 0..TILE_EDGE as usize {
            for y in 0..TILE_EDGE as usize {
                let row = first + step * (z * edge + y) * edge;
                for slot in (row..).step_by(step).take(TILE_EDGE as usize) {
                    let mask = view.mask(slot);
                    let enclosed = view.is_enclosed(slot);
                    self.own
                        .add_node(at, enclosed, |word| (mask.visible(word), mask.valid(word)));
                }
            }
        }
        self.memo.remember(key, self.own.get(at));
        at
    }
}

/// Shards of the memo: threads remembering tiles seldom wait on each other.
const MEMO_SHARD_BITS: u32 = 6;
const MEMO_SHARDS: usize = 1 << MEMO_SHARD_BITS;
/// Tiles remembered per shard before it is emptied: bounds the memo at
/// half a million tiles, some 50 MB with 64 lights, over a fly-through
/// whose frames meet ever more tiles.
const MEMO_SHARD_CAPACITY: usize = 1 << 13;

/// Tiles' own summaries, kept across frames and threads by the light mesh
/// (see the module's comment): each under its tile, its lattice's steps,
/// and the store and the brick revision it was read from.
#[derive(Debug)]
pub struct TileMemo {
    shards: [RwLock<Shard>; MEMO_SHARDS],
}

/// One shard's summaries, by tile and lattice steps.
type Shard = FxHashMap<(IVec3, i32), Remembered>;

/// What a remembered summary was read from.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct MemoKey {
    tile: IVec3,
    steps: i32,
    store: u64,
    revision: u64,
}

/// One tile's own summary, and the store and brick revision it holds for.
#[derive(Debug)]
struct Remembered {
    store: u64,
    revision: u64,
    bits: Box<[u64]>,
    enclosed: bool,
}

impl Default for TileMemo {
    fn default() -> TileMemo {
        TileMemo {
            shards: std::array::from_fn(|_| RwLock::default()),
        }
    }
}

impl TileMemo {
    fn shard(&self, tile: IVec3) -> &RwLock<Shard> {
        // Fx hashes mix into their high bits.
        let hash = FxBuildHasher.hash_one(tile);
        &self.shards[(hash >> (u64::BITS - MEMO_SHARD_BITS)) as usize]
    }

    /// The shard of `tile`, to read. A thread that panicked holding a
    /// shard left it whole (each edit is one insert or clear), so a
    /// poisoned lock is taken as it is.
    fn read(&self, tile: IVec3) -> RwLockReadGuard<'_, Shard> {
        self.shard(tile).read().unwrap_or_else(|e| e.into_inner())
    }

    /// The shard of `tile`, to edit, as [`TileMemo::read`] takes it.
    fn write(&self, tile: IVec3) -> RwLockWriteGuard<'_, Shard> {
        self.shard(tile).write().unwrap_or_else(|e| e.into_inner())
    }

    /// Copies the summary remembered for `key` into `into`'s summary
    /// `at`; false, leaving it, where none is remembered for that store
    /// and revision.
    fn recall(&self, key: &MemoKey, into: &mut Summaries, at: usize) -> bool {
        let shard = self.read(key.tile);
        match shard.get(&(key.tile, key.steps)) {
            Some(held) if (held.store, held.revision) == (key.store, key.revision) => {
                into.set(at, &held.bits, held.enclosed);
                true
            }
            _ => false,
        }
    }

    /// Summaries remembered, in all shards.
    #[cfg(test)]
    fn len(&self) -> usize {
        (self.shards.iter())
            .map(|shard| shard.read().unwrap_or_else(|e| e.into_inner()).len())
            .sum()
    }

    /// Remembers `summary`, read under `key`.
    fn remember(&self, key: MemoKey, summary: Summary) {
        let mut shard = self.write(key.tile);
        if shard.len() >= MEMO_SHARD_CAPACITY {
            shard.clear();
        }
        let held = Remembered {
            store: key.store,
            revision: key.revision,
            bits: summary.bits.into(),
            enclosed: summary.enclosed,
        };
        shard.insert((key.tile, key.steps), held);
    }
}

/// Summaries of sets of nodes, by tile: per light word, the lights every
/// node sees and those none sees (counting only bits that are known), and
/// whether a node lies inside closed geometry.
struct Summaries {
    words: usize,
    index: FxHashMap<IVec3, usize>,
    /// Per summary, `words` words of lights all see, then `words` of
    /// lights none sees.
    bits: Vec<u64>,
    enclosed: Vec<bool>,
}

/// One summary, read.
struct Summary<'a> {
    bits: &'a [u64],
    enclosed: bool,
}

impl Summary<'_> {
    fn seen_by_all(&self, word: usize) -> u64 {
        self.bits[word]
    }

    fn seen_by_none(&self, word: usize) -> u64 {
        self.bits[self.bits.len() / 2 + word]
    }
}

impl Summaries {
    fn new(words: usize) -> Summaries {
        Summaries {
            words,
            index: FxHashMap::default(),
            bits: Vec::new(),
            enclosed: Vec::new(),
        }
    }

    fn len(&self) -> usize {
        self.enclosed.len()
    }

    fn clear(&mut self) {
        self.index.clear();
        self.bits.clear();
        self.enclosed.clear();
    }

    fn find(&self, tile: IVec3) -> Option<usize> {
        self.index.get(&tile).copied()
    }

    /// A summary of no nodes yet: every light counts as seen by all and by
    /// none until a node says otherwise.
    fn insert(&mut self, tile: IVec3) -> usize {
        let at = self.len();
        self.index.insert(tile, at);
        self.bits.resize(self.bits.len() + 2 * self.words, !0);
        self.enclosed.push(false);
        at
    }

    /// Sets summary `at` to `bits` and `enclosed`, as [`Self::get`] reads
    /// them.
    fn set(&mut self, at: usize, bits: &[u64], enclosed: bool) {
        self.bits[2 * self.words * at..2 * self.words * (at + 1)].copy_from_slice(bits);
        self.enclosed[at] = enclosed;
    }

    fn get(&self, at: usize) -> Summary<'_> {
        Summary {
            bits: &self.bits[2 * self.words * at..2 * self.words * (at + 1)],
            enclosed: self.enclosed[at],
        }
    }

    /// Adds a node to summary `at`: `bits(word)` gives its visible and its
    /// valid lights of that word.
    fn add_node(&mut self, at: usize, enclosed: bool, bits: impl Fn(usize) -> (u64, u64)) {
        let words = self.words;
        let summary = &mut self.bits[2 * words * at..2 * words * (at + 1)];
        for word in 0..words {
            let (visible, valid) = bits(word);
            summary[word] &= visible | !valid;
            summary[words + word] &= !visible | !valid;
        }
        self.enclosed[at] |= enclosed;
    }

    /// Adds every node of `from`'s summary `near` to summary `at`.
    fn absorb(&mut self, at: usize, from: &Summaries, near: usize) {
        let words = self.words;
        let near = from.get(near);
        let summary = &mut self.bits[2 * words * at..2 * words * (at + 1)];
        for (into, bits) in summary.iter_mut().zip(near.bits) {
            *into &= bits;
        }
        self.enclosed[at] |= near.enclosed;
    }
}

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::lightmesh::enclosure::leave_out_enclosed;
    use crate::lightmesh::masks::{split, BrickEnclosure, MaskStore};

    const H: f32 = 0.1;
    /// Lights of the test store, in two words: seen everywhere (but from
    /// inside the enclosed block), seen beyond a plane x = 3 steps, hidden
    /// everywhere, hidden by a dynamic object on the plane z = 1.
    const LIGHTS: [usize; 4] = [0, 1, 66, 67];
    const ENCLOSED_BELOW_Y: i32 = -6;

    fn store() -> MaskStore {
        let mut store = MaskStore::new(70);
        for z in -16..=16 {
            for y in -16..=16 {
                for x in -16..=16 {
                    let node = IVec3::new(x, y, z);
                    let inside = y <= ENCLOSED_BELOW_Y;
                    store.set(node, 0, !inside, Some(false));
                    store.set(node, 1, x >= 3, Some(false));
                    store.set(node, 66, false, None);
                    store.set(node, 67, true, Some(z == 1));
                    if inside {
                        let (brick, slot) = split(node);
                        let mut flags = BrickEnclosure::default();
                        flags.known[slot / 64] = 1 << (slot % 64);
                        flags.enclosed[slot / 64] = 1 << (slot % 64);
                        store.merge_enclosure(brick, &flags);
                    }
                }
            }
        }
        store
    }

    /// What walking the point's set finds, as `interpolate` walks it: the
    /// lights of `reach` every node sees and those some node sees, or None
    /// for an empty set. The set is a half-ball on `lattice`, a lattice of
    /// `steps` mesh steps.
    fn walked(
        (lattice, steps): (Lattice, i32),
        radius: f32,
        bricks: &mut BrickCache,
        (p, n): (Vec3, Vec3),
        reach: &[u64],
    ) -> Option<(Vec<u64>, Vec<u64>)> {
        let mut nodes = Vec::new();
        lattice.half_ball(p, n, radius, &mut nodes);
        for node in &mut nodes {
            *node *= steps;
        }
        leave_out_enclosed(&mut nodes, bricks, reach);
        let mut all = reach.to_vec();
        let mut any = vec![0; reach.len()];
        for &node in &nodes {
            let mask = bricks.mask(node).expect("every node of the test has bits");
            for word in 0..reach.len() {
                assert_eq!(mask.valid(word) & reach[word], reach[word]);
                let seen = mask.visible(word) & reach[word];
                all[word] &= seen;
                any[word] |= seen;
            }
        }
        (!nodes.is_empty()).then_some((all, any))
    }

    /// Points inside the filled block: on nodes, on lattice planes, deep
    /// in the enclosed block (whose sets may be empty), in the first cells
    /// of a tile whose half-balls just reach back over the edge at x = 3
    /// into the tile before, and
    /// anywhere; with normals of every kind (axis-aligned ones put whole
    /// layers of nodes on the tangent plane).
    fn points(lattice: Lattice, count: usize) -> Vec<(Vec3, Vec3)> {
        let mut state = 0x9e37_79b9_7f4a_7c15u64;
        let mut uniform = move || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        (0..count)
            .map(|i| {
                let mut local = Vec3::new(uniform(), uniform(), uniform()) * 10.0 - 5.0;
                match i % 8 {
                    0 => local = local.round(),
                    1 => local.x = local.x.round(),
                    2 => local.y = -9.0 + uniform() - 0.5,
                    3 => local.x = 4.0 + 0.5 * uniform(),
                    _ => {}
                }
                let n = match i % 5 {
                    0 => Vec3::Y,
                    1 => -Vec3::X,
                    2 => Vec3::X,
                    _ => (Vec3::new(uniform(), uniform(), uniform()) - 0.5).normalize_or(Vec3::Z),
                };
                (lattice.origin + local * lattice.h, n)
            })
            .collect()
    }

    fn reach_of(i: usize) -> [u64; 2] {
        let mut reach = [0; 2];
        for (k, &light) in LIGHTS.iter().enumerate() {
            if (i >> k) & 1 == 1 {
                reach[light / 64] |= 1 << (light % 64);
            }
        }
        reach
    }

    #[test]
    fn a_settled_point_gets_what_walking_its_set_finds() {
        let store = store();
        let mesh = Lattice::new(H);
        // One memo for both lattices, as a mesh's scratch shares it.
        let memo = Arc::<TileMemo>::default();
        // The mesh's own half-balls, and the wide set's (`super::wide`):
        // every other node, twice the radius.
        for steps in [1, 2] {
            let lattice = Lattice {
                origin: mesh.origin,
                h: H * steps as f32,
            };
            let radius = 2.5 * lattice.h;
            let memo = Arc::clone(&memo);
            let mut agreement = Agreement::new((lattice, radius, steps), store.words(), memo);
            let mut bricks = BrickCache::new(&store);
            let (mut settled, mut walked_only) = (0, 0);
            let points = points(lattice, 4000).into_iter().map(|(p, n)| {
                // The same mesh cells for both lattices.
                (mesh.origin + (p - mesh.origin) / steps as f32, n)
            });
            for (i, point) in points.enumerate() {
                let reach = reach_of(i % 16);
                let mut seen = [0; 2];
                let walk = walked((lattice, steps), radius, &mut bricks, point, &reach);
                if agreement.settle(point.0, &reach, &mut bricks, &mut seen) {
                    settled += 1;
                    let (all, any) = walk.expect("a settled point's set is never empty");
                    assert_eq!(all, any, "{point:?}: its nodes disagree");
                    assert_eq!(seen.to_vec(), all, "{point:?}");
                } else {
                    walked_only += 1;
                }
            }
            // Both ways are taken: points near the edge at x = 3, the plane
            // z = 1 or the enclosed block walk; the others are settled
            // (fewer of the wide sets, which reach further).
            assert!(
                settled > 400 && walked_only > 400,
                "{steps} steps: {settled} / {walked_only}"
            );
        }
    }

    #[test]
    fn remembered_summaries_hold_until_their_brick_is_edited() {
        let mut store = store();
        let lattice = Lattice::new(H);
        let memo = Arc::<TileMemo>::default();
        // Light 0, which every node around the point sees.
        let reach = reach_of(0b0001);
        let point = lattice.origin + Vec3::new(-6.5, 0.5, 0.5) * H;
        let settle = |store: &MaskStore| {
            let memo = Arc::clone(&memo);
            let mut agreement = Agreement::new((lattice, 2.5 * H, 1), store.words(), memo);
            let mut bricks = BrickCache::new(store);
            let mut seen = [0; 2];
            let settled = (0..POINTS_BEFORE_SUMMARY)
                .map(|_| agreement.settle(point, &reach, &mut bricks, &mut seen))
                .last();
            (settled, seen)
        };
        assert_eq!(settle(&store), (Some(true), reach));
        let remembered = memo.len();
        assert!(remembered > 0);
        // A later frame's scratch recalls them: the same answer, nothing
        // read again.
        assert_eq!(settle(&store), (Some(true), reach));
        assert_eq!(memo.len(), remembered);
        // A node beside the point loses sight of the light: its brick's
        // summary from before is not recalled, and the point walks.
        store.set(IVec3::new(-6, 1, 0), 0, false, Some(false));
        assert_eq!(settle(&store).0, Some(false));
    }

    #[test]
    fn a_tiles_summary_waits_for_points_enough() {
        let store = store();
        let lattice = Lattice::new(H);
        let mut bricks = BrickCache::new(&store);
        let mut agreement = Agreement::new((lattice, 2.5 * H, 1), store.words(), Arc::default());
        let reach = reach_of(0b0101);
        // Points a tile apart, as far from the camera: each walks, and no
        // summary is made.
        for x in 0..100 {
            let point = lattice.origin + Vec3::new(0.5 + 4.0 * x as f32, 0.5, 0.5) * H;
            assert!(!agreement.settle(point, &reach, &mut bricks, &mut [0; 2]));
        }
        assert_eq!((agreement.own.len(), agreement.around.len()), (0, 0));
        // Points enough in the first tile get its summary.
        let beside = lattice.origin + Vec3::new(1.5, 0.5, 0.5) * H;
        for _ in 2..POINTS_BEFORE_SUMMARY {
            assert!(!agreement.settle(beside, &reach, &mut bricks, &mut [0; 2]));
        }
        assert!(agreement.settle(beside, &reach, &mut bricks, &mut [0; 2]));
        assert_eq!(agreement.around.len(), 1);
    }

    #[test]
    fn summaries_dropped_at_capacity_are_made_again_alike() {
        let store = store();
        let lattice = Lattice::new(H);
        let mut bricks = BrickCache::new(&store);
        let mut agreement = Agreement::new((lattice, 2.5 * H, 1), store.words(), Arc::default());
        let far = lattice.origin + Vec3::new(0.5, 0.5, 0.5) * H;
        let reach = reach_of(0b0101);
        let mut first = [0; 2];
        for _ in 1..POINTS_BEFORE_SUMMARY {
            assert!(!agreement.settle(far, &reach, &mut bricks, &mut first));
        }
        assert!(agreement.settle(far, &reach, &mut bricks, &mut first));
        // Fill the caches with tiles of other points until they are dropped.
        for x in 0..CAPACITY as i32 + 1 {
            let elsewhere = lattice.origin + Vec3::new(x as f32 * 4.0, 400.0, 0.0) * H;
            for _ in 0..POINTS_BEFORE_SUMMARY {
                agreement.settle(elsewhere, &reach, &mut bricks, &mut [0; 2]);
            }
        }
        assert!(agreement.own.len() <= CAPACITY + 64 && agreement.around.len() <= CAPACITY);
        assert!(agreement.met.len() <= CAPACITY);
        let mut again = [0; 2];
        for _ in 1..POINTS_BEFORE_SUMMARY {
            agreement.settle(far, &reach, &mut bricks, &mut again);
        }
        assert!(agreement.settle(far, &reach, &mut bricks, &mut again));
        assert_eq!(first, again);
        assert_eq!(first, [1, 0]);
    }

    #[test]
    fn a_point_that_asks_for_no_light_settles_without_a_summary() {
        let store = store();
        let lattice = Lattice::new(H);
        let mut bricks = BrickCache::new(&store);
        let inside = lattice.origin + Vec3::new(0.5, 0.5, 0.5) * H;
        let mut agreement = Agreement::new((lattice, 2.5 * H, 1), store.words(), Arc::default());
        let mut seen = [7; 2];
        assert!(agreement.settle(inside, &[0; 2], &mut bricks, &mut seen));
        assert_eq!(seen, [0, 0]);
        let made = (
            agreement.own.len(),
            agreement.around.len(),
            agreement.met.len(),
        );
        assert_eq!(made, (0, 0, 0), "no tile was met or summarised");
        // Below kI = 2 its set may be empty: formula (1) decides.
        let mut small = Agreement::new((lattice, 1.9 * H, 1), store.words(), Arc::default());
        assert!(!small.settle(inside, &[0; 2], &mut bricks, &mut [0; 2]));
    }

    #[test]
    fn small_radii_and_points_beyond_the_lattice_always_walk() {
        let store = store();
        let lattice = Lattice::new(H);
        let mut bricks = BrickCache::new(&store);
        let reach = reach_of(0b0001);
        let inside = lattice.origin + Vec3::new(0.5, 0.5, 0.5) * H;
        // Below kI = 2 a half-ball may hold no node: formula (1) decides.
        let mut small = Agreement::new((lattice, 1.9 * H, 1), store.words(), Arc::default());
        assert!(!small.settle(inside, &reach, &mut bricks, &mut [0; 2]));
        let mut agreement = Agreement::new((lattice, 2.5 * H, 1), store.words(), Arc::default());
        for _ in 1..POINTS_BEFORE_SUMMARY {
            agreement.settle(inside, &reach, &mut bricks, &mut [0; 2]);
        }
        assert!(agreement.settle(inside, &reach, &mut bricks, &mut [0; 2]));
        for beyond in [
            Vec3::splat(1e30),
            Vec3::new(f32::NAN, 0.0, 0.0),
            Vec3::splat(f32::INFINITY),
        ] {
            assert!(!agreement.settle(beyond, &reach, &mut bricks, &mut [0; 2]));
        }
    }
}
