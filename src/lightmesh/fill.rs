//! Stage 4 of an LMM frame, mask fill: the (node, light) bits that the
//! demand asks for and are not known, in parallel over bricks. A missing
//! static bit costs a segment from the node to the light against the static
//! structure; where that is clear and the dynamic bit is missing, a second
//! segment against the dynamic objects only. This is the only place node
//! masks are written.

use rayon::prelude::*;

use super::demand::{BrickDemand, Demand};
use super::masks::{join, LayerUpdate, MaskStore, BRICK_NODES};
use super::{LightMesh, LightMeshError, LightMeshStats};
use crate::accel::World;
use crate::render::light::RenderLight;

/// Bits computed for one brick, laid out like the demand's table.
struct FilledBrick {
    update: LayerUpdate,
    nodes: u64,
    bits_needed: u64,
    bits_computed: u64,
}

/// Runs `test` for every set bit of `bits`; returns the bits it said yes to.
fn trace_bits(bits: u64, mut test: impl FnMut(u32) -> bool) -> u64 {
    let mut found = 0;
    let mut remaining = bits;
    while remaining != 0 {
        let bit = remaining.trailing_zeros();
        remaining &= remaining - 1;
        if test(bit) {
            found |= 1 << bit;
        }
    }
    found
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
                self.masks.merge_brick(brick.brick, &filled.update);
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
            update: LayerUpdate::zeroed(demand.needed.len()),
            nodes: 0,
            bits_needed: 0,
            bits_computed: 0,
        };
        for slot in 0..BRICK_NODES {
            let needed = &demand.needed[slot * words..(slot + 1) * words];
            if needed.iter().all(|&word| word == 0) {
                continue;
            }
            let mask = stored.map(|bits| self.masks.slot_mask(bits, slot));
            let x = self.lattice.node_position(join(demand.brick, slot));
            let mut any = false;
            for (word, &needed) in needed.iter().enumerate() {
                let at = slot * words + word;
                let (static_visible, static_valid) = mask.map_or((0, 0), |m| m.static_layer(word));
                let (_, dynamic_valid) = mask.map_or((0, 0), |m| m.dynamic_layer(word));
                let light = |bit: u32| &lights[word * 64 + bit as usize];

                let missing_static = needed & !static_valid;
                let found_static = trace_bits(missing_static, |bit| {
                    !world.occluded_static(&light(bit).shadow_ray(x))
                });
                let open = (static_visible & static_valid) | found_static;
                let missing_dynamic = needed & open & !dynamic_valid;
                let found_dynamic = trace_bits(missing_dynamic, |bit| {
                    world.occluded_dynamic(&light(bit).shadow_ray(x))
                });
                filled.update.static_computed[at] = missing_static;
                filled.update.static_visible[at] = found_static;
                filled.update.dynamic_computed[at] = missing_dynamic;
                filled.update.dynamic_occluded[at] = found_dynamic;

                let computed = missing_static | missing_dynamic;
                filled.bits_needed += needed.count_ones() as u64;
                filled.bits_computed += computed.count_ones() as u64;
                any |= computed != 0;
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
