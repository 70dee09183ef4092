//! The city's motion as keyframes: cars lapping rectangles of streets,
//! trees swaying in the wind and the camera's fly-through. Every motion
//! loops within [`DURATION`], so a render of the whole clip can repeat.

use std::f32::consts::TAU;

use glam::{Quat, Vec2, Vec3};

use crate::look_at_rotation;
use lmanim::scene::{Interpolation, Sampler};

/// Length of the city's clip, seconds: 240 frames at 24 fps.
pub(super) const DURATION: f32 = 10.0;

/// `keys + 1` times spread evenly over [0, DURATION].
fn key_times(keys: u32) -> Vec<f32> {
    (0..=keys)
        .map(|key| DURATION * key as f32 / keys as f32)
        .collect()
}

/// A LINEAR sampler of `value` at `keys + 1` even times.
pub(super) fn linear<const N: usize>(keys: u32, value: impl Fn(f32) -> [f32; N]) -> Sampler {
    let times = key_times(keys);
    Sampler {
        interpolation: Interpolation::Linear,
        values: times.iter().flat_map(|&t| value(t)).collect(),
        times,
        width: N,
    }
}

/// A CUBICSPLINE sampler of `value` at `keys + 1` even times, tangents
/// (derivatives per second, as glTF has them) by central differences.
pub(super) fn cubic<const N: usize>(keys: u32, value: impl Fn(f32) -> [f32; N]) -> Sampler {
    const STEP: f32 = 1e-3;
    let times = key_times(keys);
    let values = times
        .iter()
        .flat_map(|&t| {
            let (before, after) = (value(t - STEP), value(t + STEP));
            let tangent: [f32; N] = std::array::from_fn(|i| (after[i] - before[i]) / (2.0 * STEP));
            [tangent, value(t), tangent].into_iter().flatten()
        })
        .collect();
    Sampler {
        interpolation: Interpolation::CubicSpline,
        times,
        values,
        width: N,
    }
}

/// A closed path of straight street segments, walked by arc length.
pub(super) struct Route {
    corners: Vec<Vec2>,
    /// Arc length at each corner, from the first; the last is the length.
    lengths: Vec<f32>,
}

impl Route {
    /// The rectangle `min`..`max` of street centre lines, driven on the
    /// right-hand lane `lane` metres off the centre line, anticlockwise
    /// seen from above or the other way round.
    pub(super) fn block_ring(min: Vec2, max: Vec2, lane: f32, anticlockwise: bool) -> Route {
        // Anticlockwise (x then z rising) keeps the right-hand lane inside.
        let inset = if anticlockwise { lane } else { -lane };
        let (lo, hi) = (min + Vec2::splat(inset), max - Vec2::splat(inset));
        let mut corners = vec![lo, Vec2::new(hi.x, lo.y), hi, Vec2::new(lo.x, hi.y)];
        if !anticlockwise {
            corners.reverse();
        }
        let mut lengths = vec![0.0];
        for (index, corner) in corners.iter().enumerate() {
            let next = corners[(index + 1) % corners.len()];
            lengths.push(lengths[index] + corner.distance(next));
        }
        Route { corners, lengths }
    }

    pub(super) fn length(&self) -> f32 {
        self.lengths[self.corners.len()]
    }

    /// The point `distance` metres along the route, wrapping around.
    pub(super) fn at(&self, distance: f32) -> Vec2 {
        let distance = distance.rem_euclid(self.length());
        let segment = self.lengths[1..]
            .iter()
            .position(|&end| distance < end)
            .unwrap_or(self.corners.len() - 1);
        let from = self.corners[segment];
        let to = self.corners[(segment + 1) % self.corners.len()];
        let t = (distance - self.lengths[segment])
            / (self.lengths[segment + 1] - self.lengths[segment]);
        from.lerp(to, t)
    }

    /// Translation and rotation samplers of a car (facing +Z) lapping the
    /// route `laps` times in [`DURATION`], starting `start` metres along.
    /// The heading follows a chord 4 m long, which rounds the corners.
    pub(super) fn drive(&self, start: f32, laps: u32) -> (Sampler, Sampler) {
        const KEYS: u32 = 80;
        let speed = laps as f32 * self.length() / DURATION;
        let along = move |t: f32| start + speed * t;
        let translation = linear(KEYS, |t| {
            let p = self.at(along(t));
            [p.x, 0.0, p.y]
        });
        let rotation = linear(KEYS, |t| {
            let ahead = self.at(along(t) + 2.0) - self.at(along(t) - 2.0);
            Quat::from_rotation_y(ahead.x.atan2(ahead.y)).to_array()
        });
        (translation, rotation)
    }
}

/// A joint's sway: rotation about a horizontal axis, `amplitude` radians,
/// `cycles` whole periods in [`DURATION`], shifted by `phase` radians.
pub(super) fn sway(axis: Vec3, amplitude: f32, cycles: u32, phase: f32) -> Sampler {
    let frequency = cycles as f32 / DURATION;
    cubic(40, move |t| {
        let angle = amplitude * (TAU * frequency * t + phase).sin();
        Quat::from_axis_angle(axis, angle).to_array()
    })
}

/// Where the camera is and what it looks at: a Catmull-Rom curve through
/// evenly timed keys of (eye, target).
pub(super) struct FlyThrough {
    pub keys: Vec<(Vec3, Vec3)>,
}

impl FlyThrough {
    fn at(&self, t: f32) -> (Vec3, Vec3) {
        let last = self.keys.len() - 1;
        let u = (t / DURATION).clamp(0.0, 1.0) * last as f32;
        let segment = (u.floor() as usize).min(last - 1);
        let s = u - segment as f32;
        let key = |i: isize| self.keys[i.clamp(0, last as isize) as usize];
        let i = segment as isize;
        let (p0, p1, p2, p3) = (key(i - 1), key(i), key(i + 1), key(i + 2));
        let spline = |a: Vec3, b: Vec3, c: Vec3, d: Vec3| {
            0.5 * (2.0 * b
                + (c - a) * s
                + (2.0 * a - 5.0 * b + 4.0 * c - d) * s * s
                + (3.0 * b - a - 3.0 * c + d) * s * s * s)
        };
        (
            spline(p0.0, p1.0, p2.0, p3.0),
            spline(p0.1, p1.1, p2.1, p3.1),
        )
    }

    /// The camera node's translation (CUBICSPLINE) and rotation (LINEAR,
    /// looking at the target) samplers.
    pub(super) fn samplers(&self) -> (Sampler, Sampler) {
        let translation = cubic(40, |t| self.at(t).0.to_array());
        let rotation = linear(120, |t| {
            let (eye, target) = self.at(t);
            look_at_rotation(eye, target, Vec3::Y)
                .unwrap_or(Quat::IDENTITY)
                .to_array()
        });
        (translation, rotation)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_car_laps_its_route_and_faces_where_it_drives() {
        let route = Route::block_ring(Vec2::ZERO, Vec2::new(20.0, 40.0), 1.8, true);
        assert!((route.length() - 2.0 * (16.4 + 36.4)).abs() < 1e-3);
        assert!(route
            .at(route.length() + 3.0)
            .abs_diff_eq(route.at(3.0), 1e-4));
        let (translation, rotation) = route.drive(5.0, 1);
        assert_eq!(translation.validate(), Ok(()));
        assert_eq!(rotation.validate(), Ok(()));
        // The last key is the first: the lap closes within the clip.
        let first = &translation.values[..3];
        let last = &translation.values[translation.values.len() - 3..];
        for (a, b) in first.iter().zip(last) {
            assert!((a - b).abs() < 1e-3, "{first:?} against {last:?}");
        }
        // 5 m along the first side (+x): facing +x.
        let heading = Quat::from_slice(&rotation.values[..4]) * Vec3::Z;
        assert!(heading.abs_diff_eq(Vec3::X, 1e-4), "{heading}");
    }

    #[test]
    fn cubic_tangents_are_derivatives_per_second() {
        let sampler = cubic(10, |t| [3.0 * t]);
        assert_eq!(sampler.validate(), Ok(()));
        for key in sampler.values.chunks(3) {
            assert!((key[0] - 3.0).abs() < 1e-2 && (key[2] - 3.0).abs() < 1e-2);
        }
    }
}
