//! How wide a light's penumbra is at a shading point, from the distance
//! between the point and what blocks the light.
//!
//! Formula (2) over a half-ball of fixed radius r = kI·h draws every
//! penumbra about 2r wide. A real lamp's is not: for a spherical lamp of
//! radius R at distance D from the point, an occluder's edge at distance
//! z from the point casts a penumbra of width 2·R·z / (D − z) there.
//! It is narrow where the occluder touches the receiver (an umbra
//! remains at the contact) and wide far from it (STUDY.md measured this
//! as what the fixed radius leaves: "the width of the transition, not its
//! shape").
//!
//! With `lightmesh.penumbra: blocker`, a point whose interpolation set
//! disagrees on a light (some of its nodes see the light, some do not)
//! traces one closest-hit ray towards the light's centre; where that ray
//! is clear (the lit half of the penumbra), one more from the blocked
//! node nearest the point. The first hit gives z, and so the radius
//! r_i = R·z / (D − z) the light's penumbra wants at the point.
//!
//! A half-ball of the light mesh's own step h resolves one width of
//! penumbra well, 2·kI·h: with fewer nodes its shares turn coarse, and it
//! cannot reach further. So the light's share is taken over the lamp's
//! disk as the point sees it, a disk of radius r_i across the light's
//! direction (`super::lamp_disk`), its samples answered by the nodes of
//! the lattice level whose radius kI·h_k comes nearest r_i, h_k = h·2^k
//! for k from [`FINEST_LEVEL`] to [`COARSEST_LEVEL`] (the levels share
//! the mesh's origin, so a coarser level's nodes are nodes of the mesh):
//! narrow at a contact, wide far from the occluder. The disk has r_i
//! itself, not the level's kI·h_k: a level stands for radii up to √2 from
//! its own, and a disk that much too wide darkened the lit side of every
//! penumbra (STUDY.md, "Grazing lamps"). A level node's answer is its
//! segment's to the light: read from the mesh's masks where the node is
//! the mesh's and its bit is known, remembered from a neighbouring point
//! ([`LevelScratch`]), or traced; nothing is kept between frames. Below
//! the finest level the light is taken as visible or not as the centre ray
//! found: a hard shadow, which is what the lamp gives there.
//!
//! Points whose nodes all agree on a light (far from any shadow edge, most
//! points) trace nothing and keep their value; with `penumbra: wide`,
//! those whose wide set disagrees on a lamp are sized too (`super::wide`),
//! and so are those a lamp grazes where one ray finds the lamp's part
//! nearest the surface hidden ([`grazing_estimate`]).
//! Nothing here is kept from frame to frame, so reuse of the masks stays
//! exact.

use glam::{IVec3, Vec3};
use std::hash::BuildHasher;

use rustc_hash::FxBuildHasher;
use serde::{Deserialize, Serialize};

use super::lattice::Lattice;
use crate::accel::{Ray, StaticTriangle, World};
use crate::render::light::{segment_to_lamp, RenderLight};

/// How formula (2) sizes each light's interpolation set.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Penumbra {
    /// The paper's: one radius kI·h for every light and point.
    Fixed,
    /// Each lamp's radius from the distance to its blocker, where the
    /// point's nodes disagree on it (closer to a real lamp than `fixed` on
    /// every scene of STUDY.md); lights without a lamp radius keep kI·h.
    Blocker,
    /// As `blocker`, and also where the half-ball cannot see a penumbra:
    /// where the point's wide set (the half-ball of twice the radius on
    /// every other node, `super::wide`) disagrees on a lamp its own nodes
    /// agree on, so a penumbra wider than kI·h reaches every point in it;
    /// and where a lamp grazes the surface, so the wedge beside an
    /// occluder standing on it is found ([`grazing_estimate`]). The
    /// closest to a real lamp on every scene of STUDY.md, at the cost
    /// BENCHMARKS.md measures.
    #[default]
    Wide,
}

impl Penumbra {
    /// Whether lamps' penumbrae are sized by their blockers.
    pub fn sizes_by_blocker(self) -> bool {
        self != Penumbra::Fixed
    }

    /// Whether points also ask their wide set.
    pub fn asks_wide_set(self) -> bool {
        self == Penumbra::Wide
    }

    /// Whether lamps every node sees are probed at grazing incidence
    /// ([`grazing_estimate`]).
    pub fn probes_grazing_lamps(self) -> bool {
        self == Penumbra::Wide
    }
}

/// The finest and the coarsest level a penumbra's set is taken from, as
/// powers of two of the light mesh's step.
pub const FINEST_LEVEL: i32 = -3;
pub const COARSEST_LEVEL: i32 = 3;

/// What the rays towards one light found at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockerEstimate {
    /// The radius the light's penumbra wants at the point; `None` where
    /// nothing could be found to size it by.
    pub radius: Option<f32>,
    /// Whether the ray from the point to the light's centre is clear.
    pub centre_visible: bool,
    /// Closest-hit rays traced: one or two.
    pub rays: u64,
}

/// The physical penumbra radius of `light` at the point whose ray origin
/// is `origin`, for a set whose blocked node nearest the point lies at
/// `nearest_blocked`. Returns `None` for a light without a lamp to size a
/// penumbra by: a directional light, or a point light of radius 0, whose
/// shadow the light mesh softens by kI·h alone, as the paper does (a
/// physical radius of 0 would draw it hard, which is Whitted's shadow at
/// the light mesh's cost).
pub fn estimate(
    origin: Vec3,
    light: &RenderLight,
    nearest_blocked: Vec3,
    world: &World,
) -> Option<BlockerEstimate> {
    let centre = light.position()?;
    if light.lamp_radius <= 0.0 {
        return None;
    }
    let centre_blocker = blocker_distance(&light.shadow_ray(origin), centre, world);
    let centre_visible = centre_blocker.is_none();
    // A blocked node whose own segment is found clear can only be one the
    // dynamic layer marked, since moved away: nothing to size by.
    let blocker = centre_blocker
        .or_else(|| blocker_distance(&light.shadow_ray(nearest_blocked), centre, world));
    Some(BlockerEstimate {
        radius: blocker.map(|blocker| penumbra_radius(light.lamp_radius, blocker)),
        centre_visible,
        rays: 1 + centre_visible as u64,
    })
}

/// Lamps whose centre lies within this cosine of a surface's tangent
/// plane (seen from the point, against its normal) graze it.
pub const GRAZING_COSINE: f32 = 0.3;

/// The penumbra radius at a point on a surface of normal `normal` whose
/// nodes all see a lamp that grazes it: the blocker of one ray towards
/// the lamp's point nearest the surface. A half-ball stands above the
/// surface, so its nodes sample only the half of the lamp's disk away
/// from it: at grazing incidence an occluder standing on the surface (a
/// pilaster on a wall) hides the lamp's near half from points in a thin
/// wedge beside its shadow, and every node there sees the lamp. The ray
/// finds that occluder. Returns `None` for a light without a lamp or not
/// grazing the surface (nothing traced); the estimate's radius is `None`
/// where the ray is clear.
pub fn grazing_estimate(
    origin: Vec3,
    normal: Vec3,
    light: &RenderLight,
    world: &World,
) -> Option<BlockerEstimate> {
    let centre = light.position()?;
    let to_lamp = centre - origin;
    let height = to_lamp.dot(normal);
    let grazing = height > 0.0 && height < GRAZING_COSINE * to_lamp.length();
    if light.lamp_radius <= 0.0 || !grazing {
        return None;
    }
    // Nearest the surface, but above its tangent plane.
    let lowest = centre - normal * light.lamp_radius.min(0.5 * height);
    let ray = segment_to_lamp(origin, lowest);
    let Some(lowest_blocker) = blocker_distance(&ray, lowest, world) else {
        return Some(BlockerEstimate {
            radius: None,
            centre_visible: true,
            rays: 1,
        });
    };
    // The nodes see the centre, the point need not: its own ray decides
    // the hard answer, and sizes the penumbra where it is blocked.
    let centre_blocker = blocker_distance(&light.shadow_ray(origin), centre, world);
    let blocker = centre_blocker.unwrap_or(lowest_blocker);
    Some(BlockerEstimate {
        radius: Some(penumbra_radius(light.lamp_radius, blocker)),
        centre_visible: centre_blocker.is_none(),
        rays: 2,
    })
}

/// R·z / (D − z): the penumbra radius, at the point, of a lamp of radius
/// `lamp_radius` behind a blocker at distance z of a ray of length D.
fn penumbra_radius(lamp_radius: f32, (z, distance): (f32, f32)) -> f32 {
    lamp_radius * z / (distance - z).max(f32::MIN_POSITIVE)
}

/// The level of `mesh_lattice` whose half-ball radius `ki`·h_k comes
/// nearest `radius` by ratio (the boundaries between levels lie at
/// √2·2^k of the mesh's own radius), or `None` where `radius` is below
/// the finest level's lower boundary: too narrow a penumbra for any level
/// to resolve. Only comparisons with exact powers of two of one constant
/// decide it, so the GPU picks the same level.
pub fn level(mesh_lattice: Lattice, ki: f32, radius: f32) -> Option<Lattice> {
    let steps = radius / (ki * mesh_lattice.h);
    let boundary = |level: i32| std::f32::consts::SQRT_2 * power_of_two(level);
    if steps.is_nan() || steps < boundary(FINEST_LEVEL - 1) {
        return None;
    }
    let level = (FINEST_LEVEL..COARSEST_LEVEL)
        .find(|&level| steps < boundary(level))
        .unwrap_or(COARSEST_LEVEL);
    Some(Lattice {
        origin: mesh_lattice.origin,
        h: mesh_lattice.h * power_of_two(level),
    })
}

/// 2^`exponent`, exactly (from its bits: `exp2` need not be exact).
fn power_of_two(exponent: i32) -> f32 {
    f32::from_bits(((127 + exponent) as u32) << 23)
}

/// One thread's working space for the lattice levels: the nodes of the
/// lamp disk at hand (`super::lamp_disk`), the answers its points'
/// segments gave, and per light the static triangle its last blocked
/// segment crossed (the next segments to that light, from nodes close by,
/// mostly cross it too: one triangle test instead of a walk, with the
/// walk's answer).
#[derive(Default)]
pub struct LevelScratch {
    pub nodes: Vec<(IVec3, f32)>,
    pub answers: LevelAnswers,
    pub blockers: Vec<Option<StaticTriangle>>,
}

/// Which level nodes see which lights, as one thread's points traced
/// them. A point's neighbours want mostly the same nodes of the same
/// level (a pixel is a centimetre or two, a level's step several), and a
/// segment's answer does not depend on the point that asked, so an answer
/// looked up here is the one tracing gives and frames keep their bits.
/// Levels are told apart by their step h (exact powers of two of the
/// mesh's, so equal steps are equal levels).
///
/// The table is direct-mapped: a segment has one slot, by a hash of it,
/// and a segment that hashes there later takes the slot over. A lookup is
/// one probe, with nothing to grow or empty, which costs less than the
/// hash map it replaced (the 64-lamp bench asks 53 M times a frame). It
/// is made per thread and frame: nothing is kept between frames.
#[derive(Default)]
pub struct LevelAnswers {
    /// Allocated on the first question: only `blocker` and `wide` ask.
    slots: Vec<Option<(Segment, bool)>>,
}

/// A level node's segment to a light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
struct Segment {
    step: u32,
    node: IVec3,
    light: usize,
}

impl LevelAnswers {
    /// 2^16 slots, about 2 MiB per thread (a hash map of as many answers
    /// found almost as many; four times as many found 3% more and made
    /// the frame slower).
    const SLOT_BITS: u32 = 16;

    /// Whether `node` of `level` sees light number `light`, from what
    /// was traced before or else by `trace`; and whether it was traced.
    pub fn sees(
        &mut self,
        level: Lattice,
        node: IVec3,
        light: usize,
        trace: impl FnOnce() -> bool,
    ) -> (bool, bool) {
        if self.slots.is_empty() {
            self.slots = vec![None; 1 << Self::SLOT_BITS];
        }
        let segment = Segment {
            step: level.h.to_bits(),
            node,
            light,
        };
        let slot = &mut self.slots[Self::slot_of(segment)];
        match *slot {
            Some((held, sees)) if held == segment => (sees, false),
            _ => {
                let sees = trace();
                *slot = Some((segment, sees));
                (sees, true)
            }
        }
    }

    fn slot_of(segment: Segment) -> usize {
        // Fx hashes mix into their high bits.
        let hash = FxBuildHasher.hash_one(segment);
        (hash >> (u64::BITS - Self::SLOT_BITS)) as usize
    }
}

/// The distance from `ray`'s origin to the first thing it hits, and from
/// its origin to `target`, the lamp's point it is aimed at.
fn blocker_distance(ray: &Ray, target: Vec3, world: &World) -> Option<(f32, f32)> {
    let hit = world.closest_hit(ray)?;
    let distance = (target - ray.origin).length();
    Some((hit.t * distance, distance))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::world::WorldObject;
    use crate::render::light::LightSource;
    use glam::Affine3A;

    /// A floor at y = 0 and, along z, the lamp-side face of a curb 7 cm
    /// high at x = 0.1 (the face is what shadows the floor beyond it).
    fn floor_and_curb() -> World {
        let floor = [
            Vec3::new(-4.0, 0.0, -4.0),
            Vec3::new(4.0, 0.0, -4.0),
            Vec3::new(4.0, 0.0, 4.0),
            Vec3::new(-4.0, 0.0, 4.0),
        ];
        let curb = [
            Vec3::new(0.1, 0.0, -4.0),
            Vec3::new(0.1, 0.07, -4.0),
            Vec3::new(0.1, 0.07, 4.0),
            Vec3::new(0.1, 0.0, 4.0),
        ];
        let quad = [[0, 2, 1], [0, 3, 2]];
        let object = |positions| WorldObject {
            positions,
            triangles: &quad,
            to_render: Affine3A::IDENTITY,
            dynamic: false,
        };
        World::build(&[object(&floor), object(&curb)])
    }

    fn lamp(position: Vec3, lamp_radius: f32) -> RenderLight {
        RenderLight {
            source: LightSource::Point { position },
            power: Vec3::ONE,
            range: None,
            lamp_radius,
        }
    }

    /// A lamp 30 cm above the floor, 1.5 m from the curb, radius 10 cm:
    /// it meets the floor beyond the curb at cos θ ≈ 0.1.
    const GRAZING_LAMP: Vec3 = Vec3::new(-1.5, 0.3, 0.0);

    fn on_floor(x: f32) -> Vec3 {
        Vec3::new(x, 1e-4, 0.0)
    }

    #[test]
    fn a_grazing_lamp_is_sized_by_what_hides_its_part_nearest_the_surface() {
        let world = floor_and_curb();
        let light = lamp(GRAZING_LAMP, 0.1);
        // In the wedge: the curb hides the lamp's lowest point, not its
        // centre. The blocker is the curb, 0.7 m along the ray's 2.3.
        let origin = on_floor(0.8);
        let estimate = grazing_estimate(origin, Vec3::Y, &light, &world).expect("grazing");
        assert!(estimate.centre_visible);
        assert_eq!(estimate.rays, 2);
        let lowest = GRAZING_LAMP - Vec3::Y * 0.1;
        let distance = (lowest - origin).length();
        let z = distance * (0.7 / 2.3);
        let expected = 0.1 * z / (distance - z);
        let radius = estimate.radius.expect("a blocker");
        assert!(
            (radius - expected).abs() < 1e-4,
            "{radius} against {expected}"
        );
        // Further out the whole lamp clears the curb: one clear ray.
        let clear = grazing_estimate(on_floor(1.5), Vec3::Y, &light, &world).expect("grazing");
        assert_eq!(
            (clear.radius, clear.centre_visible, clear.rays),
            (None, true, 1)
        );
        // Close behind the curb it hides the centre too: the hard answer
        // is the centre's, and so is the blocker.
        let behind = grazing_estimate(on_floor(0.3), Vec3::Y, &light, &world).expect("grazing");
        assert!(!behind.centre_visible && behind.radius.is_some());
    }

    #[test]
    fn lamps_that_do_not_graze_or_have_no_radius_trace_nothing() {
        let world = floor_and_curb();
        let origin = on_floor(0.8);
        let estimate = |light: &RenderLight| grazing_estimate(origin, Vec3::Y, light, &world);
        // Overhead; in the tangent plane; under it; a bare point light.
        assert_eq!(estimate(&lamp(Vec3::new(0.8, 2.0, 0.0), 0.1)), None);
        assert_eq!(estimate(&lamp(Vec3::new(-1.5, 1e-4, 0.0), 0.1)), None);
        assert_eq!(estimate(&lamp(Vec3::new(-1.5, -0.3, 0.0), 0.1)), None);
        assert_eq!(estimate(&lamp(GRAZING_LAMP, 0.0)), None);
        let sun = RenderLight {
            source: LightSource::Directional {
                towards: Vec3::new(-1.0, 0.1, 0.0).normalize(),
            },
            ..lamp(GRAZING_LAMP, 0.1)
        };
        assert_eq!(estimate(&sun), None);
        // A lamp whose radius reaches under the tangent plane is probed
        // at half its centre's height, above the floor: clear here.
        let low = estimate(&lamp(Vec3::new(3.0, 0.05, 0.0), 0.1)).expect("grazing");
        assert_eq!(low.radius, None);
    }

    #[test]
    fn a_level_node_is_traced_once_per_light_and_level_until_the_scratch_fills() {
        let mesh = Lattice::new(0.1);
        let finer = level(mesh, 2.5, 0.12).expect("a level");
        let mut levels = LevelAnswers::default();
        let node = IVec3::new(3, -1, 7);
        assert_eq!(levels.sees(mesh, node, 0, || true), (true, true));
        assert_eq!(
            levels.sees(mesh, node, 0, || panic!("traced twice")),
            (true, false)
        );
        // Another light, or the same node numbers on another level, are
        // other segments.
        assert_eq!(levels.sees(mesh, node, 1, || false), (false, true));
        assert_eq!(levels.sees(finer, node, 0, || false), (false, true));
        assert_eq!(levels.sees(finer, node, 0, || true), (false, false));
        // A segment that takes its slot over puts it back to tracing.
        let segment = |node| Segment {
            step: mesh.h.to_bits(),
            node,
            light: 0,
        };
        let slot = LevelAnswers::slot_of(segment(node));
        let other = (0..)
            .map(|x| IVec3::new(x, 5, 5))
            .find(|&other| LevelAnswers::slot_of(segment(other)) == slot)
            .expect("a segment with the same slot");
        assert_eq!(levels.sees(mesh, other, 0, || false), (false, true));
        assert_eq!(levels.sees(mesh, node, 0, || true), (true, true));
        assert_eq!(levels.slots.len(), 1 << LevelAnswers::SLOT_BITS);
    }

    #[test]
    fn the_level_follows_the_radius_by_powers_of_two() {
        let mesh = Lattice::new(0.1);
        let h_of = |radius| level(mesh, 2.5, radius).map(|lattice| lattice.h);
        assert_eq!(h_of(0.25), Some(0.1));
        assert_eq!(h_of(0.5), Some(0.2));
        assert_eq!(h_of(0.12), Some(0.05));
        // Past the coarsest and the finest levels.
        assert_eq!(h_of(100.0), Some(0.8));
        assert_eq!(h_of(0.25 / 8.0), Some(0.0125));
        assert_eq!(h_of(0.25 / 11.0), Some(0.0125));
        assert_eq!(h_of(0.25 / 12.0), None);
        assert_eq!(h_of(0.0), None);
        assert_eq!(h_of(f32::NAN), None);
        // The boundary between levels 0 and 1 is √2 steps of the mesh.
        let boundary = 2.5 * 0.1 * std::f32::consts::SQRT_2;
        assert_eq!(h_of(boundary * 0.999), Some(0.1));
        assert_eq!(h_of(boundary * 1.001), Some(0.2));
        assert_eq!(level(mesh, 2.5, 0.5).unwrap().origin, mesh.origin);
    }
}
