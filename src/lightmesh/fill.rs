//! Stage 4 of an LMM frame, mask fill: the (node, light) bits that the
//! demand asks for and no earlier frame computed, one shadow segment from
//! the node to the light each, in parallel over bricks. This is the only
//! place node masks are written.

use rayon::prelude::*;

use super::demand::{BrickDemand, Demand};
use super::masks::{join, MaskStore, BRICK_NODES};
use super::{LightMesh, LightMeshError, LightMeshStats};
use crate::accel::World;
use crate::render::light::RenderLight;

/// Bits computed for one brick, laid out like the demand's table.
struct FilledBrick {
    computed: Box<[u64]>,
    visible: Box<[u64]>,
    nodes: u64,
    bits_needed: u64,
    bits_computed: u64,
}

impl LightMesh {
    /// Computes the missing bits of `demand`, recording counts in `stats`.
    /// Refuses (before allocating) when the masks would outgrow the memory
    /// limit.
    pub fn fill(
        &mut self,
        demand: &Demand,
        lights: &[RenderLight],
        world: &World,
        stats: &mut LightMeshStats,
    ) -> Result<(), LightMeshError> {
        self.check_memory(demand, lights.len())?;
        let filled: Vec<FilledBrick> = demand
            .bricks
            .par_iter()
            .map(|brick| self.fill_brick(brick, demand.words, lights, world))
            .collect();
        for (brick, filled) in demand.bricks.iter().zip(filled) {
            stats.nodes_computed += filled.nodes;
            stats.bits_computed += filled.bits_computed;
            stats.bits_reused += filled.bits_needed - filled.bits_computed;
            if filled.bits_computed > 0 {
                self.masks
                    .merge_brick(brick.brick, &filled.computed, &filled.visible);
            }
        }
        stats.nodes_cached = self.masks.nodes_cached() as u64;
        Ok(())
    }

    fn fill_brick(
        &self,
        demand: &BrickDemand,
        words: usize,
        lights: &[RenderLight],
        world: &World,
    ) -> FilledBrick {
        let stored = self.masks.brick(demand.brick);
        let mut filled = FilledBrick {
            computed: vec![0; demand.needed.len()].into_boxed_slice(),
            visible: vec![0; demand.needed.len()].into_boxed_slice(),
            nodes: 0,
            bits_needed: 0,
            bits_computed: 0,
        };
        for slot in 0..BRICK_NODES {
            let needed = &demand.needed[slot * words..(slot + 1) * words];
            if needed.iter().all(|&word| word == 0) {
                continue;
            }
            let valid = stored.map(|bits| self.masks.slot_mask(bits, slot).valid);
            let x = self.lattice.node_position(join(demand.brick, slot));
            let mut any = false;
            for word in 0..words {
                let missing = needed[word] & !valid.map_or(0, |valid| valid[word]);
                filled.bits_needed += needed[word].count_ones() as u64;
                filled.bits_computed += missing.count_ones() as u64;
                let mut bits = missing;
                while bits != 0 {
                    let bit = bits.trailing_zeros();
                    bits &= bits - 1;
                    if !world.occluded(&lights[word * 64 + bit as usize].shadow_ray(x)) {
                        filled.visible[slot * words + word] |= 1 << bit;
                    }
                }
                filled.computed[slot * words + word] = missing;
                any |= missing != 0;
            }
            filled.nodes += any as u64;
        }
        filled
    }

    fn check_memory(&self, demand: &Demand, lights: usize) -> Result<(), LightMeshError> {
        let bytes = self.bytes_after(demand, lights);
        if bytes > self.memory_limit {
            return Err(self.too_large(bytes));
        }
        Ok(())
    }

    /// Memory the store will hold after filling `demand`, plus the frame's
    /// demand and fill tables.
    fn bytes_after(&self, demand: &Demand, lights: usize) -> usize {
        let new_bricks = demand
            .bricks
            .iter()
            .filter(|brick| self.masks.brick(brick.brick).is_none())
            .count();
        // The store's new bricks plus the frame's demand and fill tables.
        (self.masks.brick_count() + new_bricks) * MaskStore::brick_bytes(lights)
            + demand.bricks.len() * MaskStore::brick_bytes(lights) * 3 / 2
    }
}
