//! The level nodes that stand for a lamp's disk as a shading point sees it.
//!
//! A spherical lamp of radius R at distance D, behind an occluder's edge
//! at distance z from the point, is hidden from the point on the part of
//! its disk beyond the edge. A node offset from the point by v, across the
//! light's direction, sees the lamp's centre past that edge where the
//! point sees the lamp's point v·(D − z)/z: the nodes on the disk of
//! radius r = R·z/(D − z) across the light's direction, each asking
//! whether it sees the lamp's centre, sample the lamp's disk as the point
//! sees it. That is the disk `penumbra::level` sizes.
//!
//! A half-ball on the surface samples it only where the light falls
//! straight down: tilted, its nodes stand above the surface and see the
//! shadow where it lies further from the lamp, and half the disk (the
//! part towards the surface) is missing. So the samples are the disk's,
//! spread over it by a fixed pattern ([`DISK`]); a sample under the
//! surface, or too close to it for its nearest node to be above, is moved
//! along its own line to the lamp's centre, which does not change the
//! line it sees the lamp along, until it stands a level step above the
//! surface. (Moved along the point's line instead, parallel to its own, a
//! sample far along it asks about a wider disk than its offset says:
//! under a grazing lamp that drew the lit side of a penumbra too dark.)
//! Each sample's nearest level node answers for it, so neighbouring
//! points ask the same nodes (their answers are remembered,
//! `penumbra::LevelAnswers`) and the GPU, doing the same arithmetic, asks
//! the same ones.
//!
//! STUDY.md measured it against the half-ball moved towards the lamp that
//! it replaces: the boxes' penumbra error fell from 0.38/0.27/0.39 of
//! Whitted's to 0.24/0.15/0.29; the other scenes did not move.

use glam::{IVec3, Vec3};
use wide::f32x8;

use super::lattice::{self, Lattice};
use crate::render::lanes::{dot, each3, splat3};
use crate::render::omega::LANES;

/// Points spread evenly over the unit disk, a Vogel spiral: point i at
/// radius √((i + ½)/N) and angle i times the golden angle. Written as the
/// f32 values both backends read (`light_mesh.wgsl` holds the same list).
pub const DISK: [(f32, f32); 32] = [
    (0.125, 0.0),
    (-0.15964505, 0.14624794),
    (0.024436234, -0.27843827),
    (0.20122224, 0.26245877),
    (-0.36926755, -0.065318234),
    (0.34980246, -0.2225157),
    (-0.11700208, 0.4352419),
    (-0.22313565, -0.42963412),
    (0.48411512, 0.17679806),
    (-0.5036411, 0.20789573),
    (0.2427883, -0.51882446),
    (0.17941438, 0.5720013),
    (-0.540757, -0.31337973),
    (0.63436955, -0.13946436),
    (-0.38714585, 0.55067515),
    (-0.08943965, -0.6901997),
    (0.5490717, 0.46275827),
    (-0.7388785, 0.030554945),
    (0.53895515, -0.5363323),
    (-0.036058187, 0.77979153),
    (-0.51281756, -0.6145268),
    (0.8123596, 0.109301835),
    (-0.6883106, 0.47890863),
    (0.18808606, -0.83606136),
    (0.43503326, 0.75919104),
    (-0.8504484, -0.27131623),
    (0.8261024, -0.38168025),
    (-0.3578882, 0.8551556),
    (-0.31940734, -0.88803375),
    (0.84990865, 0.44668815),
    (-0.94403464, 0.2488445),
    (0.5365958, -0.83452976),
];

/// [`DISK`]'s coordinates by axis, eight samples to a row: the lanes of
/// [`disk_nodes`].
const DISK_LANES: [[[f32; LANES]; DISK.len() / LANES]; 2] = {
    let mut lanes = [[[0.0; LANES]; DISK.len() / LANES]; 2];
    let mut i = 0;
    while i < DISK.len() {
        lanes[0][i / LANES][i % LANES] = DISK[i].0;
        lanes[1][i / LANES][i % LANES] = DISK[i].1;
        i += 1;
    }
    lanes
};

/// The level nodes standing for the lamp centred at `lamp`, of radius
/// `radius` across the light's direction, seen from `p` on a surface of
/// normal `n`, into `out` with each sample's squared distance from the
/// disk's centre (the kernel's weight is of that distance). One entry per
/// sample of [`DISK`]: a node nearest two samples counts twice.
///
/// Eight samples at a time, with the operations and the order of one
/// sample's scalar arithmetic in each lane (the test below holds the two
/// to the bit, and the shader does the scalar's): a lamp in penumbra asks
/// this of every point it reaches, and one sample at a time it took a
/// tenth of the default's shading in a 2160p frame that reuses masks.
pub fn disk_nodes(
    level: Lattice,
    p: Vec3,
    n: Vec3,
    lamp: Vec3,
    radius: f32,
    out: &mut Vec<(IVec3, f32)>,
) {
    out.clear();
    let to_lamp = lamp - p;
    let distance = to_lamp.length();
    let light = to_lamp * (1.0 / distance);
    let (across, up) = disk_axes(light);
    let lamp_height = to_lamp.dot(n);
    let (radius, h) = (f32x8::splat(radius), f32x8::splat(level.h));
    let (n, p, to_lamp) = (splat3(n), splat3(p), splat3(to_lamp));
    let (across, up, origin) = (splat3(across), splat3(up), splat3(level.origin));
    for (x, y) in DISK_LANES[0].iter().zip(&DISK_LANES[1]) {
        let (x, y) = (radius * f32x8::new(*x), radius * f32x8::new(*y));
        let offset = each3(|axis| across[axis] * x + up[axis] * y);
        // Along the sample's own line to the lamp's centre, the fraction
        // of the way that lifts it a step above the surface. Near the
        // horizon that grows as 1/cosine: no sample moves past half the
        // way. A NaN lifts by nothing (`max` takes its second operand).
        let height = dot(offset, n);
        let rise = (f32x8::splat(lamp_height) - height).max(f32x8::splat(f32::MIN_POSITIVE));
        let lift = ((h - height) / rise)
            .max(f32x8::splat(0.0))
            .min(f32x8::splat(0.5));
        let node = each3(|axis| {
            let sample = (p[axis] + offset[axis]) + (to_lamp[axis] - offset[axis]) * lift;
            lattice::floor_ints((sample - origin[axis]) / h + f32x8::splat(0.5)).to_array()
        });
        let squared = dot(offset, offset).to_array();
        out.extend((0..LANES).map(|lane| {
            let node = IVec3::new(node[0][lane], node[1][lane], node[2][lane]);
            (node, squared[lane])
        }));
    }
}

/// Two unit vectors across `light` (a unit vector), at right angles: the
/// first across `light` and the axis `light` is least along (ties to x,
/// then y), the second across both.
fn disk_axes(light: Vec3) -> (Vec3, Vec3) {
    let magnitude = light.abs();
    let axis = if magnitude.x <= magnitude.y && magnitude.x <= magnitude.z {
        Vec3::X
    } else if magnitude.y <= magnitude.z {
        Vec3::Y
    } else {
        Vec3::Z
    };
    let across = light.cross(axis).normalize();
    (across, light.cross(across))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_disk_pattern_covers_the_unit_disk_evenly() {
        let radii: Vec<f32> = DISK.iter().map(|&(x, y)| (x * x + y * y).sqrt()).collect();
        assert!(radii.windows(2).all(|pair| pair[0] < pair[1]), "{radii:?}");
        assert!(radii[0] > 0.1 && radii[DISK.len() - 1] < 1.0);
        // Each ring of equal area holds as many points: a quarter of the
        // disk's area within radius 1/2.
        let inner = radii.iter().filter(|&&radius| radius < 0.5).count();
        assert_eq!(inner, DISK.len() / 4);
        let (sx, sy) = DISK
            .iter()
            .fold((0.0, 0.0), |(sx, sy), &(x, y)| (sx + x, sy + y));
        let centroid = (sx / DISK.len() as f32, sy / DISK.len() as f32);
        assert!(
            centroid.0.abs() < 0.02 && centroid.1.abs() < 0.02,
            "{centroid:?}"
        );
    }

    /// [`disk_nodes`] one sample at a time, as the shader computes it:
    /// what the eight lanes must give, to the bit.
    fn disk_nodes_one_by_one(
        level: Lattice,
        p: Vec3,
        n: Vec3,
        lamp: Vec3,
        radius: f32,
    ) -> Vec<(IVec3, f32)> {
        let to_lamp = lamp - p;
        let light = to_lamp * (1.0 / to_lamp.length());
        let (across, up) = disk_axes(light);
        let lamp_height = to_lamp.dot(n);
        (DISK.iter())
            .map(|&(x, y)| {
                let offset = across * (radius * x) + up * (radius * y);
                let height = offset.dot(n);
                let rise = (lamp_height - height).max(f32::MIN_POSITIVE);
                // Not `clamp`: a NaN lifts by nothing.
                #[allow(clippy::manual_clamp)]
                let lift = ((level.h - height) / rise).max(0.0).min(0.5);
                let sample = (p + offset) + (to_lamp - offset) * lift;
                let node = lattice::floor(level.local(sample) + Vec3::splat(0.5)).as_ivec3();
                (node, offset.length_squared())
            })
            .collect()
    }

    fn bits(nodes: &[(IVec3, f32)]) -> Vec<(IVec3, u32)> {
        nodes.iter().map(|&(node, d)| (node, d.to_bits())).collect()
    }

    /// The hard cases of the lanes: a lamp straight overhead and on the
    /// surface's plane (samples under it, a rise of nothing), a point on
    /// a lattice plane and one far out, a disk of no radius, and a NaN
    /// normal.
    #[test]
    fn lanes_give_one_by_one_samples_bits_where_the_lift_is_hard() {
        let level = Lattice::new(0.05);
        let mut nodes = Vec::new();
        let cases = [
            (
                Vec3::new(0.31, 0.0, -0.12),
                Vec3::Y,
                Vec3::new(0.31, 3.0, -0.12),
                0.12,
            ),
            (
                Vec3::new(0.31, 0.0, -0.12),
                Vec3::Y,
                Vec3::new(4.0, 0.0, 1.0),
                0.3,
            ),
            (
                Vec3::new(0.25, 0.05, 0.5),
                Vec3::Y,
                Vec3::new(-3.0, 0.06, 2.0),
                0.5,
            ),
            (
                Vec3::new(1.0e6, 2.0, -3.0e5),
                Vec3::Y,
                Vec3::new(1.0e6 + 3.0, 5.0, -3.0e5),
                0.2,
            ),
            (
                Vec3::new(1.0, 2.0, 3.0),
                Vec3::Z,
                Vec3::new(1.0, 6.0, 3.0),
                0.0,
            ),
            (
                Vec3::new(1.0, 2.0, 3.0),
                Vec3::NAN,
                Vec3::new(1.0, 6.0, 3.0),
                0.2,
            ),
        ];
        for (p, n, lamp, radius) in cases {
            disk_nodes(level, p, n, lamp, radius, &mut nodes);
            let one_by_one = disk_nodes_one_by_one(level, p, n, lamp, radius);
            assert_eq!(bits(&nodes), bits(&one_by_one), "p {p}, lamp {lamp}");
        }
    }

    proptest::proptest! {
        /// Over points, normals, lamps, radii and levels of every
        /// orientation, the lanes give the one-by-one samples' nodes and
        /// distances, to the bit.
        #[test]
        fn lanes_give_one_by_one_samples_bits(
            p in proptest::array::uniform3(-50.0f32..50.0),
            n in proptest::array::uniform3(-1.0f32..1.0),
            to_lamp in proptest::array::uniform3(-20.0f32..20.0),
            radius in 0.0f32..2.0,
            level in -3i32..=3,
        ) {
            let n = Vec3::from(n).normalize_or(Vec3::Y);
            let (p, lamp) = (Vec3::from(p), Vec3::from(p) + Vec3::from(to_lamp));
            let level = Lattice::new(0.1 * 2f32.powi(level));
            let mut nodes = Vec::new();
            disk_nodes(level, p, n, lamp, radius, &mut nodes);
            let one_by_one = disk_nodes_one_by_one(level, p, n, lamp, radius);
            proptest::prop_assert_eq!(bits(&nodes), bits(&one_by_one));
        }
    }

    /// Node `node`'s distance from the line through `p` towards `lamp`.
    fn from_the_line(level: Lattice, node: IVec3, p: Vec3, lamp: Vec3) -> f32 {
        let light = (lamp - p).normalize();
        let d = level.node_position(node) - p;
        (d - light * d.dot(light)).length()
    }

    #[test]
    fn samples_stand_above_the_surface_within_the_disk_around_the_line_to_the_lamp() {
        let level = Lattice::new(0.05);
        let radius = 2.5 * level.h;
        let snap = level.h * 3f32.sqrt() / 2.0;
        let mut nodes = Vec::new();
        let p = Vec3::new(0.31, 0.0, -0.12);
        // Straight above, at 45° and at 80° from the normal, on a floor
        // on a lattice plane and on a tilted roof.
        let floor = (Vec3::new(0.31, level.origin.y, -0.12), Vec3::Y);
        let roof = (p, Vec3::new(0.3, 0.9, -0.2).normalize());
        for (p, n) in [floor, roof] {
            for lamp in [
                p + n * 3.0,
                p + Vec3::new(2.0, 2.0, 0.5),
                p + Vec3::new(5.0, 0.9, -1.0),
            ] {
                disk_nodes(level, p, n, lamp, radius, &mut nodes);
                assert_eq!(nodes.len(), DISK.len());
                for &(node, distance_squared) in &nodes {
                    let height = (level.node_position(node) - p).dot(n);
                    assert!(height > 0.0, "{node} under the surface, lamp {lamp}");
                    assert!(distance_squared <= radius * radius * 1.0001);
                    let off_line = from_the_line(level, node, p, lamp);
                    assert!(off_line <= radius + snap, "{off_line} from the line");
                }
            }
        }
    }

    #[test]
    fn the_disk_is_across_the_light_and_its_samples_differ() {
        let level = Lattice::new(0.02);
        let mut nodes = Vec::new();
        let p = Vec3::new(1.0, 2.0, 3.0);
        let lamp = p + Vec3::new(-1.0, 4.0, 2.0);
        disk_nodes(level, p, Vec3::Y, lamp, 0.2, &mut nodes);
        let mut distinct: Vec<IVec3> = nodes.iter().map(|&(node, _)| node).collect();
        distinct.sort_by_key(|node| node.to_array());
        distinct.dedup();
        // Samples 3.5 cm apart or more, nodes 2 cm apart: all distinct.
        assert_eq!(distinct.len(), DISK.len());
        // The axes are unit vectors at right angles, across the light.
        for light in [Vec3::X, Vec3::new(0.0, -1.0, 0.0), (lamp - p).normalize()] {
            let (across, up) = disk_axes(light);
            for (a, b) in [(across, light), (up, light), (across, up)] {
                assert!(a.dot(b).abs() < 1e-6);
            }
            assert!((across.length() - 1.0).abs() < 1e-6 && (up.length() - 1.0).abs() < 1e-6);
        }
    }

    #[test]
    fn degenerate_and_huge_inputs_give_nodes_without_panicking() {
        let level = Lattice::new(0.1);
        let mut nodes = Vec::new();
        let far = Vec3::splat(3.0e7);
        disk_nodes(
            level,
            far,
            Vec3::Y,
            far + Vec3::new(1.0, 1.0, 0.0),
            0.25,
            &mut nodes,
        );
        assert_eq!(nodes.len(), DISK.len());
        // A lamp at the point itself or under the surface, a NaN radius.
        let p = Vec3::new(0.5, 0.0, 0.5);
        for (lamp, radius) in [(p, 0.25), (p - Vec3::Y, 0.25), (p + Vec3::Y, f32::NAN)] {
            disk_nodes(level, p, Vec3::Y, lamp, radius, &mut nodes);
            assert_eq!(nodes.len(), DISK.len());
        }
    }
}
