//! The light mesh's lattice: node (i, j, k) sits at `origin + h·(i, j, k)`,
//! integer coordinates, no bound on extent. The origin is fixed per scene
//! (in render space, which is itself fixed per sequence), so a node is the
//! same node in every frame and its mask can be reused.

use bytemuck::cast;
use glam::{IVec3, Vec3};
use wide::{f32x8, i32x8};

use crate::bits::set_bits;

/// Where the lattice origin sits inside a cell, as a fraction of `h` per
/// axis. Scenes are modelled on round coordinates (floors at y = 0, walls on
/// whole metres); an irrational-looking offset keeps nodes off those planes,
/// so the common case is the general position the paper's counts assume.
/// Tests that want nodes on surfaces set the origin explicitly.
pub const GENERAL_POSITION: Vec3 = Vec3::new(0.382_683_4, 0.414_213_57, 0.447_213_6);

/// Node coordinates must stay well inside `i32` so that brick arithmetic
/// and neighbour offsets cannot overflow.
pub const MAX_NODE_COORDINATE: f32 = (1 << 28) as f32;

/// The largest interpolation radius, in steps (kI): the paper uses 2.1–3;
/// at 8 a point already averages a thousand nodes. Settings refuse more.
pub const MAX_KI: f32 = 8.0;

/// ⌊v⌋ per axis, the very values `Vec3::floor` gives (−0 and NaN
/// included). On the x86-64 baseline `f32::floor` is a libm call (its
/// instruction needs SSE4.1), a percent of a light-mesh frame spent on
/// the half-ball's box, the lamp disk's samples and the tile of a point.
///
/// Written per axis rather than with `array::map`, whose closures one
/// build left as calls on a hot path (`accel::wide::WideNode::child_box`).
pub fn floor(v: Vec3) -> Vec3 {
    Vec3::new(floor_f32(v.x), floor_f32(v.y), floor_f32(v.z))
}

/// ⌈v⌉ per axis, the very values `Vec3::ceil` gives; see [`floor`].
pub fn ceil(v: Vec3) -> Vec3 {
    -floor(-v)
}

/// 2^23: from there on in magnitude every f32 is an integer (or infinite,
/// or NaN), its own floor.
const EXACT_INTEGERS: f32 = 8_388_608.0;

/// `x.floor()` by truncation: below 2^23 in magnitude the cast to `i32`
/// and back is exact, from there on every f32 is an integer (or infinite,
/// or NaN) and is its own floor. The sign is put back for −0, the one
/// input whose floor truncation gets wrong besides the negatives it
/// corrects by one.
fn floor_f32(x: f32) -> f32 {
    if x.is_nan() || x.abs() >= EXACT_INTEGERS {
        return x;
    }
    let truncated = x as i32 as f32;
    let floor = match truncated > x {
        true => truncated - 1.0,
        false => truncated,
    };
    floor.copysign(x)
}

/// `floor(x) as i32` in each of eight lanes: the node coordinate, with
/// `as`'s saturation (and 0 for NaN), as [`floor`] and the cast give it
/// lane by lane. Truncation (`trunc_int` saturates as `as` does) is the
/// floor but where it rounded a negative up, which shows as the
/// truncation's value above `x`; below −2^23 every f32 is an integer,
/// and below −2^31 the saturated truncation lies above `x` with nothing
/// to correct.
pub fn floor_ints(x: f32x8) -> i32x8 {
    let truncated = x.trunc_int();
    let rounded_up = truncated.round_float().simd_gt(x) & x.simd_gt(f32x8::splat(-EXACT_INTEGERS));
    // A set lane of the mask is −1 as an integer.
    truncated + cast::<f32x8, i32x8>(rounded_up)
}

/// Most nodes along one axis of a half-ball's box.
pub(crate) const MAX_SPAN: usize = 2 * MAX_KI as usize + 1;
/// [`MAX_SPAN`] rounded up to whole rows of eight SIMD lanes.
const PADDED_SPAN: usize = MAX_SPAN.next_multiple_of(8);

/// Up to eight nodes of a row along x: node `first + (i, 0, 0)` for each
/// bit i of `lanes`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Row {
    pub first: IVec3,
    pub lanes: u8,
}

impl Row {
    pub fn nodes(self) -> impl Iterator<Item = IVec3> {
        set_bits(self.lanes.into()).map(move |lane| self.first + IVec3::new(lane as i32, 0, 0))
    }
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lattice {
    pub origin: Vec3,
    /// Node spacing in metres.
    pub h: f32,
}

impl Lattice {
    /// A lattice of step `h` in general position relative to render space.
    pub fn new(h: f32) -> Lattice {
        Lattice {
            origin: GENERAL_POSITION * h,
            h,
        }
    }

    pub fn node_position(&self, node: IVec3) -> Vec3 {
        self.origin + self.h * node.as_vec3()
    }

    /// |node − p|², rounded as [`Lattice::half_ball`] rounds it: per-axis
    /// offsets, then (x² + y²) + z².
    pub fn distance_squared(&self, node: IVec3, p: Vec3) -> f32 {
        let offset = |axis: usize| (self.origin[axis] + self.h * node[axis] as f32) - p[axis];
        let (x, y, z) = (offset(0), offset(1), offset(2));
        (x * x + y * y) + z * z
    }

    /// `p` in steps from the origin: node coordinates, fractional.
    pub fn local(&self, p: Vec3) -> Vec3 {
        (p - self.origin) / self.h
    }

    /// Whether every node within `radius` of `p` has a representable
    /// coordinate.
    pub fn covers(&self, p: Vec3, radius: f32) -> bool {
        let far = ((p - self.origin).abs() + Vec3::splat(radius)) / self.h;
        far.max_element() < MAX_NODE_COORDINATE
    }

    /// How far from the tangent plane at `p` a node still counts as on it
    /// (see [`Lattice::half_ball`]): the rounding of node positions and
    /// surface points of this magnitude.
    fn on_plane_tolerance(&self, p: Vec3, radius: f32) -> f32 {
        8.0 * f32::EPSILON * (p.abs().max_element() + self.origin.abs().max_element() + radius)
    }

    /// Steps 1 and 2 of the paper: the nodes `x` with `|x − p| ≤ radius` and
    /// `(n, x − p) > 0`, appended to `out` in a fixed order (k, j, i).
    /// A node on the tangent plane (including `p` itself when it is a node)
    /// fails step 2: it is not on the visible side. "On" allows for the
    /// rounding of node positions and surface points (a few ULPs of the
    /// coordinates), so a floor lying on a lattice plane loses all of its
    /// in-plane nodes rather than a random half of them.
    ///
    /// `radius` is at most [`MAX_KI`] steps.
    pub fn half_ball(&self, p: Vec3, n: Vec3, radius: f32, out: &mut Vec<IVec3>) {
        self.half_ball_rows(p, n, radius, |row| out.extend(row.nodes()));
    }

    /// [`Lattice::half_ball`]'s nodes a row at a time, in the same order:
    /// `visit` gets each row along x that holds some. Where a caller
    /// handles a row as a whole (one brick lookup for its nodes), this
    /// spares it a list of nodes.
    pub fn half_ball_rows(&self, p: Vec3, n: Vec3, radius: f32, visit: impl FnMut(Row)) {
        let on_plane = self.on_plane_tolerance(p, radius);
        self.rows_in_front(p, n, radius, on_plane, visit);
    }

    /// Rows holding every node of the half-balls of radius `radius` of the
    /// points `q` with normal `n` that lie within `spread` of `p`: the ball
    /// about `p` grown by the distance, its plane lowered by the offset,
    /// both with a margin for rounding that outgrows the coordinates' (see
    /// [`Spread::grown`]). Demand walks this once for a run of such points
    /// instead of each one's half-ball: it needs more nodes than they do
    /// (their union's rim, a thin layer behind the plane), never fewer.
    ///
    /// Where that ball would exceed [`MAX_KI`] steps, [`Spread::fits`]
    /// said no such run forms.
    pub fn spread_half_ball_rows(
        &self,
        p: Vec3,
        n: Vec3,
        radius: f32,
        spread: Spread,
        visit: impl FnMut(Row),
    ) {
        let (grown, plane) = spread.grown(self, p, radius);
        self.rows_in_front(p, n, grown, plane, visit);
    }

    /// The rows of nodes `x` with |x − p| ≤ `radius` and (n, x − p) >
    /// `plane`, in [`Lattice::half_ball`]'s order.
    fn rows_in_front(&self, p: Vec3, n: Vec3, radius: f32, plane: f32, mut visit: impl FnMut(Row)) {
        let local = self.local(p);
        let reach = radius / self.h;
        assert!(
            reach <= MAX_KI,
            "half-ball radius of {reach} steps; at most {MAX_KI}"
        );
        let low = ceil(local - Vec3::splat(reach)).as_ivec3();
        let high = floor(local + Vec3::splat(reach)).as_ivec3();
        let radius_squared = radius * radius;
        // Offsets per axis, computed once: `node_position(node) - p` for
        // each coordinate, exactly as a per-node evaluation would round it.
        // Slots past the span stay infinite: no ball holds them.
        let offsets = |axis: usize, from: i32, to: i32| {
            let mut along = [f32::INFINITY; PADDED_SPAN];
            for (slot, index) in along.iter_mut().zip(from..=to) {
                *slot = (self.origin[axis] + self.h * index as f32) - p[axis];
            }
            along
        };
        let (x, y, z) = (
            offsets(0, low.x, high.x),
            offsets(1, low.y, high.y),
            offsets(2, low.z, high.z),
        );
        let span = |from: i32, to: i32| (to - from + 1).clamp(0, MAX_SPAN as i32) as usize;
        // A row of nodes along x is tested eight at a time, with the
        // arithmetic of `length_squared` and `dot` on each node's offset
        // (same operations, same order, same rounding).
        let x_blocks = span(low.x, high.x).div_ceil(8);
        let x_lanes: [(f32x8, f32x8); PADDED_SPAN / 8] = std::array::from_fn(|block| {
            let dx = f32x8::new(std::array::from_fn(|lane| x[block * 8 + lane]));
            (dx * dx, f32x8::splat(n.x) * dx)
        });
        let radius_lanes = f32x8::splat(radius_squared);
        let plane_lanes = f32x8::splat(plane);
        for (kz, &dz) in z[..span(low.z, high.z)].iter().enumerate() {
            for (jy, &dy) in y[..span(low.y, high.y)].iter().enumerate() {
                // (x² + y²) + z² ≥ y² + z² in rounded arithmetic too: a row
                // whose centre misses the ball has no node in it.
                if dy * dy + dz * dz > radius_squared {
                    continue;
                }
                let (dy2, dz2) = (f32x8::splat(dy * dy), f32x8::splat(dz * dz));
                let (ny, nz) = (f32x8::splat(n.y * dy), f32x8::splat(n.z * dz));
                for (block, &(dx2, nx)) in x_lanes[..x_blocks].iter().enumerate() {
                    let inside = (dx2 + dy2 + dz2).simd_le(radius_lanes)
                        & (nx + ny + nz).simd_gt(plane_lanes);
                    let lanes = inside.to_bitmask() as u8;
                    if lanes != 0 {
                        let first = low + IVec3::new((block * 8) as i32, jy as i32, kz as i32);
                        visit(Row { first, lanes });
                    }
                }
            }
        }
    }
}

/// How far the points of a run lie from its first point `p` (all with its
/// normal n): the largest |q − p| and |(n, q − p)|.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Spread {
    pub distance: f32,
    pub offset: f32,
}

/// The rounding allowance of [`Spread::grown`], relative to the grown
/// radius: far above the few ULPs by which a point's rounded distances and
/// dot products can differ from the leader's (ten or so epsilons).
const SPREAD_MARGIN: f32 = 1e-5;

impl Spread {
    /// The spread that also holds `q`, a point with the leader's normal.
    pub fn holding(self, p: Vec3, n: Vec3, q: Vec3) -> Spread {
        Spread {
            distance: self.distance.max((q - p).length()),
            offset: self.offset.max(n.dot(q - p).abs()),
        }
    }

    /// The grown radius and the lowered plane of
    /// [`Lattice::spread_half_ball_rows`] about `p`. A node of a run
    /// point's half-ball is within `radius` of it and in front of its plane
    /// as rounded; so it is within `radius + distance` of `p` and above
    /// `−offset` from p's plane, up to the rounding of both points'
    /// offsets and of their box of nodes (steps from the origin, whose
    /// error grows with the coordinates). Twice
    /// [`Lattice::on_plane_tolerance`] covers the latter, and
    /// [`SPREAD_MARGIN`] the former.
    fn grown(self, lattice: &Lattice, p: Vec3, radius: f32) -> (f32, f32) {
        let reach = radius + self.distance;
        let absolute = 2.0 * lattice.on_plane_tolerance(p, reach);
        let grown = reach * (1.0 + SPREAD_MARGIN) + absolute;
        let plane = -(self.offset * (1.0 + SPREAD_MARGIN) + SPREAD_MARGIN * grown + absolute);
        (grown, plane)
    }

    /// Whether the grown ball about `p` stays within [`MAX_KI`] steps.
    pub fn fits(self, lattice: &Lattice, p: Vec3, radius: f32) -> bool {
        self.grown(lattice, p, radius).0 / lattice.h <= MAX_KI
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every kind of f32: zeros of both signs, halves, just below and
    /// above integers, the last fractions below 2^23, integers beyond,
    /// the edges of i32, the largest values, infinities and NaN, and a
    /// hundred thousand each of random bits and random fractions.
    fn every_kind_of_f32() -> Vec<f32> {
        let mut values = vec![
            0.0f32,
            -0.0,
            0.5,
            -0.5,
            1.0,
            -1.0,
            0.999_999_94,
            -0.999_999_94,
            1e-45,
            -1e-45,
            1e-30,
            -1e-30,
            8_388_607.5,
            -8_388_607.5,
            8_388_608.0,
            -8_388_608.0,
            16_777_217.0,
            3e9,
            -3e9,
            2_147_483_648.0,
            -2_147_483_648.0,
            -2_147_483_904.0,
            f32::NAN,
            f32::MAX,
            f32::MIN,
            f32::INFINITY,
            f32::NEG_INFINITY,
            2.5e-8,
            -123.456,
        ];
        let mut state = 0x2545_f491_4f6c_dd1du64;
        for _ in 0..100_000 {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            values.push(f32::from_bits(state as u32));
            values.push((state as i32 as f32) / 1024.0);
        }
        values
    }

    /// The lattice's floor and ceiling are std's, bit for bit, at every
    /// kind of f32.
    #[test]
    fn floor_and_ceil_are_std_bit_for_bit() {
        for x in every_kind_of_f32() {
            let v = Vec3::splat(x);
            let same =
                |a: Vec3, b: Vec3| (a.x.is_nan() && b.x.is_nan()) || a.x.to_bits() == b.x.to_bits();
            assert!(same(floor(v), v.floor()), "floor of {x:e}");
            assert!(same(ceil(v), v.ceil()), "ceil of {x:e}");
        }
    }

    /// Eight lanes' floors as integers are `floor(x) as i32`, saturated
    /// and 0 for NaN, at every kind of f32.
    #[test]
    fn floor_ints_are_the_floors_cast() {
        let values = every_kind_of_f32();
        for lanes in values.chunks_exact(8) {
            let lanes: [f32; 8] = lanes.try_into().unwrap();
            let expected = lanes.map(|x| floor(Vec3::splat(x)).x as i32);
            assert_eq!(
                floor_ints(f32x8::new(lanes)).to_array(),
                expected,
                "{lanes:?}"
            );
        }
    }

    fn count(lattice: &Lattice, p: Vec3, n: Vec3, radius: f32) -> usize {
        let mut nodes = Vec::new();
        lattice.half_ball(p, n, radius, &mut nodes);
        nodes.len()
    }

    #[test]
    fn half_ball_holds_nodes_within_the_radius_on_the_normal_side() {
        let lattice = Lattice::new(0.5);
        let p = Vec3::new(0.3, 0.7, -0.2);
        let n = Vec3::new(0.1, 1.0, 0.2).normalize();
        let mut nodes = Vec::new();
        lattice.half_ball(p, n, 1.25, &mut nodes);
        assert!(!nodes.is_empty());
        for node in &nodes {
            let x = lattice.node_position(*node);
            assert!((x - p).length() <= 1.25 && n.dot(x - p) > 0.0);
        }
        // Brute force over a generous box finds the same set.
        let mut brute = 0;
        for k in -10..10 {
            for j in -10..10 {
                for i in -10..10 {
                    let x = lattice.node_position(IVec3::new(i, j, k));
                    brute +=
                        ((x - p).length_squared() <= 1.25 * 1.25 && n.dot(x - p) > 0.0) as usize;
                }
            }
        }
        assert_eq!(nodes.len(), brute);
    }

    proptest::proptest! {
        /// The rows tested eight nodes at a time find exactly the nodes a
        /// node-by-node test finds, in (k, j, i) order, for radii up to
        /// [`MAX_KI`] steps (rows of up to three lane blocks).
        #[test]
        fn half_ball_equals_the_node_by_node_test(
            p in proptest::array::uniform3(-40.0f32..40.0),
            n in proptest::array::uniform3(-1.0f32..1.0),
            h in 0.05f32..2.0,
            ki in 1.0f32..MAX_KI,
            on_axes in proptest::bool::ANY,
        ) {
            let lattice = Lattice::new(h);
            // Floors and walls: a normal along the axes, and the point on
            // the lattice's planes through a node, where rows of nodes lie
            // on the tangent plane itself.
            let (p, n) = match on_axes {
                true => (
                    lattice.node_position(lattice.local(Vec3::from(p)).round().as_ivec3()),
                    Vec3::from(n).round().normalize_or(Vec3::Y),
                ),
                false => (Vec3::from(p), Vec3::from(n).normalize_or(Vec3::Y)),
            };
            let radius = ki * h;
            let mut nodes = Vec::new();
            lattice.half_ball(p, n, radius, &mut nodes);
            let centre = ((p - lattice.origin) / h).round().as_ivec3();
            let reach = MAX_KI as i32 + 1;
            let mut brute = Vec::new();
            for k in -reach..=reach {
                for j in -reach..=reach {
                    for i in -reach..=reach {
                        let node = centre + IVec3::new(i, j, k);
                        let offset = lattice.node_position(node) - p;
                        let inside = lattice.distance_squared(node, p) <= radius * radius;
                        proptest::prop_assert_eq!(inside, offset.length_squared() <= radius * radius);
                        if inside
                            && n.dot(offset) > lattice.on_plane_tolerance(p, radius)
                        {
                            brute.push(node);
                        }
                    }
                }
            }
            proptest::prop_assert_eq!(nodes, brute);
        }
    }

    proptest::proptest! {
        /// A run's grown ball holds every node of each of its points'
        /// half-balls: points scattered within the spread of the first, on
        /// its plane to rounding or just off it, at coordinates up to 1e5
        /// steps from the origin (where the node positions' rounding is
        /// a fair part of a step), on the lattice's nodes and planes, with
        /// normals along the axes, grazing them and anywhere.
        #[test]
        fn a_spread_ball_holds_every_run_points_half_ball(
            first in proptest::array::uniform3(-1.0f32..1.0),
            scale in proptest::sample::select(vec![4.0f32, 40.0, 4e3, 1e5]),
            n in proptest::array::uniform3(-1.0f32..1.0),
            normal in 0..3,
            on_lattice in proptest::bool::ANY,
            ki in 1.0f32..6.0,
            along in proptest::collection::vec(
                (proptest::array::uniform3(-1.0f32..1.0), -1.0f32..1.0),
                1..8,
            ),
        ) {
            let h = 0.1;
            let lattice = match on_lattice {
                true => Lattice { origin: Vec3::ZERO, h },
                false => Lattice::new(h),
            };
            let mut p = Vec3::from(first) * scale * h;
            let n = match normal {
                0 => Vec3::from(n).round().normalize_or(Vec3::Y),
                1 => Vec3::new(1.0, 1e-3, 0.0).normalize(),
                _ => Vec3::from(n).normalize_or(Vec3::Y),
            };
            if on_lattice {
                p = lattice.node_position(lattice.local(p).round().as_ivec3());
            }
            let radius = ki * h;
            let mut spread = Spread::default();
            let mut points = vec![p];
            for (offset, off_plane) in along {
                let tangent = Vec3::from(offset) - n * n.dot(Vec3::from(offset));
                let q = p + tangent * h + n * (off_plane * h / 16.0);
                spread = spread.holding(p, n, q);
                points.push(q);
            }
            proptest::prop_assume!(spread.fits(&lattice, p, radius));
            let mut grown = Vec::new();
            lattice.spread_half_ball_rows(p, n, radius, spread, |row| grown.extend(row.nodes()));
            for q in points {
                let mut own = Vec::new();
                lattice.half_ball(q, n, radius, &mut own);
                for node in own {
                    proptest::prop_assert!(grown.contains(&node), "{node} of {q} missing");
                }
            }
        }
    }

    #[test]
    fn a_point_on_a_node_excludes_that_node() {
        let lattice = Lattice {
            origin: Vec3::ZERO,
            h: 1.0,
        };
        let p = Vec3::new(2.0, 3.0, 4.0);
        let mut nodes = Vec::new();
        lattice.half_ball(p, Vec3::Y, 1.0, &mut nodes);
        // Radius h around a node: its 6 neighbours; only the one above
        // passes step 2, the 4 on the tangent plane and the node itself fail.
        assert_eq!(nodes, vec![IVec3::new(2, 4, 4)]);
    }

    #[test]
    fn a_plane_on_a_lattice_plane_loses_its_own_nodes() {
        let on_plane = Lattice {
            origin: Vec3::ZERO,
            h: 1.0,
        };
        let general = Lattice::new(1.0);
        let mut total_on = 0;
        let mut total_general = 0;
        for step in 0..200 {
            let p = Vec3::new(step as f32 * 0.137, 0.0, step as f32 * 0.291);
            total_on += count(&on_plane, p, Vec3::Y, 2.5);
            total_general += count(&general, p, Vec3::Y, 2.5);
        }
        assert!(total_on < total_general, "{total_on} vs {total_general}");
    }

    #[test]
    fn coverage_refuses_coordinates_past_the_limit() {
        let lattice = Lattice::new(1e-3);
        assert!(lattice.covers(Vec3::splat(1e3), 1.0));
        assert!(!lattice.covers(Vec3::new(1e6, 0.0, 0.0), 1.0));
    }
}
