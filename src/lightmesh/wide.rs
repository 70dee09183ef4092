//! Penumbrae wider than the mesh's half-ball.
//!
//! A point finds that it lies in a light's penumbra when the nodes of its
//! half-ball disagree on the light; only then does `penumbra: blocker`
//! size the penumbra by the blocker's distance. `penumbra: wide` (the
//! default) looks further. A lamp's penumbra can be wider than that
//! half-ball's radius kI·h: a point deep inside it, or on its lit side
//! further than kI·h from the hard shadow's edge, has nodes that all agree
//! and kept a hard value. STUDY.md found that this was what kept the
//! street (penumbrae wider than kI·h) above 0.6 of Whitted's error.
//!
//! So a point also asks a wider set: the half-ball of radius 2·kI·h on the
//! lattice of step 2h (every other node of the mesh, about as many nodes
//! as its own half-ball), keeping its nodes as LMM1 keeps a set's (an
//! enclosed node blocked from an asked lamp leaves). Where that set
//! disagrees on a lamp the mesh's half-ball agrees on, the lamp's blocker
//! is found as for a set that disagrees (the blocked node nearest the
//! point comes from the wide set), and a penumbra that wants a level
//! coarser than the mesh's is sized by it; a narrower one the point's own
//! nodes would have seen, so their answer stands.
//!
//! Only lamps are asked (lights with a radius to size a penumbra by). The
//! wide set's nodes are mesh nodes, demanded and filled with the
//! half-ball's for those lamps, so every bit it reads is known and a cached
//! frame finds what a cold one finds. A summary per tile of the wide
//! lattice ([`Agreement`]) settles most points without walking the set.

use std::sync::Arc;

use glam::{IVec3, Vec3};

use super::agreement::{Agreement, TileMemo};
use super::enclosure::leave_out_enclosed;
use super::masks::BrickCache;
use super::sight::Sight;
use super::wide_ball::{lamps, WideBall, STEPS};
use super::LightMesh;
use crate::render::light::RenderLight;

/// One thread's working space for the wide sets of its points.
pub struct WideScratch {
    ball: WideBall,
    /// The frame's lamps ([`lamps`]); none unless points ask their wide
    /// set (`penumbra: wide`).
    lamps: Vec<u64>,
    agreement: Agreement,
    /// The lamps a point's wide set was demanded for, and of those the
    /// ones its own set agrees on, which it asks the wide set about.
    demanded: Vec<u64>,
    asked: Vec<u64>,
    /// The wide set's kept nodes and what they see of the asked lamps.
    nodes: Vec<IVec3>,
    sight: Sight,
    /// The summary's answer for a settled point (unread: a settled wide
    /// set disagrees on nothing).
    settled: Vec<u64>,
    /// The asked lamps the wide set disagrees on.
    mixed: Vec<u64>,
}

impl WideScratch {
    pub fn new(mesh: &LightMesh, lights: &[RenderLight]) -> WideScratch {
        let words = mesh.masks().words();
        let lamps = match mesh.penumbra.asks_wide_set() {
            true => lamps(lights, words),
            false => vec![0; words],
        };
        WideScratch::with(WideBall::of(mesh), lamps, mesh.tile_memo())
    }

    /// Scratch for the wide sets of `ball`, asking about `lamps`,
    /// remembering tiles' summaries in `memo`.
    fn with(ball: WideBall, lamps: Vec<u64>, memo: Arc<TileMemo>) -> WideScratch {
        let words = lamps.len();
        WideScratch {
            ball,
            lamps,
            agreement: Agreement::new((ball.lattice, ball.radius, STEPS), words, memo),
            demanded: vec![0; words],
            asked: vec![0; words],
            nodes: Vec::new(),
            sight: Sight::default(),
            settled: vec![0; words],
            mixed: vec![0; words],
        }
    }

    /// Finds the lamps of `reach` that the point's wide set disagrees on
    /// while its own set agrees on them (every node sees the lamp: a bit
    /// of `all`; none does: not a bit of `any`), for [`Self::mixed`]. The
    /// set was demanded for the point's lamps but the `faint` ones
    /// (`super::faint`), so only those are read: a faint lamp keeps the
    /// point's own set's answer.
    pub fn look(
        &mut self,
        (p, n): (Vec3, Vec3),
        reach: &[u64],
        (all, any, faint): (&[u64], &[u64], &[u64]),
        bricks: &mut BrickCache,
    ) {
        self.mixed.fill(0);
        for word in 0..reach.len() {
            self.demanded[word] = reach[word] & self.lamps[word] & !faint[word];
            self.asked[word] = self.demanded[word] & (all[word] | !any[word]);
        }
        if self.asked.iter().all(|&word| word == 0)
            || (self.agreement).settle(p, &self.asked, bricks, &mut self.settled)
        {
            return;
        }
        self.nodes.clear();
        self.ball.nodes(p, n, &mut self.nodes);
        // The enclosed nodes left out are those blocked from a lamp the
        // wide set was demanded for (another light's bit may be unknown).
        leave_out_enclosed(&mut self.nodes, bricks, &self.demanded);
        self.sight.tally(&self.nodes, &self.asked, bricks);
        for word in 0..reach.len() {
            self.mixed[word] = self.sight.any[word] & !self.sight.all[word];
        }
    }

    /// Word `word` of the lamps the last point [`Self::look`]ed at found
    /// its wide set disagreeing on.
    pub fn mixed(&self, word: usize) -> u64 {
        self.mixed[word]
    }

    /// The wide set's nodes of the last point [`Self::look`] walked, each
    /// with whether it sees light number `light`.
    pub fn seen_from(&self, light: usize) -> impl Iterator<Item = (IVec3, bool)> + '_ {
        self.nodes.iter().copied().zip(self.sight.sees(light))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::lightmesh::lattice::Lattice;
    use crate::lightmesh::masks::MaskStore;

    const H: f32 = 0.1;

    /// Light 0, a lamp, is seen by the mesh's nodes at x ≥ 3 steps; light
    /// 1, no lamp, by the same; light 2, a lamp, by every node.
    fn store() -> MaskStore {
        let mut store = MaskStore::new(3);
        for z in -16..=16 {
            for y in -16..=16 {
                for x in -16..=16 {
                    let node = IVec3::new(x, y, z);
                    store.set(node, 0, x >= 3, Some(false));
                    store.set(node, 1, x >= 3, Some(false));
                    store.set(node, 2, true, Some(false));
                }
            }
        }
        store
    }

    #[test]
    fn a_lamp_edge_beyond_the_half_ball_but_within_the_wide_set_is_found() {
        let store = store();
        let mut bricks = BrickCache::new(&store);
        let mut wide = WideScratch::with(
            WideBall::around(Lattice::new(H), 2.5),
            vec![0b101],
            Arc::default(),
        );
        let reach = [0b111];
        let mesh = Lattice::new(H);
        let up = Vec3::Y;
        let mixed_at = |wide: &mut WideScratch, bricks: &mut BrickCache, x: f32, (all, any)| {
            let p = mesh.origin + Vec3::new(x, 0.3, 0.2) * H;
            wide.look((p, up), &reach, (&[all], &[any], &[0]), bricks);
            wide.mixed(0)
        };
        // 3.5 steps before the edge, the mesh's half-ball (2.5 steps) sees
        // no node of the lamp's and agrees; the wide one (5 steps) does.
        // Light 1 is no lamp and light 2 is seen by all: never mixed.
        assert_eq!(
            mixed_at(&mut wide, &mut bricks, -0.5, (0b100, 0b110)),
            0b001
        );
        assert!(wide.seen_from(0).any(|(_, sees)| sees));
        assert!(wide.seen_from(0).any(|(_, sees)| !sees));
        assert!(wide.seen_from(0).all(|(node, _)| node % 2 == IVec3::ZERO));
        // Where the point's own set disagrees on the lamp, it is not asked.
        assert_eq!(mixed_at(&mut wide, &mut bricks, 1.5, (0b100, 0b111)), 0);
        // Further than the wide radius from the edge: nothing.
        assert_eq!(mixed_at(&mut wide, &mut bricks, -6.5, (0b100, 0b110)), 0);
        // Beyond the edge the lit side agrees too, and the wide set sees
        // back over it.
        assert_eq!(mixed_at(&mut wide, &mut bricks, 6.0, (0b111, 0b111)), 0b001);
        // No lamps, nothing asked (penumbrae of fixed width).
        let mut fixed = WideScratch::with(
            WideBall::around(Lattice::new(H), 2.5),
            vec![0],
            Arc::default(),
        );
        assert_eq!(mixed_at(&mut fixed, &mut bricks, -0.5, (0b100, 0b110)), 0);
    }
}
