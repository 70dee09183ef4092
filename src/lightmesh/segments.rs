//! The fill (stage 4) as a flat list of node-to-light segments, for a
//! tracer elsewhere: the GPU backend traces them in one compute pass.
//!
//! As in the CPU's fill ([`super::fill`]), a light's missing nodes in a
//! brick are first settled together where the shaft from their box to the
//! light meets no geometry: every one of them sees it (shafts settle only
//! "nothing in the way", conservatively, so the bits are those the
//! segments would give). Where the shaft is blocked, the triangle that
//! blocks the first node's segment (one CPU ray) may hide the group's
//! whole box from the light, well inside its edges: then none of them
//! sees it. The segments that remain carry both layers' tests,
//! since the dynamic test depends on the static one: a node blocked by
//! static geometry needs no dynamic bit. The tracer tests the static
//! structure where the static bit is missing, then, where the node is
//! open (its static bit known visible, or just found so) and the dynamic
//! bit is missing, the dynamic objects.
//!
//! Shafts cost the CPU time while they save the tracer segments
//! ([`Shafts`] turns them off; the bits are the same either way). On
//! lavapipe, whose tracing is the CPU's own cores, they pay: the city
//! fly-through's steady frames without them spend about 40% less in the
//! CPU's fill stage but trace a third to a half more segments and render
//! 14–39% slower (BENCHMARKS.md). Whether a real GPU, whose tracing does
//! not take the CPU's cores, is faster without them has not been
//! measured; `benches/device_check.sh` measures it.

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::demand::{BrickDemand, Demand};
use super::fill::{group_box, wall_hides_box, MIN_SHAFT_NODES};
use super::masks::{join, LayerUpdate, UpdateRows, BRICK_NODES};
use super::{LightMesh, LightMeshError, LightMeshStats};
use crate::accel::shaft::Shaft;
use crate::accel::World;
use crate::bits::{holders_by_bit, set_bits};
use crate::render::light::RenderLight;

/// Whether [`LightMesh::fill_segments`] settles groups of a light's nodes
/// by shafts before making their segments.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shafts {
    /// Test a shaft per light and brick; a clear one settles its nodes,
    /// and so does a wall that hides their box from the light.
    Test,
    /// Make a segment for every missing bit.
    Skip,
}

/// One node-to-light segment of the fill.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Segment {
    /// The node's slot in its brick (the tracer places it on the lattice).
    pub node: u16,
    pub light: u32,
    /// The static bit is missing: test the static structure.
    pub test_static: bool,
    /// The static bit is known and visible.
    pub known_visible: bool,
    /// The dynamic bit is missing: test the dynamic objects where the node
    /// is open.
    pub test_dynamic: bool,
    /// The dynamic bit is known and occluded (where it is not missing):
    /// with the answer, what the bit's visibility is once it is filled,
    /// which a tracer that writes the masks in place needs.
    pub known_occluded: bool,
}

impl Segment {
    /// Whether the node sees the light once the segment's `answer` is in:
    /// the static layer open and no dynamic object in the way, as
    /// [`super::masks::NodeMask::visible`] folds the two layers (the bit
    /// is then valid, as the fill leaves every bit it is given).
    pub fn sees(&self, answer: &SegmentAnswer) -> bool {
        let open = if self.test_static {
            !answer.static_blocked
        } else {
            self.known_visible
        };
        let occluded = if self.test_dynamic {
            answer.dynamic_blocked
        } else {
            self.known_occluded
        };
        open && !occluded
    }
}

/// What the tracer found for one segment.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct SegmentAnswer {
    pub static_blocked: bool,
    /// Whether the dynamic objects were tested (the node was open).
    pub dynamic_tested: bool,
    pub dynamic_blocked: bool,
}

/// Where a bit of a brick's fill goes: the node's slot and the light.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct Place {
    slot: u16,
    light: u32,
}

impl Place {
    /// The word and the bit that this place's bit is in a brick's update
    /// whose rows are `slots` (which hold this place's).
    fn locate(&self, slots: &[usize], words: usize) -> (usize, u64) {
        let row = (slots.binary_search(&(self.slot as usize)))
            .expect("the update has a row for each place");
        let light = self.light as usize;
        (row * words + light / 64, 1 << (light % 64))
    }
}

impl From<&Segment> for Place {
    fn from(segment: &Segment) -> Place {
        Place {
            slot: segment.node,
            light: segment.light,
        }
    }
}

/// A frame's fill: per demanded brick (in the demand's order), the bits
/// shafts and walls settled and the segments left for the tracer. Kept
/// brick by brick, so that the tracer's records are made and the answers
/// merged in parallel, without one list of every segment in between
/// (tens of millions on a cold frame of many lamps).
///
/// A brick's segments go light by light, each light's in slot order, so
/// that neighbouring threads of the tracer (a row of the brick's nodes)
/// trace nearly the same path through the scene towards one light, where
/// node by node they set off towards every light in turn: on lavapipe's
/// eight-wide lanes that made the city fly-through's fill trace about
/// twice as fast (BENCHMARKS.md, "The fill in light order").
#[derive(Clone, Debug, Default)]
pub struct SegmentFill {
    bricks: Vec<BrickFill>,
    shafts: u64,
    hidden_groups: u64,
}

/// One brick's part of a [`SegmentFill`].
#[derive(Clone, Debug, Default)]
struct BrickFill {
    segments: Vec<Segment>,
    /// Static bits a clear shaft settled visible, static bits a wall
    /// settled blocked (a group's, or the one node whose segment found
    /// the wall), and dynamic bits a clear shaft settled unblocked.
    static_clear: Vec<Place>,
    static_hidden: Vec<Place>,
    dynamic_clear: Vec<Place>,
    shafts: u64,
    hidden_groups: u64,
}

/// How the CPU settled a group of a light's missing static bits in a
/// brick.
enum Group {
    /// The shaft from their box to the light meets nothing: all see it.
    Clear,
    /// The first node's occluder hides their whole box: none sees it.
    Hidden,
    /// The first node's segment is blocked, by a wall that does not hide
    /// the box: the others need a segment each.
    FirstBlocked,
    /// Neither: a segment each.
    Mixed,
}

impl SegmentFill {
    /// The segments, in brick, light and node order, each as `record`
    /// makes it for the tracer from the brick's index (in the demand's
    /// order) and the segment.
    pub fn records<T: Send>(&self, record: impl Fn(usize, &Segment) -> T + Sync + Send) -> Vec<T> {
        (self.bricks.par_iter().enumerate())
            .flat_map_iter(|(index, brick)| {
                let record = &record;
                (brick.segments.iter()).map(move |segment| record(index, segment))
            })
            .collect()
    }

    /// How many segments there are.
    pub fn len(&self) -> usize {
        self.bricks.iter().map(|brick| brick.segments.len()).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// One light word of one brick's missing bits, node by node.
struct WordBits {
    test_static: Vec<u64>,
    known_visible: Vec<u64>,
    test_dynamic: Vec<u64>,
    known_occluded: Vec<u64>,
}

impl LightMesh {
    /// The fill of `demand`'s missing bits: groups settled by shafts
    /// where `shafts` says so, and a segment for each bit left, in brick,
    /// light and node order (see [`SegmentFill`]). Refuses (before
    /// allocating) when the masks would outgrow the memory limit.
    pub fn fill_segments(
        &self,
        demand: &Demand,
        lights: &[RenderLight],
        world: &World,
        shafts: Shafts,
    ) -> Result<SegmentFill, LightMeshError> {
        self.check_memory(demand, lights.len())?;
        let bricks: Vec<BrickFill> = (demand.bricks.par_iter())
            .map(|brick| self.brick_segments(brick, demand.words, (lights, world), shafts))
            .collect();
        let shafts = bricks.iter().map(|brick| brick.shafts).sum();
        let hidden_groups = bricks.iter().map(|brick| brick.hidden_groups).sum();
        Ok(SegmentFill {
            bricks,
            shafts,
            hidden_groups,
        })
    }

    fn brick_segments(
        &self,
        brick: &BrickDemand,
        words: usize,
        (lights, world): (&[RenderLight], &World),
        shafts: Shafts,
    ) -> BrickFill {
        let stored = self.masks.brick(brick.brick);
        // Only shafts place the nodes.
        let positions: Vec<Vec3> = match shafts {
            Shafts::Test => (0..BRICK_NODES)
                .map(|slot| self.lattice.node_position(join(brick.brick, slot)))
                .collect(),
            Shafts::Skip => Vec::new(),
        };
        let mut fill = BrickFill::default();
        for word in 0..words {
            let mut bits = WordBits {
                test_static: vec![0; BRICK_NODES],
                known_visible: vec![0; BRICK_NODES],
                test_dynamic: vec![0; BRICK_NODES],
                known_occluded: vec![0; BRICK_NODES],
            };
            for slot in 0..BRICK_NODES {
                let needed = brick.needed[slot * words + word];
                let ((visible, valid), (occluded, dynamic_valid)) =
                    stored.map_or(((0, 0), (0, 0)), |b| {
                        let mask = self.masks.slot_mask(b, slot);
                        (mask.static_layer(word), mask.dynamic_layer(word))
                    });
                bits.test_static[slot] = needed & !valid;
                bits.known_visible[slot] = visible & valid;
                bits.test_dynamic[slot] =
                    needed & !dynamic_valid & (bits.test_static[slot] | bits.known_visible[slot]);
                bits.known_occluded[slot] = occluded & dynamic_valid;
            }
            let light = |bit: usize| &lights[word * 64 + bit];
            let place = |slot: usize, bit: usize| Place {
                slot: slot as u16,
                light: (word * 64 + bit) as u32,
            };
            // Static groups first: a clear shaft leaves its nodes open, a
            // wall that hides their box closes them. Each settles only
            // its own light's bits, so the groups made before it stand.
            let static_groups = match shafts {
                Shafts::Test => holders_by_bit(&bits.test_static),
                Shafts::Skip => holders_by_bit(&[]),
            };
            for (bit, members) in static_groups.iter() {
                let blocked = match fill.static_group(members, &positions, light(bit), world) {
                    Group::Clear => {
                        for &slot in members {
                            bits.test_static[slot] &= !(1 << bit);
                            bits.known_visible[slot] |= 1 << bit;
                            fill.static_clear.push(place(slot, bit));
                        }
                        continue;
                    }
                    Group::Hidden => members,
                    Group::FirstBlocked => &members[..1],
                    Group::Mixed => continue,
                };
                // Blocked statically: the dynamic bit is not asked.
                for &slot in blocked {
                    bits.test_static[slot] &= !(1 << bit);
                    bits.test_dynamic[slot] &= !(1 << bit);
                    fill.static_hidden.push(place(slot, bit));
                }
            }
            // Dynamic shafts over the nodes known open; with no dynamic
            // object at all, every open node's dynamic bit is clear
            // without one.
            let open_dynamic: Vec<u64> = match (world.has_dynamic(), shafts) {
                (true, Shafts::Skip) => Vec::new(),
                _ => (0..BRICK_NODES)
                    .map(|slot| bits.test_dynamic[slot] & bits.known_visible[slot])
                    .collect(),
            };
            for (bit, members) in holders_by_bit(&open_dynamic).iter() {
                let clear = !world.has_dynamic()
                    || shaft_box(members, &positions).is_some_and(|bounds| {
                        fill.shaft_is_clear(bounds, light(bit), |shaft| {
                            world.shaft_is_clear_dynamic(shaft)
                        })
                    });
                if clear {
                    for &slot in members {
                        bits.test_dynamic[slot] &= !(1 << bit);
                        fill.dynamic_clear.push(place(slot, bit));
                    }
                }
            }
            let missing = |slot: usize| bits.test_static[slot] | bits.test_dynamic[slot];
            let lights_missing = (0..BRICK_NODES).fold(0, |all, slot| all | missing(slot));
            for bit in set_bits(lights_missing) {
                let at = 1u64 << bit;
                for slot in (0..BRICK_NODES).filter(|&slot| missing(slot) & at != 0) {
                    fill.segments.push(Segment {
                        node: slot as u16,
                        light: (word * 64 + bit) as u32,
                        test_static: bits.test_static[slot] & at != 0,
                        known_visible: bits.known_visible[slot] & at != 0,
                        test_dynamic: bits.test_dynamic[slot] & at != 0,
                        known_occluded: bits.known_occluded[slot] & at != 0,
                    });
                }
            }
        }
        fill
    }

    /// Records the bits `fill`'s shafts and walls settled, and makes
    /// every brick with segments in the store, ahead of the tracer's
    /// answers: a tracer that writes the masks in place (the GPU's pool)
    /// needs each brick it writes to have its slot, holding those bits,
    /// before it runs.
    /// [`LightMesh::merge_segments`] records those bits again with the
    /// answers, which leaves them as they are.
    pub fn settle_groups(&mut self, demand: &Demand, fill: &SegmentFill) {
        let words = demand.words;
        // Most bricks have no group: nothing to make or scan for them.
        let updates: Vec<(IVec3, LayerUpdate, Vec<usize>)> = (demand.bricks.par_iter())
            .zip(&fill.bricks)
            .filter(|(_, brick)| brick.has_groups())
            .map(|(demanded, brick)| {
                let slots = brick.touched_slots(&[]);
                (demanded.brick, brick.group_update(words, &slots), slots)
            })
            .collect();
        let named: Vec<_> = (updates.iter())
            .map(|(brick, update, slots)| (*brick, update, UpdateRows::Named(slots)))
            .collect();
        self.masks.merge_bricks_at(&named);
        let bricks = demand.bricks.iter().map(|demanded| demanded.brick);
        for (brick, fill) in bricks.zip(&fill.bricks) {
            if !fill.segments.is_empty() {
                self.masks.hold(brick);
            }
        }
    }

    /// Records the groups' bits and the tracer's `answers` (parallel to
    /// the segments) in the masks, and what the fill did in `stats`, as
    /// [`LightMesh::fill`] records its own. The bricks' updates are made
    /// in parallel, then merged in the demand's order.
    pub fn merge_segments(
        &mut self,
        demand: &Demand,
        fill: &SegmentFill,
        answers: &[SegmentAnswer],
        stats: &mut LightMeshStats,
    ) {
        debug_assert_eq!(answers.len(), fill.len());
        let words = demand.words;
        let mut rest = answers;
        let brick_answers: Vec<&[SegmentAnswer]> = (fill.bricks.iter())
            .map(|brick| {
                let (own, after) = rest.split_at(brick.segments.len());
                rest = after;
                own
            })
            .collect();
        let merged: Vec<BrickMerge> = (fill.bricks.par_iter())
            .zip(&demand.bricks)
            .zip(brick_answers)
            .map(|((brick, demanded), answers)| brick.merge(demanded, answers, words))
            .collect();
        stats.fill_shafts += fill.shafts;
        stats.fill_hidden_groups += fill.hidden_groups;
        let mut updates = Vec::new();
        for (demanded, merge) in demand.bricks.iter().zip(&merged) {
            stats.fill_segments += merge.segments;
            stats.nodes_computed += merge.nodes_computed;
            stats.bits_computed += merge.bits_computed;
            stats.bits_reused += merge.bits_needed - merge.bits_computed;
            if merge.bits_computed > 0 {
                updates.push((
                    demanded.brick,
                    &merge.update,
                    UpdateRows::Named(&merge.slots),
                ));
            }
        }
        self.masks.merge_bricks_at(&updates);
        stats.nodes_cached = self.masks.nodes_cached() as u64;
    }
}

/// One brick's bits from its fill, and what they count for the stats.
struct BrickMerge {
    update: LayerUpdate,
    /// The slots whose bits `update` holds, one row each
    /// ([`MaskStore::merge_bricks_at`]).
    slots: Vec<usize>,
    segments: u64,
    nodes_computed: u64,
    bits_computed: u64,
    bits_needed: u64,
}

impl BrickFill {
    /// The brick's update from its shafts and `answers` (parallel to its
    /// segments), with `words` light words per node.
    fn merge(&self, demanded: &BrickDemand, answers: &[SegmentAnswer], words: usize) -> BrickMerge {
        let slots = self.touched_slots(&self.segments);
        let mut update = self.group_update(words, &slots);
        let mut segments = 0;
        for (segment, answer) in self.segments.iter().zip(answers) {
            let (word, bit) = Place::from(segment).locate(&slots, words);
            if segment.test_static {
                segments += 1;
                update.static_computed[word] |= bit;
                if !answer.static_blocked {
                    update.static_visible[word] |= bit;
                }
            }
            if answer.dynamic_tested {
                segments += 1;
                update.dynamic_computed[word] |= bit;
                if answer.dynamic_blocked {
                    update.dynamic_occluded[word] |= bit;
                }
            }
        }
        // A segment whose tests were all skipped leaves its row empty.
        let (mut nodes_computed, mut bits_computed) = (0, 0);
        for row in 0..slots.len() {
            let range = row * words..(row + 1) * words;
            let computed: u64 = (update.static_computed[range.clone()].iter())
                .zip(&update.dynamic_computed[range])
                .map(|(s, d)| (s | d).count_ones() as u64)
                .sum();
            nodes_computed += (computed > 0) as u64;
            bits_computed += computed;
        }
        BrickMerge {
            update,
            slots,
            segments,
            nodes_computed,
            bits_computed,
            bits_needed: demanded.needed.iter().map(|w| w.count_ones() as u64).sum(),
        }
    }
}

impl BrickFill {
    /// The places whose bits shafts and walls settled: static clear,
    /// static hidden, dynamic clear.
    fn group_places(&self) -> [&[Place]; 3] {
        [&self.static_clear, &self.static_hidden, &self.dynamic_clear]
    }

    /// Whether shafts or walls settled any of the brick's bits.
    fn has_groups(&self) -> bool {
        self.group_places().iter().any(|places| !places.is_empty())
    }

    /// The slots the brick's groups and `segments` touch, in order, once
    /// each: the rows of its update.
    fn touched_slots(&self, segments: &[Segment]) -> Vec<usize> {
        let mut slots: Vec<usize> = (self.group_places().into_iter().flatten())
            .map(|place| place.slot as usize)
            .chain(segments.iter().map(|segment| segment.node as usize))
            .collect();
        slots.sort_unstable();
        slots.dedup();
        slots
    }

    /// The brick's update from its groups alone (clear shafts and hiding
    /// walls), a row for each of `slots`, which hold the groups' own.
    fn group_update(&self, words: usize, slots: &[usize]) -> LayerUpdate {
        let mut update = LayerUpdate::zeroed(slots.len() * words);
        for place in &self.static_clear {
            let (word, bit) = place.locate(slots, words);
            update.static_computed[word] |= bit;
            update.static_visible[word] |= bit;
        }
        for place in &self.static_hidden {
            let (word, bit) = place.locate(slots, words);
            update.static_computed[word] |= bit;
        }
        for place in &self.dynamic_clear {
            let (word, bit) = place.locate(slots, words);
            update.dynamic_computed[word] |= bit;
        }
        update
    }

    /// How `members`' missing static bits of `light` settle as a group:
    /// as the CPU's fill settles them ([`super::fill`]), by a clear shaft,
    /// or by the wall that blocks the first node's segment hiding the
    /// group's whole box; where that wall hides less, the first node's
    /// bit is settled all the same, as the CPU's fill settles it.
    fn static_group(
        &mut self,
        members: &[usize],
        positions: &[Vec3],
        light: &RenderLight,
        world: &World,
    ) -> Group {
        let Some(bounds) = shaft_box(members, positions) else {
            return Group::Mixed;
        };
        if self.shaft_is_clear(bounds, light, |shaft| world.shaft_is_clear_static(shaft)) {
            return Group::Clear;
        }
        let first = light.shadow_ray(positions[members[0]]);
        let Some(wall) = world.static_occluder(&first, None) else {
            return Group::Mixed;
        };
        if wall_hides_box(world, wall, light, bounds) {
            self.hidden_groups += 1;
            Group::Hidden
        } else {
            Group::FirstBlocked
        }
    }

    /// Whether the shaft from a group's box, `(min, max)`, to `light` is
    /// clear by `is_clear`; only a light with a position has a shaft.
    fn shaft_is_clear(
        &mut self,
        (min, max): (Vec3, Vec3),
        light: &RenderLight,
        is_clear: impl Fn(&Shaft) -> bool,
    ) -> bool {
        let Some(apex) = light.position() else {
            return false;
        };
        self.shafts += 1;
        is_clear(&Shaft::new(min, max, apex))
    }
}

/// The box of `members`' `positions`, where the group is large enough
/// to be worth a shaft ([`MIN_SHAFT_NODES`]).
fn shaft_box(members: &[usize], positions: &[Vec3]) -> Option<(Vec3, Vec3)> {
    (members.len() >= MIN_SHAFT_NODES).then(|| group_box(members, positions))
}

#[cfg(test)]
mod tests {
    use glam::IVec3;

    use super::*;
    use crate::lightmesh::demand::BrickDemand;
    use crate::lightmesh::lattice::Lattice;

    /// A demand of one light word for the brick at the origin's nodes.
    fn brick_at_the_origin(needed: Vec<u64>) -> Demand {
        Demand {
            bricks: vec![BrickDemand {
                brick: IVec3::ZERO,
                needed: needed.into(),
            }],
            words: 1,
            ..Demand::default()
        }
    }

    /// A brick's segments come light by light, nodes in slot order within
    /// a light, one for each needed bit the store lacks.
    #[test]
    fn a_bricks_segments_go_light_by_light() {
        let lights: Vec<RenderLight> = (0..5)
            .map(|i| RenderLight {
                source: crate::render::light::LightSource::Point {
                    position: Vec3::new(i as f32, 9.0, 0.0),
                },
                power: Vec3::ONE,
                range: None,
                lamp_radius: 0.0,
            })
            .collect();
        let mut mesh = LightMesh::new(Lattice::new(0.2), 2.5, lights.len(), 1 << 30);
        // Node 7 already holds light 1's bit in both layers.
        let mut known = LayerUpdate::zeroed(BRICK_NODES);
        known.static_computed[7] = 0b10;
        known.dynamic_computed[7] = 0b10;
        mesh.masks.merge_brick(IVec3::ZERO, &known);
        let mut needed = vec![0u64; BRICK_NODES];
        for (slot, bits) in [(300, 0b10001), (7, 0b00110), (40, 0b10010), (0, 0b00100)] {
            needed[slot] = bits;
        }
        let demand = brick_at_the_origin(needed);
        let world = World::build(&[]);
        let fill = (mesh.fill_segments(&demand, &lights, &world, Shafts::Skip)).unwrap();
        let order: Vec<(u32, u16)> = (fill.bricks[0].segments.iter())
            .map(|segment| (segment.light, segment.node))
            .collect();
        assert_eq!(
            order,
            [(0, 300), (1, 40), (2, 0), (2, 7), (4, 40), (4, 300)]
        );
    }

    /// The rule the GPU's fill writes the pool by (`fill_segments.wgsl`)
    /// is the store's fold of what the merge records: over every state a
    /// bit can be in before its fill (both layers, valid or not) and every
    /// answer its segment can get, [`Segment::sees`] is the bit the store
    /// then holds, and the bit is valid.
    #[test]
    fn a_segment_sees_what_the_store_folds_once_its_answer_is_merged() {
        let mut cases = Vec::new();
        for state in 0..16u32 {
            let [static_valid, static_visible, dynamic_valid, dynamic_occluded] =
                [0, 1, 2, 3].map(|bit| state >> bit & 1 == 1);
            if static_visible && !static_valid || dynamic_occluded && !dynamic_valid {
                continue; // the store never holds such a bit
            }
            let test_static = !static_valid;
            let known_visible = static_valid && static_visible;
            let test_dynamic = !dynamic_valid && (test_static || known_visible);
            if !test_static && !test_dynamic {
                continue; // nothing to fill
            }
            for static_blocked in [false, true] {
                if static_blocked && !test_static {
                    continue;
                }
                let open = if test_static {
                    !static_blocked
                } else {
                    known_visible
                };
                for dynamic_blocked in [false, true] {
                    let dynamic_tested = open && test_dynamic;
                    if dynamic_blocked && !dynamic_tested {
                        continue;
                    }
                    let prior = [
                        static_valid,
                        static_visible,
                        dynamic_valid,
                        dynamic_occluded,
                    ];
                    let answer = SegmentAnswer {
                        static_blocked,
                        dynamic_tested,
                        dynamic_blocked,
                    };
                    cases.push((prior, [test_static, known_visible, test_dynamic], answer));
                }
            }
        }
        let lights = 64;
        let mut mesh = LightMesh::new(Lattice::new(0.2), 2.5, lights, 1 << 30);
        let mut prior_bits = LayerUpdate::zeroed(BRICK_NODES);
        let mut needed = vec![0u64; BRICK_NODES];
        let mut brick = BrickFill::default();
        for (index, (prior, flags, _)) in cases.iter().enumerate() {
            let (node, light) = (index / lights, index % lights);
            let bit = 1u64 << light;
            let set = |on: bool| if on { bit } else { 0 };
            prior_bits.static_computed[node] |= set(prior[0]);
            prior_bits.static_visible[node] |= set(prior[1]);
            prior_bits.dynamic_computed[node] |= set(prior[2]);
            prior_bits.dynamic_occluded[node] |= set(prior[3]);
            needed[node] |= bit;
            brick.segments.push(Segment {
                node: node as u16,
                light: light as u32,
                test_static: flags[0],
                known_visible: flags[1],
                test_dynamic: flags[2],
                known_occluded: prior[2] && prior[3],
            });
        }
        mesh.masks.merge_brick(IVec3::ZERO, &prior_bits);
        let demand = brick_at_the_origin(needed);
        let fill = SegmentFill {
            bricks: vec![brick],
            ..SegmentFill::default()
        };
        let answers: Vec<SegmentAnswer> = cases.iter().map(|case| case.2).collect();
        mesh.merge_segments(&demand, &fill, &answers, &mut LightMeshStats::default());
        let segments = &fill.bricks[0].segments;
        // A missing static bit with the dynamic one missing (3 answers) or
        // known either way (2 each), and a known-visible node's missing
        // dynamic bit (2).
        assert_eq!(segments.len(), 9);
        for (segment, answer) in segments.iter().zip(&answers) {
            let node = join(IVec3::ZERO, segment.node as usize);
            assert_eq!(
                mesh.masks.get(node, segment.light as usize),
                Some(segment.sees(answer)),
                "{segment:?}, {answer:?}"
            );
        }
    }
}
