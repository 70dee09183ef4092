//! Which lattice nodes lie inside closed geometry: LMM1's cheap stand-in
//! for the point-to-node tests that LMM runs at every shading point.
//!
//! Without them, a floor point at the base of a box takes into its
//! interpolation set the nodes inside the box, which see no light, and its
//! contact shadow spreads outwards: measured against the physical lamp,
//! LMM1 was then farther off than hard Whitted shadows (STUDY.md). LMM's
//! step 3 drops those nodes at the cost of one segment per candidate and
//! point (some 30 per point at kI = 2.5); this drops them at the cost of
//! [`PROBES`] short rays per *node*, once, since a node's place in the
//! static geometry never changes.
//!
//! A node is enclosed when, of the probe rays from it that meet static
//! geometry within [`REACH_IN_RADII`] interpolation radii, more meet a
//! triangle's back (the side its winding faces away from) than its front.
//! Inside a closed solid every probe that meets something meets a back;
//! in the open, only the back of an open (one-sided) surface can be met,
//! so a node below a floor plane counts as enclosed (as it should: it is
//! behind the floor for every point above it), while a node under a
//! one-sided leaf also sees the ground's front and is not. Probes that a
//! solid's bottom face shares with the floor it rests on may find the
//! floor's front first; the majority over all directions still decides
//! for nodes near the base of solids up to a few radii wide (a node near
//! the base of a much larger solid may not be found: it then keeps LMM1's
//! old behaviour).
//!
//! In a frame this runs for LMM1 only, and settles the nodes the demand
//! named that are blocked from some light and have no flag yet (see
//! [`blocks_some`]); formula (2) then leaves out enclosed nodes blocked
//! from some light the point asks for. On the CPU it runs after the fill;
//! on the GPU, before the fill's answers are back, so there a node whose
//! bits are still being traced is probed too (it may turn out blocked).
//! Only static geometry is probed, so no moving object can change a flag,
//! probing a node early changes no image, and reuse stays exact. The disk
//! cache keeps the flags with the static bits (`super::cache`), so a warm
//! run probes only nodes no earlier run settled.

use glam::{IVec3, Vec3};
use rayon::prelude::*;

use super::demand::Demand;
use super::masks::{join, BrickCache, BrickEnclosure, NodeMask, BRICK_NODES};
use super::LightMesh;
use crate::accel::{Ray, World};

/// How far probes reach, in interpolation radii r = kI·h: a node that a
/// floor point's half-ball holds is within r of that point, so the surface
/// between them is within r of the node, and twice that leaves room for
/// probes that meet it at a slant.
pub const REACH_IN_RADII: f32 = 4.0;

/// Probe directions: the six axes and the eight diagonals, unit length.
pub const PROBES: [Vec3; 14] = {
    const D: f32 = 0.577_350_26; // 1/√3
    [
        Vec3::X,
        Vec3::NEG_X,
        Vec3::Y,
        Vec3::NEG_Y,
        Vec3::Z,
        Vec3::NEG_Z,
        Vec3::new(D, D, D),
        Vec3::new(D, D, -D),
        Vec3::new(D, -D, D),
        Vec3::new(D, -D, -D),
        Vec3::new(-D, D, D),
        Vec3::new(-D, D, -D),
        Vec3::new(-D, -D, D),
        Vec3::new(-D, -D, -D),
    ]
};

/// Whether the point `at` lies inside closed static geometry, probing
/// `reach` metres around it (see the module doc).
pub fn is_enclosed(world: &World, at: Vec3, reach: f32) -> bool {
    ProbeOrder::default().is_enclosed(world, at, reach)
}

/// The order one thread sends its probes in: the directions that met
/// geometry at its last node first. The verdict does not depend on the
/// order (probing stops only where the probes left cannot change the
/// majority), so any order gives every node the flag [`PROBES`]' own order
/// gives it. The order matters for cost: a probe that meets nothing
/// counts for neither side, and a node in the open, whose probes meet
/// only the floor below it, is settled once the fronts outnumber the
/// probes left. Neighbouring nodes (a thread probes a brick's nodes in
/// slot order) mostly meet the same surfaces, so sending the directions
/// that met first spends fewer probes on misses, which are also the
/// probes that walk the whole reach.
#[derive(Clone, Debug)]
pub struct ProbeOrder {
    directions: [u8; PROBES.len()],
}

impl Default for ProbeOrder {
    fn default() -> ProbeOrder {
        ProbeOrder {
            directions: std::array::from_fn(|i| i as u8),
        }
    }
}

impl ProbeOrder {
    /// [`is_enclosed`]'s verdict for `at`; the directions that met
    /// geometry there go first at the next node, each group in its order.
    pub fn is_enclosed(&mut self, world: &World, at: Vec3, reach: f32) -> bool {
        let (mut backs, mut fronts) = (0, 0);
        let mut met = 0u16;
        for (done, &index) in self.directions.iter().enumerate() {
            // Stop once the probes left cannot change the verdict.
            let left = PROBES.len() - done;
            if backs > fronts + left || fronts >= backs + left {
                break;
            }
            let direction = PROBES[index as usize];
            if let Some(hit) = world.closest_static_hit(&Ray::new(at, direction, reach)) {
                met |= 1 << index;
                if hit.geometric_normal.dot(direction) > 0.0 {
                    backs += 1;
                } else {
                    fronts += 1;
                }
            }
        }
        let old = self.directions;
        let has_met = |&&index: &&u8| met >> index & 1 == 1;
        let (first, rest) = (
            old.iter().filter(has_met),
            old.iter().filter(|i| !has_met(i)),
        );
        for (slot, &index) in self.directions.iter_mut().zip(first.chain(rest)) {
            *slot = index;
        }
        backs > fronts
    }
}

/// Whether the node of `mask` is known to be blocked from some light of
/// `lights` (one word per 64 lights). Only such nodes are probed and left
/// out: a node that sees every light a point asks for votes as an open
/// node would, wherever it lies, so its flag cannot change the point.
/// This keeps the probes to nodes in shadow, and makes formula (2) depend
/// on the current masks and the static geometry only, never on which
/// frame first asked for a node.
pub fn blocks_some(mask: &NodeMask, lights: &[u64]) -> bool {
    (lights.iter().enumerate())
        .any(|(word, &wanted)| wanted & mask.valid(word) & !mask.visible(word) != 0)
}

/// Whether some light of `lights` has no valid bit at the node of `mask`
/// yet: its fill is still on its way.
fn misses_some(mask: &NodeMask, lights: &[u64]) -> bool {
    (lights.iter().enumerate()).any(|(word, &wanted)| wanted & !mask.valid(word) != 0)
}

/// LMM1's stand-in for the point-to-node tests: leaves out of `nodes` those
/// inside closed geometry (their flag settled by the enclosure stage) that
/// are blocked from some light of `lights`.
pub fn leave_out_enclosed(nodes: &mut Vec<IVec3>, bricks: &mut BrickCache, lights: &[u64]) {
    nodes.retain(|&node| {
        !(bricks.is_enclosed(node)
            && bricks
                .mask(node)
                .is_some_and(|mask| blocks_some(&mask, lights)))
    });
}

/// What the enclosure stage did in a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct EnclosureWork {
    /// Nodes probed: their flag was settled now.
    pub probed: u64,
    /// Nodes whose flag an earlier frame settled, read as it left it
    /// (flags depend on the static geometry alone, so none is dropped).
    pub reused: u64,
}

/// The nodes of a demand whose enclosure flags are to be settled, brick
/// by brick in the demand's order: the CPU probes them where it fills
/// ([`LightMesh::settle_enclosure`]), the GPU beside its fill
/// (`backend::gpu::enclosure`), and either answer goes into the store
/// by [`LightMesh::merge_probes`].
#[derive(Clone, Debug, Default)]
pub struct ProbeList {
    /// Per brick of the demand, its slots to probe, in slot order.
    pub bricks: Vec<Vec<u16>>,
    /// Nodes a point asked about whose flag was already settled.
    pub reused: u64,
}

impl ProbeList {
    /// How many nodes are to be probed.
    pub fn len(&self) -> usize {
        self.bricks.iter().map(Vec::len).sum()
    }

    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// (brick's index in the demand, slot) of each node, in order.
    pub fn nodes(&self) -> impl Iterator<Item = (usize, u16)> + '_ {
        (self.bricks.iter().enumerate())
            .flat_map(|(brick, slots)| slots.iter().map(move |&slot| (brick, slot)))
    }
}

impl LightMesh {
    /// The nodes `demand` names whose enclosure flag is not settled yet
    /// and that are blocked from some light they are asked for, or may be
    /// (its bit is not valid yet). After the CPU's fill every needed bit
    /// is valid; the GPU's may still be tracing.
    pub fn nodes_to_probe(&self, demand: &Demand) -> ProbeList {
        let words = demand.words;
        let bricks: Vec<(Vec<u16>, u64)> = (demand.bricks.par_iter())
            .map(|brick| {
                let known = self.masks.enclosure(brick.brick).known;
                let Some(bits) = self.masks.brick(brick.brick) else {
                    return (Vec::new(), 0);
                };
                let mut slots = Vec::new();
                let mut reused = 0;
                for slot in 0..BRICK_NODES {
                    let mask = self.masks.slot_mask(bits, slot);
                    let needed = &brick.needed[slot * words..(slot + 1) * words];
                    if !blocks_some(&mask, needed) && !misses_some(&mask, needed) {
                        continue;
                    }
                    if known[slot / 64] >> (slot % 64) & 1 == 1 {
                        reused += 1;
                    } else {
                        slots.push(slot as u16);
                    }
                }
                (slots, reused)
            })
            .collect();
        ProbeList {
            reused: bricks.iter().map(|(_, reused)| reused).sum(),
            bricks: bricks.into_iter().map(|(slots, _)| slots).collect(),
        }
    }

    /// Settles the flag of every node [`LightMesh::nodes_to_probe`] names
    /// by probing `world` on the CPU, in parallel over bricks.
    pub fn settle_enclosure(&mut self, demand: &Demand, world: &World) -> EnclosureWork {
        let probes = self.nodes_to_probe(demand);
        let reach = self.probe_reach();
        let enclosed: Vec<Vec<bool>> = (demand.bricks.par_iter().zip(&probes.bricks))
            .map_init(ProbeOrder::default, |order, (brick, slots)| {
                (slots.iter())
                    .map(|&slot| {
                        let at = self.lattice.node_position(join(brick.brick, slot as usize));
                        order.is_enclosed(world, at, reach)
                    })
                    .collect()
            })
            .collect();
        self.merge_probes(demand, &probes, &enclosed.concat())
    }

    /// How far a node's probes reach: [`REACH_IN_RADII`] radii.
    pub fn probe_reach(&self) -> f32 {
        REACH_IN_RADII * self.radius()
    }

    /// Records the flags of `probes`' nodes (of `demand`'s bricks):
    /// whether each is `enclosed`, one answer per node in the list's order.
    pub fn merge_probes(
        &mut self,
        demand: &Demand,
        probes: &ProbeList,
        enclosed: &[bool],
    ) -> EnclosureWork {
        debug_assert_eq!(enclosed.len(), probes.len());
        let mut answers = enclosed.iter();
        for (brick, slots) in demand.bricks.iter().zip(&probes.bricks) {
            if slots.is_empty() {
                continue;
            }
            let mut settled = BrickEnclosure::default();
            for (&slot, &enclosed) in slots.iter().zip(&mut answers) {
                let (word, bit) = (slot as usize / 64, 1u64 << (slot % 64));
                settled.known[word] |= bit;
                if enclosed {
                    settled.enclosed[word] |= bit;
                }
            }
            self.masks.merge_enclosure(brick.brick, &settled);
        }
        EnclosureWork {
            probed: probes.len() as u64,
            reused: probes.reused,
        }
    }
}

#[cfg(test)]
mod tests {
    use glam::{Affine3A, Vec3};

    use super::*;
    use crate::accel::WorldObject;

    /// A floor (a one-sided plane facing +Y, 4 m square) and a closed unit
    /// box wound outwards, resting on it, its bottom face in the floor's
    /// plane.
    fn box_on_floor() -> World {
        let floor = [-2.0f32, 2.0].map(|x| [-2.0f32, 2.0].map(|z| Vec3::new(x, 0.0, z)));
        let floor_positions = [floor[0][0], floor[1][0], floor[1][1], floor[0][1]];
        let floor_triangles = [[0, 2, 1], [0, 3, 2]];
        let cube_positions: Vec<Vec3> = unit_cube_corners()
            .into_iter()
            .map(|corner| corner - Vec3::splat(0.5))
            .collect();
        World::build(&[
            WorldObject {
                positions: &floor_positions,
                triangles: &floor_triangles,
                to_render: Affine3A::IDENTITY,
                dynamic: false,
            },
            WorldObject {
                positions: &cube_positions,
                triangles: &CUBE_TRIANGLES,
                to_render: Affine3A::from_translation(Vec3::new(0.0, 0.5, 0.0)),
                dynamic: false,
            },
        ])
    }

    /// The unit cube's triangles over [`unit_cube_corners`], two a face.
    const CUBE_TRIANGLES: [[u32; 3]; 12] = [
        [0, 4, 6],
        [0, 6, 2],
        [1, 3, 7],
        [1, 7, 5],
        [0, 1, 5],
        [0, 5, 4],
        [2, 6, 7],
        [2, 7, 3],
        [0, 2, 3],
        [0, 3, 1],
        [4, 5, 7],
        [4, 7, 6],
    ];

    /// Corner i of the unit cube has x, y, z from its bits 0, 1, 2.
    fn unit_cube_corners() -> Vec<Vec3> {
        (0..8)
            .map(|i| Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32))
            .collect()
    }

    /// Every triangle of the test box faces out, which the probes'
    /// back-or-front count relies on.
    #[test]
    fn the_test_box_is_wound_outwards() {
        let corners = unit_cube_corners();
        let centre = Vec3::splat(0.5);
        for triangle in CUBE_TRIANGLES {
            let [a, b, c] = triangle.map(|i| corners[i as usize]);
            let normal = (b - a).cross(c - a);
            assert!(normal.dot((a + b + c) / 3.0 - centre) > 0.0, "{triangle:?}");
        }
    }

    #[test]
    fn nodes_inside_the_box_and_under_the_floor_are_enclosed() {
        let world = box_on_floor();
        let reach = 0.8;
        for inside in [
            Vec3::new(0.0, 0.5, 0.0),
            Vec3::new(0.45, 0.03, 0.1),  // at the base, by a side
            Vec3::new(-0.3, 0.02, -0.4), // near a bottom corner
            Vec3::new(0.2, 0.97, 0.2),   // under the top
        ] {
            assert!(is_enclosed(&world, inside, reach), "{inside}");
        }
        assert!(
            is_enclosed(&world, Vec3::new(1.2, -0.1, 0.3), reach),
            "below the floor"
        );
    }

    proptest::proptest! {
        /// The verdict does not depend on the order of the probes: a
        /// thread's order, however its earlier nodes shaped it, gives each
        /// node the flag that [`PROBES`]' own order gives it. The points
        /// include ones on the box's faces and the floor's plane.
        #[test]
        fn any_probe_order_gives_the_same_flags(
            seed in proptest::collection::vec(0u8..14, 14),
            points in proptest::collection::vec(
                (-1.2f32..1.2, -0.3f32..1.3, -1.2f32..1.2, 0u8..4),
                1..40,
            ),
        ) {
            let world = box_on_floor();
            let reach = 0.8;
            // A permutation from the seed: each step swaps in a slot.
            let mut order = ProbeOrder::default();
            for (i, &j) in seed.iter().enumerate() {
                order.directions.swap(i, j as usize);
            }
            for (x, y, z, snap) in points {
                // Snap some coordinates onto the faces and the floor.
                let at = match snap {
                    0 => Vec3::new(x, y, z),
                    1 => Vec3::new(0.5, y, z),
                    2 => Vec3::new(x, 0.0, z),
                    _ => Vec3::new(x, 1.0, -0.5),
                };
                proptest::prop_assert_eq!(
                    order.is_enclosed(&world, at, reach),
                    is_enclosed(&world, at, reach),
                    "at {}", at
                );
            }
        }
    }

    #[test]
    fn a_thread_probes_first_the_directions_that_met_geometry() {
        let world = box_on_floor();
        let mut order = ProbeOrder::default();
        // Over the floor, away from the box: only the floor is met, by
        // the probes that point down; the verdict is reached after the
        // eleventh probe (three fronts, three probes left), so the last
        // two downward diagonals are not sent.
        assert!(!order.is_enclosed(&world, Vec3::new(1.5, 0.3, 1.5), 0.8));
        let met = [3, 8, 9];
        assert!(met.iter().all(|&i| PROBES[i as usize].y < 0.0));
        let rest = (0..14).filter(|i| !met.contains(i));
        let expected: Vec<u8> = met.into_iter().chain(rest).collect();
        assert_eq!(order.directions[..], expected[..]);
    }

    #[test]
    fn nodes_in_the_open_are_not() {
        let world = box_on_floor();
        let reach = 0.8;
        for open in [
            Vec3::new(0.55, 0.03, 0.1), // just outside the base
            Vec3::new(0.0, 1.05, 0.0),  // just above the top
            Vec3::new(1.5, 0.3, 1.5),   // over the floor
            Vec3::new(0.0, 3.0, 0.0),   // out of reach of everything
        ] {
            assert!(!is_enclosed(&world, open, reach), "{open}");
        }
    }
}
