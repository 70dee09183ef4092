//! Stages 5–6 of an LMM frame: the interpolation set D_LM(P) and formula (2),
//!
//!   U_LM(P) = (1/m) Σ_k Σ_{i : N_{x_k}(i) = 1} Omega(i, P)
//!           = Σ_i Omega(i, P) · (visible nodes of light i) / m,
//!
//! with Omega always evaluated at P; the nodes may be weighed by their
//! distance to P instead of counted (`super::kernel`). LMM keeps only the nodes that P sees
//! (step 3, one short segment each); LMM1 skips that test and leaves out
//! only the nodes inside closed geometry (`super::enclosure`). An empty
//! set falls back to formula (1) with real shadow rays.

use glam::{IVec3, Vec3};

use super::agreement::Agreement;
use super::enclosure::leave_out_enclosed;
use super::kernel::{Kernel, Weights};
use super::lamp_disk;
use super::masks::BrickCache;
use super::penumbra::{self, LevelScratch};
use super::sight::Sight;
use super::wide::WideScratch;
use super::{LightMesh, LightMeshStats};
use crate::accel::offset::offset_ray_origin;
use crate::accel::{Ray, World};
use crate::bits::set_bits;
use crate::render::light::RenderLight;
use crate::render::light_terms::LightTerms;
use crate::render::omega::{LightLanes, PointLanes, LANES};
use crate::render::shadow_split::ShadowSplit;
use crate::render::surface::ShadingPoint;
use crate::render::whitted;
use crate::stats::ClassRays;

/// What shading one point cost, summed into the frame's statistics.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct PointCounts {
    pub candidates: u64,
    pub interp_set: u64,
    pub p2n_tests: u64,
    pub fallback: u64,
    /// Points whose value came from what the nodes around them agree on,
    /// without walking their half-ball ([`Agreement`]).
    pub settled: u64,
    /// Rays of `penumbra: blocker` and `wide`: those that looked for a
    /// light's blocker (grazing lamps' rays among them) and the segments
    /// of a lattice level's nodes.
    pub blocker_rays: u64,
    /// Level segments answered without a ray: from the mesh's masks, or
    /// traced by a neighbouring point ([`penumbra::LevelAnswers`]).
    pub blocker_rays_remembered: u64,
    /// Plain shadow rays (formula (1), lamp samples), by light class.
    pub shadow_rays: ClassRays,
}

impl PointCounts {
    /// The counts of a point shaded with `rays` plain shadow rays.
    pub fn shadow_rays(rays: ClassRays) -> PointCounts {
        PointCounts {
            shadow_rays: rays,
            ..PointCounts::default()
        }
    }
}

impl std::ops::AddAssign for PointCounts {
    fn add_assign(&mut self, other: PointCounts) {
        self.candidates += other.candidates;
        self.interp_set += other.interp_set;
        self.p2n_tests += other.p2n_tests;
        self.fallback += other.fallback;
        self.settled += other.settled;
        self.blocker_rays += other.blocker_rays;
        self.blocker_rays_remembered += other.blocker_rays_remembered;
        self.shadow_rays += other.shadow_rays;
    }
}

/// Reusable per-thread buffers, so shading allocates nothing per point,
/// and the brick lookups and summaries neighbouring points share.
pub struct Scratch<'a> {
    set: InterpolationSet,
    /// The lattice levels' nodes and answers (`penumbra: blocker`).
    levels: LevelScratch,
    /// What the nodes around each tile agree on (LMM1).
    agreement: Agreement,
    /// The points' wide sets (`penumbra: wide`).
    wide: WideScratch,
    bricks: BrickCache<'a>,
}

impl<'a> Scratch<'a> {
    /// Scratch for shading with `mesh` under the frame's `lights`.
    pub fn new(mesh: &'a LightMesh, lights: &[RenderLight]) -> Scratch<'a> {
        Scratch {
            set: InterpolationSet::default(),
            levels: LevelScratch::default(),
            agreement: Agreement::new(
                (mesh.lattice, mesh.radius(), 1),
                mesh.masks().words(),
                mesh.tile_memo(),
            ),
            wide: WideScratch::new(mesh, lights),
            bricks: BrickCache::new(mesh.masks()),
        }
    }
}

/// A point's interpolation set D_LM(P) and what its nodes see.
#[derive(Default)]
struct InterpolationSet {
    nodes: Vec<IVec3>,
    /// The kernel's weight of each node.
    weights: Vec<u32>,
    sight: Sight,
}

impl LightMesh {
    /// A frame's light-mesh statistics: what demand, fill and enclosure
    /// did (`work`), what shading its `points` shading points cost
    /// (`counts`), and what the store holds after it. The means are over
    /// the points that walked their half-ball (not those `settled`).
    pub fn frame_stats(
        &self,
        work: LightMeshStats,
        counts: PointCounts,
        points: u64,
    ) -> LightMeshStats {
        let walked = points.saturating_sub(counts.settled).max(1) as f64;
        LightMeshStats {
            h: self.lattice.h,
            ki: self.ki,
            mean_candidates: counts.candidates as f64 / walked,
            mean_interp_set: counts.interp_set as f64 / walked,
            mean_p2n_tests: counts.p2n_tests as f64 / walked,
            fallback_points: counts.fallback,
            points_settled: counts.settled,
            blocker_rays: counts.blocker_rays,
            blocker_rays_remembered: counts.blocker_rays_remembered,
            bits_cached: self.masks().known_bits(),
            ..work
        }
    }

    /// Direct light at `point` by formula (2), light by light into
    /// `terms`, and what it cost. `reach` holds the lights that can reach
    /// the point and `faint` its faint lamps (both from the demand stage,
    /// [`super::demand::Demand::of_point`]); every bit this reads was
    /// filled from that demand. With `point_to_node_tests` (LMM) only the nodes
    /// the point sees are interpolated; without (LMM1) all of them.
    #[allow(clippy::too_many_arguments)]
    pub fn shade(
        &self,
        point: &ShadingPoint,
        (reach, faint): (&[u64], &[u64]),
        lights: &LightLanes,
        world: &World,
        point_to_node_tests: bool,
        shadows: &ShadowSplit,
        scratch: &mut Scratch,
        terms: &mut impl LightTerms,
    ) -> PointCounts {
        let mut counts = PointCounts::default();
        let Scratch {
            set,
            levels,
            agreement,
            wide,
            bricks,
        } = scratch;
        let sight = &mut set.sight;
        sight.all.clear();
        sight.all.resize(reach.len(), 0);
        // LMM's set is what the point sees, which no summary knows.
        let total = if !point_to_node_tests
            && agreement.settle(point.position, reach, bricks, &mut sight.all)
        {
            counts.settled = 1;
            sight.any.clone_from(&sight.all);
            // Each light is seen by every node of the set or by none: none
            // below needs the set's nodes or its weight.
            0
        } else {
            let total = self.gather(
                point,
                reach,
                world,
                point_to_node_tests,
                set,
                bricks,
                &mut counts,
            );
            if total == 0 {
                counts.fallback = 1;
                counts.shadow_rays =
                    whitted::direct_light_terms(point, lights, world, shadows, terms);
                return counts;
            }
            total
        };
        let InterpolationSet {
            nodes,
            weights,
            sight,
        } = set;
        let (all, any) = (&sight.all, &sight.any);
        // The lamps the point's own set agrees on but its wide set does
        // not: it lies in their penumbra, beyond the set's reach.
        wide.look(
            (point.position, point.geometric_normal),
            reach,
            (all, any, faint),
            bricks,
        );
        let wide = &*wide;

        // Omega eight lights at a time, for the blocks where some node sees
        // a light or the wide set disagrees on it; the sum runs in light
        // order.
        let at = PointLanes::new(point);
        // Where the blocker's rays start, the same for every light.
        let origin = offset_ray_origin(point.position, point.geometric_normal);
        for (word, &lit) in any.iter().enumerate() {
            let lit = lit | wide.mixed(word);
            for block_in_word in 0..64 / LANES {
                let first = block_in_word * LANES;
                let lit_lanes = (lit >> first) as u8;
                if lit_lanes == 0 {
                    continue;
                }
                let omega = lights.omega(&at, word * 64 / LANES + block_in_word);
                for lane in set_bits((lit_lanes & omega.reaching).into()) {
                    let bit = first + lane;
                    let light = word * 64 + bit;
                    let seen_by_all = all[word] >> bit & 1 == 1;
                    let in_wide_set = wide.mixed(word) >> bit & 1 == 1;
                    let refined = faint[word] >> bit & 1 == 0;
                    let penumbra_at = PenumbraAt {
                        point,
                        origin,
                        lights: lights.lights(),
                        light,
                        world,
                        wide: in_wide_set,
                    };
                    let share = if in_wide_set {
                        // The point's own nodes agree: their answer stands
                        // where nothing sizes the penumbra.
                        let agreed = match seen_by_all {
                            true => Share::Full,
                            false => Share::Hidden,
                        };
                        let set = wide.seen_from(light);
                        self.blocker_share(penumbra_at, set, levels, bricks, &mut counts)
                            .unwrap_or(agreed)
                    } else if seen_by_all {
                        match self.penumbra.probes_grazing_lamps() && refined {
                            true => self
                                .grazing_share(penumbra_at, levels, bricks, &mut counts)
                                .unwrap_or(Share::Full),
                            false => Share::Full,
                        }
                    } else {
                        // The nodes disagree on this light: the point is in
                        // its penumbra, or near it.
                        let sees = || sight.sees(light);
                        let fixed = || {
                            let seen: u32 = (sees().zip(weights.iter()))
                                .filter(|&(sees, _)| sees)
                                .map(|(_, &weight)| weight)
                                .sum();
                            Share::Part(seen as f32 / total as f32)
                        };
                        let by_blocker = match self.penumbra.sizes_by_blocker() && refined {
                            true => {
                                let set = nodes.iter().copied().zip(sees());
                                self.blocker_share(penumbra_at, set, levels, bricks, &mut counts)
                            }
                            false => None,
                        };
                        by_blocker.unwrap_or_else(fixed)
                    };
                    match share {
                        Share::Full => terms.add(light, omega.get(lane)),
                        Share::Part(share) => terms.add(light, omega.get(lane) * share),
                        Share::Hidden => {}
                    }
                }
            }
        }
        counts
    }

    /// Steps 1–3 for `point`: its interpolation set into `set`, with the
    /// nodes' weights and what they see of the lights in `reach`; returns
    /// the weights' sum Σ w_k, 0 for an empty set (formula (1) then).
    #[allow(clippy::too_many_arguments)]
    fn gather(
        &self,
        point: &ShadingPoint,
        reach: &[u64],
        world: &World,
        point_to_node_tests: bool,
        set: &mut InterpolationSet,
        bricks: &mut BrickCache,
        counts: &mut PointCounts,
    ) -> u32 {
        let InterpolationSet {
            nodes,
            weights,
            sight,
        } = set;
        nodes.clear();
        self.lattice
            .half_ball(point.position, point.geometric_normal, self.radius(), nodes);
        counts.candidates = nodes.len() as u64;
        if point_to_node_tests {
            counts.p2n_tests = nodes.len() as u64;
            let origin = offset_ray_origin(point.position, point.geometric_normal);
            let lattice = self.lattice;
            nodes.retain(|&node| {
                let x = lattice.node_position(node);
                !world.occluded(&Ray::new(origin, x - origin, 1.0))
            });
        } else {
            leave_out_enclosed(nodes, bricks, reach);
        }
        counts.interp_set = nodes.len() as u64;
        let kernel = self.weights();
        weights.clear();
        weights.extend(nodes.iter().map(|&node| match kernel.kernel() {
            Kernel::Box => 1,
            Kernel::Smooth => kernel.weight(self.lattice.distance_squared(node, point.position)),
        }));
        // Σ w_k: with the box kernel, m; with the smooth one, zero only
        // when every node lies on the rim. An empty set reads no masks.
        let total = weights.iter().sum();
        if total == 0 {
            return 0;
        }

        // Where every node agrees (far from shadow edges, the common case)
        // a light is fully visible or fully hidden; only lights the nodes
        // disagree on need their visible nodes counted.
        sight.tally(nodes, reach, bricks);
        total
    }

    /// The share of light `at.light` at `at.point` by its blocker's
    /// distance ([`penumbra`]), the blocker found from the centre ray or
    /// from the blocked node of `set` nearest the point, and the share
    /// taken as [`Self::share_over_level`] takes it; its rays go to
    /// `counts`. `set` is the point's interpolation set (or its wide set),
    /// each node with whether it sees the light. None where nothing sizes
    /// the penumbra (a light without a lamp, or a blocked node whose
    /// segment is found clear): the half-ball's share stands there.
    fn blocker_share(
        &self,
        at: PenumbraAt,
        set: impl Iterator<Item = (IVec3, bool)>,
        levels: &mut LevelScratch,
        bricks: &mut BrickCache,
        counts: &mut PointCounts,
    ) -> Option<Share> {
        let point = at.point;
        // Ties (a lattice has many nodes at one distance) go to the least
        // coordinates, so the choice does not depend on the set's order.
        // Distances rounded as the half-ball rounds them.
        let nearest_blocked = set
            .filter(|&(_, sees)| !sees)
            .map(|(node, _)| (self.lattice.distance_squared(node, point.position), node))
            .min_by(|(a, a_node), (b, b_node)| {
                (a.total_cmp(b)).then_with(|| a_node.to_array().cmp(&b_node.to_array()))
            })
            .map_or(point.position, |(_, node)| self.lattice.node_position(node));
        let light = &at.lights[at.light];
        let estimate = penumbra::estimate(at.origin, light, nearest_blocked, at.world)?;
        counts.blocker_rays += estimate.rays;
        self.share_over_level(at, estimate, levels, bricks, counts)
    }

    /// The share of a lamp that every node of the point's set sees, where
    /// it grazes the surface and a ray towards its point nearest the
    /// surface finds a blocker ([`penumbra::grazing_estimate`]): over the
    /// lamp disk of the level that blocker sizes. None where nothing was
    /// found: the set's answer stands.
    fn grazing_share(
        &self,
        at: PenumbraAt,
        levels: &mut LevelScratch,
        bricks: &mut BrickCache,
        counts: &mut PointCounts,
    ) -> Option<Share> {
        let light = &at.lights[at.light];
        let normal = at.point.geometric_normal;
        let estimate = penumbra::grazing_estimate(at.origin, normal, light, at.world)?;
        counts.blocker_rays += estimate.rays;
        self.share_over_level(at, estimate, levels, bricks, counts)
    }

    /// The share of light `at.light` over the lamp disk of the lattice
    /// level whose radius comes nearest `estimate`'s, or the centre ray's
    /// answer where the penumbra is too narrow for any level; None where
    /// the estimate has no radius, or where the set is the wide set and
    /// the penumbra no wider than the mesh's level. A level node's answer
    /// is its segment's: read from the mesh's mask where the level is no
    /// finer than the mesh (its nodes are the mesh's) and the bit is
    /// known, else remembered from a neighbouring point (`levels`), else
    /// traced.
    fn share_over_level(
        &self,
        at: PenumbraAt,
        estimate: penumbra::BlockerEstimate,
        levels: &mut LevelScratch,
        bricks: &mut BrickCache,
        counts: &mut PointCounts,
    ) -> Option<Share> {
        let PenumbraAt {
            point,
            lights,
            light: index,
            world,
            ..
        } = at;
        let light = &lights[index];
        let hard = match estimate.centre_visible {
            true => Share::Full,
            false => Share::Hidden,
        };
        // The lamp's disk as the point sees it has the penumbra's radius;
        // the level whose half-ball radius comes nearest it answers for
        // its samples.
        let radius = estimate.radius?;
        let level = penumbra::level(self.lattice, self.ki, radius);
        // From the wide set, only a penumbra wider than the mesh's level
        // is sized: a narrower one the point's own nodes, which agree,
        // would have seen, so their answer stands.
        if at.wide && level.is_none_or(|level| level.h <= self.lattice.h) {
            return None;
        }
        let Some(level) = level else {
            return Some(hard);
        };
        let lamp = light.position()?;
        let LevelScratch {
            nodes,
            answers,
            blockers,
        } = levels;
        if blockers.len() <= index {
            blockers.resize(lights.len(), None);
        }
        let blocker = &mut blockers[index];
        lamp_disk::disk_nodes(
            level,
            point.position,
            point.geometric_normal,
            lamp,
            radius,
            nodes,
        );
        let weights = Weights::new(self.kernel, radius);
        // Level k ≥ 0's node n is the mesh's node n·2^k, at the same
        // position to the bit (scaling by a power of two is exact).
        let mesh_steps = (level.h >= self.lattice.h).then(|| (level.h / self.lattice.h) as i32);
        let (mut total, mut seen) = (0u32, 0u32);
        for &(node, distance_squared) in nodes.iter() {
            let weight = weights.weight(distance_squared);
            total += weight;
            let mesh_node = mesh_steps.and_then(|steps| scaled_node(node, steps));
            let known = mesh_node.and_then(|node| known_sight(bricks, node, index));
            let (sees, traced) = match known {
                Some(sees) => (sees, false),
                None => answers.sees(level, node, index, || {
                    !world.occluded_near(&light.shadow_ray(level.node_position(node)), blocker)
                }),
            };
            match traced {
                true => counts.blocker_rays += 1,
                false => counts.blocker_rays_remembered += 1,
            }
            if sees {
                seen += weight;
            }
        }
        match total {
            0 => Some(hard),
            _ => Some(Share::Part(seen as f32 / total as f32)),
        }
    }
}

/// `node` times `steps`, or None past the range of node coordinates (a
/// node that far out holds no bits).
fn scaled_node(node: IVec3, steps: i32) -> Option<IVec3> {
    let scale = |c: i32| c.checked_mul(steps);
    Some(IVec3::new(scale(node.x)?, scale(node.y)?, scale(node.z)?))
}

/// Whether mesh node `node` sees light number `light`, where its mask
/// knows: the answer its segment gives.
fn known_sight(bricks: &mut BrickCache, node: IVec3, light: usize) -> Option<bool> {
    let (word, bit) = (light / 64, light % 64);
    let mask = bricks.mask(node)?;
    (mask.valid(word) >> bit & 1 == 1).then(|| mask.visible(word) >> bit & 1 == 1)
}

/// Where a penumbra is sized: the point and its rays' origin, the frame's
/// lights and the number of the one sized, the world; and whether the set
/// is the point's wide set (`super::wide`).
#[derive(Clone, Copy)]
struct PenumbraAt<'a> {
    point: &'a ShadingPoint,
    origin: Vec3,
    lights: &'a [RenderLight],
    light: usize,
    world: &'a World,
    wide: bool,
}

/// What formula (2) gives a light at a point whose set disagrees on it.
enum Share {
    /// The light's whole Omega.
    Full,
    /// None of it.
    Hidden,
    /// This fraction of it.
    Part(f32),
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn level_nodes_scale_to_mesh_nodes_within_the_coordinate_range() {
        let node = IVec3::new(-3, 4, 5);
        assert_eq!(scaled_node(node, 8), Some(IVec3::new(-24, 32, 40)));
        assert_eq!(scaled_node(IVec3::new(0, i32::MAX / 2 + 1, 0), 2), None);
        assert_eq!(
            scaled_node(IVec3::new(0, 0, i32::MIN / 4), 4),
            Some(IVec3::new(0, 0, i32::MIN))
        );
        assert_eq!(scaled_node(IVec3::new(i32::MIN / 4 - 1, 0, 0), 4), None);
    }
}
