//! The fill (stage 4) as a flat list of node-to-light segments, for a
//! tracer elsewhere: the GPU backend traces them all in one compute pass,
//! where the CPU's fill ([`super::fill`]) settles groups of them with
//! shafts and remembered walls. Those shortcuts only ever settle what the
//! segments would, so either way the masks hold the segments' answers.
//!
//! A segment carries both layers' tests, since the dynamic test depends on
//! the static one: a node blocked by static geometry needs no dynamic bit.
//! The tracer tests the static structure where the static bit is missing,
//! then, where the node is open (its static bit known visible, or just
//! found so) and the dynamic bit is missing, the dynamic objects.

use glam::Vec3;
use rayon::prelude::*;

use super::demand::Demand;
use super::masks::{join, LayerUpdate, BRICK_NODES};
use super::{LightMesh, LightMeshError, LightMeshStats};
use crate::bits::set_bits;

/// One node-to-light segment of the fill.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// The node's position.
    pub origin: Vec3,
    pub light: u32,
    /// The static bit is missing: test the static structure.
    pub test_static: bool,
    /// The static bit is known and visible.
    pub known_visible: bool,
    /// The dynamic bit is missing: test the dynamic objects where the node
    /// is open.
    pub test_dynamic: bool,
}

/// What the tracer found for one segment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SegmentAnswer {
    pub static_blocked: bool,
    /// Whether the dynamic objects were tested (the node was open).
    pub dynamic_tested: bool,
    pub dynamic_blocked: bool,
}

/// A frame's fill as segments, with where each one's bits go.
#[derive(Clone, Debug, Default)]
pub struct SegmentFill {
    pub segments: Vec<Segment>,
    /// Per segment: the demand brick (its index) and the node's slot.
    places: Vec<(u32, u16)>,
}

impl LightMesh {
    /// The segments that fill `demand`'s missing bits, in brick, node and
    /// light order. Refuses (before allocating) when the masks would
    /// outgrow the memory limit.
    pub fn fill_segments(
        &self,
        demand: &Demand,
        lights: usize,
    ) -> Result<SegmentFill, LightMeshError> {
        self.check_memory(demand, lights)?;
        let words = demand.words;
        let per_brick: Vec<SegmentFill> = (demand.bricks.par_iter().enumerate())
            .map(|(index, brick)| {
                let stored = self.masks.brick(brick.brick);
                let mut fill = SegmentFill::default();
                for slot in 0..BRICK_NODES {
                    let mask = stored.map(|bits| self.masks.slot_mask(bits, slot));
                    let origin = self.lattice.node_position(join(brick.brick, slot));
                    for word in 0..words {
                        let needed = brick.needed[slot * words + word];
                        let ((visible, valid), (_, dynamic_valid)) = mask
                            .map_or(((0, 0), (0, 0)), |mask| {
                                (mask.static_layer(word), mask.dynamic_layer(word))
                            });
                        let test_static = needed & !valid;
                        let known_visible = visible & valid;
                        let test_dynamic = needed & (test_static | known_visible) & !dynamic_valid;
                        for bit in set_bits(test_static | test_dynamic) {
                            let at = 1u64 << bit;
                            fill.segments.push(Segment {
                                origin,
                                light: (word * 64 + bit) as u32,
                                test_static: test_static & at != 0,
                                known_visible: known_visible & at != 0,
                                test_dynamic: test_dynamic & at != 0,
                            });
                            fill.places.push((index as u32, slot as u16));
                        }
                    }
                }
                fill
            })
            .collect();
        let mut fill = SegmentFill::default();
        for brick in per_brick {
            fill.segments.extend(brick.segments);
            fill.places.extend(brick.places);
        }
        Ok(fill)
    }

    /// Records the tracer's `answers` (parallel to `fill.segments`) in the
    /// masks, and what the fill did in `stats`, as [`LightMesh::fill`]
    /// records its own.
    pub fn merge_segments(
        &mut self,
        demand: &Demand,
        fill: &SegmentFill,
        answers: &[SegmentAnswer],
        stats: &mut LightMeshStats,
    ) {
        debug_assert_eq!(answers.len(), fill.segments.len());
        let words = demand.words;
        let mut at = 0;
        for (index, brick) in demand.bricks.iter().enumerate() {
            let mut update = LayerUpdate::zeroed(BRICK_NODES * words);
            while let Some(&(owner, slot)) = fill
                .places
                .get(at)
                .filter(|(owner, _)| *owner as usize == index)
            {
                let (segment, answer) = (fill.segments[at], answers[at]);
                debug_assert_eq!(owner as usize, index);
                let light = segment.light as usize;
                let word = slot as usize * words + light / 64;
                let bit = 1u64 << (light % 64);
                if segment.test_static {
                    stats.fill_segments += 1;
                    update.static_computed[word] |= bit;
                    if !answer.static_blocked {
                        update.static_visible[word] |= bit;
                    }
                }
                if answer.dynamic_tested {
                    stats.fill_segments += 1;
                    update.dynamic_computed[word] |= bit;
                    if answer.dynamic_blocked {
                        update.dynamic_occluded[word] |= bit;
                    }
                }
                at += 1;
            }
            let mut computed_bits = 0;
            for slot in 0..BRICK_NODES {
                let range = slot * words..(slot + 1) * words;
                let computed: u64 = (update.static_computed[range.clone()].iter())
                    .zip(&update.dynamic_computed[range])
                    .map(|(s, d)| (s | d).count_ones() as u64)
                    .sum();
                stats.nodes_computed += (computed > 0) as u64;
                computed_bits += computed;
            }
            let needed: u64 = brick.needed.iter().map(|w| w.count_ones() as u64).sum();
            stats.bits_computed += computed_bits;
            stats.bits_reused += needed - computed_bits;
            if computed_bits > 0 {
                self.masks.merge_brick(brick.brick, &update);
            }
        }
        stats.nodes_cached = self.masks.nodes_cached() as u64;
    }
}
