//! Stage 4 of an LMM frame, mask fill: the (node, light) bits that the
//! demand asks for and are not known, in parallel over bricks. A missing
//! static bit is a segment from the node to the light against the static
//! structure; where that is clear and the dynamic bit is missing, a second
//! segment against the dynamic objects only. This is the CPU backend's
//! fill; the GPU backend's is [`super::segments`], and who else writes
//! the masks is in [`super::masks`].
//!
//! Most of a brick's nodes see a light alike, so a light's missing nodes in
//! a brick are first settled together: if the shaft from their bounding box
//! to the light meets no geometry, every one of them sees it, for the price
//! of one query; otherwise each gets its own segment. (Splitting blocked
//! shafts into octants was measured: more queries than the segments they
//! save.) Shafts only ever settle "nothing in the way", conservatively, so
//! the bits are exactly those the segments give. A blocked segment's
//! triangle is remembered and tried first on the group's next segment; when
//! it hides all eight corners of the group's box from the light, well inside
//! its edges, it hides every node of the group (its shadow volume is
//! convex), and the group is settled blocked at once. A world without dynamic
//! objects settles the dynamic layer without any query.

use rayon::prelude::*;

use super::demand::{BrickDemand, Demand};
use super::masks::{join, LayerUpdate, MaskStore, BRICK_NODES};
use super::{LightMesh, LightMeshError, LightMeshStats};
use glam::Vec3;

use crate::accel::shaft::Shaft;
use crate::accel::{StaticTriangle, World};
use crate::bits::holders_by_bit;
use crate::render::light::RenderLight;

/// Bits computed for one brick, laid out like the demand's table.
struct FilledBrick {
    update: LayerUpdate,
    nodes: u64,
    bits_needed: u64,
    bits_computed: u64,
    work: FillWork,
}

/// What settling bits cost: shaft queries, single segments, and how many of
/// those the remembered occluder answered without a walk.
#[derive(Clone, Copy, Debug, Default)]
struct FillWork {
    shafts: u64,
    segments: u64,
    remembered: u64,
    /// Groups whose box one remembered triangle hides whole.
    hidden_groups: u64,
}

/// Fewer nodes than this are cheaper to trace one by one than by a shaft.
pub(super) const MIN_SHAFT_NODES: usize = 4;

/// The two layers of a mask, each tested against its own geometry.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Layer {
    /// Static visibility: segments against the static structure.
    Static,
    /// Dynamic occlusion: segments against the dynamic objects only.
    Dynamic,
}

impl Layer {
    fn shaft_is_clear(self, world: &World, shaft: &Shaft) -> bool {
        match self {
            Layer::Static => world.shaft_is_clear_static(shaft),
            Layer::Dynamic => world.shaft_is_clear_dynamic(shaft),
        }
    }
}

/// One layer's test for one light word.
struct LayerTest<'a> {
    lights: &'a [RenderLight],
    word: usize,
    world: &'a World,
    layer: Layer,
}

impl LayerTest<'_> {
    /// For each node (positions parallel to `missing`), the lights among its
    /// missing bits whose segment is blocked.
    fn settle(&self, positions: &[Vec3], missing: &[u64], work: &mut FillWork) -> Vec<u64> {
        let mut blocked = vec![0; missing.len()];
        for (bit, members) in holders_by_bit(missing).iter() {
            let light = &self.lights[self.word * 64 + bit];
            self.settle_group(light, 1 << bit, positions, members, &mut blocked, work);
        }
        blocked
    }

    fn settle_group(
        &self,
        light: &RenderLight,
        bit: u64,
        positions: &[Vec3],
        members: &[usize],
        blocked: &mut [u64],
        work: &mut FillWork,
    ) {
        let (min, max) = group_box(members, positions);
        let grouped = members.len() >= MIN_SHAFT_NODES;
        if let (Some(apex), true) = (light.position(), grouped) {
            work.shafts += 1;
            if self
                .layer
                .shaft_is_clear(self.world, &Shaft::new(min, max, apex))
            {
                return;
            }
        }
        // A shadow cache: the brick's nodes sit side by side, so the wall
        // that hides the light from one of them usually hides it from the
        // next; its triangle is tried before the tree is walked, and first
        // against the corners of the group's box, which it may hide whole.
        let mut remembered = None;
        for (order, &i) in members.iter().enumerate() {
            work.segments += 1;
            let ray = light.shadow_ray(positions[i]);
            let occluded = match self.layer {
                Layer::Static => {
                    let occluder = self.world.static_occluder(&ray, remembered);
                    work.remembered += u64::from(occluder.is_some() && occluder == remembered);
                    if let (0, Some(wall), true) = (order, occluder, grouped) {
                        if wall_hides_box(self.world, wall, light, (min, max)) {
                            work.hidden_groups += 1;
                            for &member in members {
                                blocked[member] |= bit;
                            }
                            return;
                        }
                    }
                    remembered = occluder.or(remembered);
                    occluder.is_some()
                }
                Layer::Dynamic => self.world.occluded_dynamic(&ray),
            };
            if occluded {
                blocked[i] |= bit;
            }
        }
    }
}

/// The box of `members`' `positions`: the base of a group's shaft, and
/// what its wall must hide.
pub(super) fn group_box(members: &[usize], positions: &[Vec3]) -> (Vec3, Vec3) {
    (members.iter()).fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &i| {
        (lo.min(positions[i]), hi.max(positions[i]))
    })
}

/// Whether the static triangle `wall` hides the box `min..max` from
/// `light`: it crosses the segments from all eight corners to the light,
/// well inside its edges, so it hides every point of the box (its shadow
/// volume is convex). The fill's wall test, on either backend's fill.
pub(super) fn wall_hides_box(
    world: &World,
    wall: StaticTriangle,
    light: &RenderLight,
    (min, max): (Vec3, Vec3),
) -> bool {
    let corners: [crate::accel::Ray; 8] = std::array::from_fn(|corner| {
        let pick = |axis: usize| (corner >> axis) & 1 == 1;
        let at = Vec3::select(glam::BVec3::new(pick(0), pick(1), pick(2)), max, min);
        light.shadow_ray(at)
    });
    world.static_triangle_hides(wall, &corners)
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
        let mut updates = Vec::new();
        for (brick, filled) in demand.bricks.iter().zip(&filled) {
            stats.nodes_computed += filled.nodes;
            stats.bits_computed += filled.bits_computed;
            stats.bits_reused += filled.bits_needed - filled.bits_computed;
            stats.fill_shafts += filled.work.shafts;
            stats.fill_segments += filled.work.segments;
            stats.fill_remembered += filled.work.remembered;
            stats.fill_hidden_groups += filled.work.hidden_groups;
            if filled.bits_computed > 0 {
                updates.push((brick.brick, &filled.update));
            }
        }
        self.masks.merge_bricks(&updates);
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
        let needed = |slot: usize, word: usize| demand.needed[slot * words + word];
        // From the second frame on, most bricks already hold every bit the
        // frame needs: settle those without building anything.
        if let Some(bits) = stored {
            let complete = (0..BRICK_NODES).all(|slot| {
                let mask = self.masks.slot_mask(bits, slot);
                (0..words).all(|word| needed(slot, word) & !mask.valid(word) == 0)
            });
            if complete {
                return FilledBrick {
                    update: LayerUpdate::zeroed(0),
                    nodes: 0,
                    bits_needed: demand.needed.iter().map(|w| w.count_ones() as u64).sum(),
                    bits_computed: 0,
                    work: FillWork::default(),
                };
            }
        }
        let slots: Vec<usize> = (0..BRICK_NODES)
            .filter(|&slot| (0..words).any(|word| needed(slot, word) != 0))
            .collect();
        let positions: Vec<Vec3> = slots
            .iter()
            .map(|&slot| self.lattice.node_position(join(demand.brick, slot)))
            .collect();
        let layers = |slot: usize, word: usize| {
            stored.map_or(((0, 0), (0, 0)), |bits| {
                let mask = self.masks.slot_mask(bits, slot);
                (mask.static_layer(word), mask.dynamic_layer(word))
            })
        };
        let mut filled = FilledBrick {
            update: LayerUpdate::zeroed(demand.needed.len()),
            nodes: 0,
            bits_needed: 0,
            bits_computed: 0,
            work: FillWork::default(),
        };
        let mut computed_any = vec![false; slots.len()];
        for word in 0..words {
            let missing_static: Vec<u64> = slots
                .iter()
                .map(|&slot| needed(slot, word) & !layers(slot, word).0 .1)
                .collect();
            let static_test = LayerTest {
                lights,
                word,
                world,
                layer: Layer::Static,
            };
            let static_blocked_bits =
                static_test.settle(&positions, &missing_static, &mut filled.work);

            let missing_dynamic: Vec<u64> = slots
                .iter()
                .enumerate()
                .map(|(i, &slot)| {
                    let ((visible, valid), (_, dynamic_valid)) = layers(slot, word);
                    let open = (visible & valid) | (missing_static[i] & !static_blocked_bits[i]);
                    needed(slot, word) & open & !dynamic_valid
                })
                .collect();
            let dynamic_test = LayerTest {
                lights,
                word,
                world,
                layer: Layer::Dynamic,
            };
            let dynamic_blocked_bits = if world.has_dynamic() {
                dynamic_test.settle(&positions, &missing_dynamic, &mut filled.work)
            } else {
                vec![0; slots.len()]
            };

            for (i, &slot) in slots.iter().enumerate() {
                let at = slot * words + word;
                filled.update.static_computed[at] = missing_static[i];
                filled.update.static_visible[at] = missing_static[i] & !static_blocked_bits[i];
                filled.update.dynamic_computed[at] = missing_dynamic[i];
                filled.update.dynamic_occluded[at] = dynamic_blocked_bits[i];
                let computed = missing_static[i] | missing_dynamic[i];
                filled.bits_needed += needed(slot, word).count_ones() as u64;
                filled.bits_computed += computed.count_ones() as u64;
                computed_any[i] |= computed != 0;
            }
        }
        filled.nodes = computed_any.iter().filter(|&&any| any).count() as u64;
        filled
    }

    pub(super) fn check_memory(
        &self,
        demand: &Demand,
        lights: usize,
    ) -> Result<(), LightMeshError> {
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
