//! Stage 4 of an LMM frame, mask fill: the (node, light) bits that the
//! demand asks for and no earlier frame computed, one shadow segment from
//! the node to the light each, in parallel. This is the only place node
//! masks are written.

use rayon::prelude::*;

use super::demand::NodeDemand;
use super::masks::MaskStore;
use super::{LightMesh, LightMeshError, LightMeshStats};
use crate::accel::World;
use crate::render::light::RenderLight;

/// Bits computed for one (node, word) entry.
struct Filled {
    demand: NodeDemand,
    computed: u64,
    visible: u64,
}

impl LightMesh {
    /// Computes the missing bits of `demand`, recording counts in `stats`.
    /// Refuses (before allocating) when the masks would outgrow the memory
    /// limit.
    pub fn fill(
        &mut self,
        demand: &[NodeDemand],
        lights: &[RenderLight],
        world: &World,
        stats: &mut LightMeshStats,
    ) -> Result<(), LightMeshError> {
        self.check_memory(demand, lights.len())?;
        let masks = &self.masks;
        let lattice = self.lattice;
        let filled: Vec<Filled> = demand
            .par_iter()
            .filter_map(|entry| {
                let valid = masks
                    .node(entry.node)
                    .map_or(0, |mask| mask.valid[entry.word as usize]);
                let missing = entry.needed & !valid;
                if missing == 0 {
                    return None;
                }
                let x = lattice.node_position(entry.node);
                let mut visible = 0;
                let mut bits = missing;
                while bits != 0 {
                    let bit = bits.trailing_zeros();
                    bits &= bits - 1;
                    let light = &lights[entry.word as usize * 64 + bit as usize];
                    if !world.occluded(&light.shadow_ray(x)) {
                        visible |= 1 << bit;
                    }
                }
                Some(Filled {
                    demand: *entry,
                    computed: missing,
                    visible,
                })
            })
            .collect();

        let needed: u64 = demand
            .iter()
            .map(|entry| entry.needed.count_ones() as u64)
            .sum();
        let computed: u64 = filled.iter().map(|f| f.computed.count_ones() as u64).sum();
        stats.bits_computed += computed;
        stats.bits_reused += needed - computed;
        // Entries are sorted by node, so a node's words are adjacent.
        stats.nodes_computed += filled
            .windows(2)
            .filter(|pair| pair[0].demand.node != pair[1].demand.node)
            .count() as u64
            + (!filled.is_empty()) as u64;
        for f in filled {
            self.masks
                .set_word(f.demand.node, f.demand.word, f.computed, f.visible);
        }
        stats.nodes_cached = self.masks.nodes_cached() as u64;
        Ok(())
    }

    fn check_memory(&self, demand: &[NodeDemand], lights: usize) -> Result<(), LightMeshError> {
        let mut new_bricks: Vec<_> = demand
            .iter()
            .map(|entry| MaskStore::brick_of(entry.node))
            .filter(|brick| !self.masks.has_brick(*brick))
            .collect();
        new_bricks.sort_unstable_by_key(|brick| brick.to_array());
        new_bricks.dedup();
        let bytes = (self.masks.brick_count() + new_bricks.len()) * MaskStore::brick_bytes(lights);
        if bytes > self.memory_limit {
            return Err(LightMeshError::TooLarge {
                needed_mib: bytes >> 20,
                limit_mib: self.memory_limit >> 20,
                h: self.lattice.h,
            });
        }
        Ok(())
    }
}
