//! What the nodes of a set see of the lights a point asks about: the
//! tally that formula (2)'s interpolation set (`super::interpolate`) and
//! the wide set (`super::wide`) both make of the masks, kept apart from
//! either so that neither imports the other for it.

use glam::IVec3;

use super::masks::BrickCache;

/// What the nodes of a set see of the lights asked about.
#[derive(Default)]
pub struct Sight {
    /// The visible-light words of each node, node after node.
    pub visible: Vec<u64>,
    /// Per light word: lights visible from every node, from some node.
    pub all: Vec<u64>,
    pub any: Vec<u64>,
}

impl Sight {
    /// What `nodes` see of the lights `asked`, read through `bricks`;
    /// every bit it reads was filled from the frame's demand.
    pub fn tally(&mut self, nodes: &[IVec3], asked: &[u64], bricks: &mut BrickCache) {
        self.visible.clear();
        self.all.clear();
        self.all.extend_from_slice(asked);
        self.any.clear();
        self.any.resize(asked.len(), 0);
        for &node in nodes {
            let mask = bricks.mask(node);
            for (word, &asked) in asked.iter().enumerate() {
                debug_assert_eq!(
                    mask.map_or(0, |m| m.valid(word)) & asked,
                    asked,
                    "formula (2) read a mask bit that the fill stage did not compute"
                );
                let seen = mask.map_or(0, |m| m.visible(word)) & asked;
                self.visible.push(seen);
                self.all[word] &= seen;
                self.any[word] |= seen;
            }
        }
    }

    /// Whether each node, in order, sees light number `light`.
    pub fn sees(&self, light: usize) -> impl Iterator<Item = bool> + '_ {
        let words = self.all.len();
        let (word, bit) = (light / 64, light % 64);
        (self.visible.iter().skip(word).step_by(words)).map(move |&seen| seen >> bit & 1 == 1)
    }
}
