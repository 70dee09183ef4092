//! One channel's value at time `t`, per the glTF spec's interpolation
//! rules: the first value holds before the first key and the last after the
//! last; STEP holds a key's value until the next; LINEAR interpolates
//! straight, rotations by slerp on the shorter arc; CUBICSPLINE is the
//! cubic Hermite spline with tangents scaled by the key interval, rotations
//! normalised after. This is the innermost step of posing a frame.

use glam::DQuat;

use crate::scene::{Interpolation, Sampler};

/// How a channel's values combine: component by component, or as a unit
/// quaternion (x, y, z, w).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Values {
    Vector,
    Rotation,
}

/// The sampler's value at time `t` (seconds), `sampler.width` components;
/// None only for a sampler that fails [`Sampler::validate`] (import and the
/// builder refuse those).
pub fn sample(sampler: &Sampler, values: Values, t: f64) -> Option<Vec<f64>> {
    let times = &sampler.times;
    let per_key = sampler.elements_per_key();
    // The key's own value: the middle of CUBICSPLINE's three elements.
    let vertex = per_key / 2;
    let element = |key: usize, slot: usize| -> Option<Vec<f64>> {
        let at = (key * per_key + slot) * sampler.width;
        let slice = sampler.values.get(at..at + sampler.width)?;
        Some(slice.iter().map(|&v| f64::from(v)).collect())
    };
    let last = times.len().checked_sub(1)?;
    if t <= f64::from(times[0]) {
        return element(0, vertex);
    }
    if t >= f64::from(times[last]) {
        return element(last, vertex);
    }
    // times[0] <= t < times[last]: the key before t is in 0..last.
    let key = times.partition_point(|&time| f64::from(time) <= t) - 1;
    let (t0, t1) = (f64::from(times[key]), f64::from(times[key + 1]));
    let span = t1 - t0;
    let s = (t - t0) / span;
    match sampler.interpolation {
        Interpolation::Step => element(key, 0),
        Interpolation::Linear => {
            let (a, b) = (element(key, 0)?, element(key + 1, 0)?);
            Some(match values {
                Values::Vector => a.iter().zip(&b).map(|(a, b)| a + (b - a) * s).collect(),
                Values::Rotation => slerp(&a, &b, s)?,
            })
        }
        Interpolation::CubicSpline => {
            let p0 = element(key, 1)?;
            let m0 = element(key, 2)?;
            let p1 = element(key + 1, 1)?;
            let m1 = element(key + 1, 0)?;
            let [h00, h10, h01, h11] = hermite_basis(s);
            let point: Vec<f64> = (0..sampler.width)
                .map(|i| h00 * p0[i] + h10 * span * m0[i] + h01 * p1[i] + h11 * span * m1[i])
                .collect();
            Some(match values {
                Values::Vector => point,
                Values::Rotation => quaternion(&point)?.normalize().to_array().to_vec(),
            })
        }
    }
}

/// The cubic Hermite basis at `s` in [0, 1]: weights of the start point,
/// the start tangent, the end point and the end tangent.
fn hermite_basis(s: f64) -> [f64; 4] {
    let (s2, s3) = (s * s, s * s * s);
    [
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        -2.0 * s3 + 3.0 * s2,
        s3 - s2,
    ]
}

/// Spherical interpolation on the shorter arc: `b` is negated when the two
/// quaternions lie in opposite hemispheres, since q and −q are one rotation.
fn slerp(a: &[f64], b: &[f64], s: f64) -> Option<Vec<f64>> {
    let a = quaternion(a)?.normalize();
    let mut b = quaternion(b)?.normalize();
    if a.dot(b) < 0.0 {
        b = -b;
    }
    Some(a.slerp(b, s).normalize().to_array().to_vec())
}

fn quaternion(values: &[f64]) -> Option<DQuat> {
    match *values {
        [x, y, z, w] => Some(DQuat::from_xyzw(x, y, z, w)),
        _ => None,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn sampler(
        interpolation: Interpolation,
        times: &[f32],
        values: &[f32],
        width: usize,
    ) -> Sampler {
        let sampler = Sampler {
            interpolation,
            times: times.to_vec(),
            values: values.to_vec(),
            width,
        };
        assert_eq!(sampler.validate(), Ok(()));
        sampler
    }

    fn at(sampler: &Sampler, values: Values, t: f64) -> Vec<f64> {
        sample(sampler, values, t).expect("valid sampler")
    }

    fn close(a: &[f64], b: &[f64]) -> bool {
        a.len() == b.len() && a.iter().zip(b).all(|(a, b)| (a - b).abs() < 1e-6)
    }

    #[test]
    fn values_hold_before_the_first_and_after_the_last_key() {
        for interpolation in [Interpolation::Step, Interpolation::Linear] {
            let s = sampler(interpolation, &[1.0, 2.0], &[10.0, 20.0], 1);
            assert_eq!(at(&s, Values::Vector, -5.0), vec![10.0]);
            assert_eq!(at(&s, Values::Vector, 1.0), vec![10.0]);
            assert_eq!(at(&s, Values::Vector, 2.0), vec![20.0]);
            assert_eq!(at(&s, Values::Vector, 9.0), vec![20.0]);
        }
        // CUBICSPLINE holds the key's value, not a tangent.
        let s = sampler(
            Interpolation::CubicSpline,
            &[1.0, 2.0],
            &[7.0, 10.0, 7.0, 7.0, 20.0, 7.0],
            1,
        );
        assert_eq!(at(&s, Values::Vector, 0.0), vec![10.0]);
        assert_eq!(at(&s, Values::Vector, 3.0), vec![20.0]);
    }

    #[test]
    fn a_single_key_holds_for_all_time() {
        let s = sampler(Interpolation::Linear, &[0.5], &[1.0, 2.0, 3.0], 3);
        for t in [-1.0, 0.5, 4.0] {
            assert_eq!(at(&s, Values::Vector, t), vec![1.0, 2.0, 3.0]);
        }
        let s = sampler(Interpolation::CubicSpline, &[0.5], &[9.0, 4.0, 9.0], 1);
        assert_eq!(at(&s, Values::Vector, 2.0), vec![4.0]);
    }

    #[test]
    fn step_holds_each_key_until_the_next() {
        let s = sampler(Interpolation::Step, &[0.0, 1.0, 2.0], &[1.0, 5.0, 9.0], 1);
        assert_eq!(at(&s, Values::Vector, 0.99), vec![1.0]);
        assert_eq!(at(&s, Values::Vector, 1.0), vec![5.0]);
        assert_eq!(at(&s, Values::Vector, 1.5), vec![5.0]);
    }

    #[test]
    fn linear_interpolates_each_component() {
        let s = sampler(
            Interpolation::Linear,
            &[0.0, 2.0],
            &[0.0, 10.0, -4.0, 4.0, 20.0, 0.0],
            3,
        );
        assert!(close(&at(&s, Values::Vector, 0.5), &[1.0, 12.5, -3.0]));
    }

    #[test]
    fn linear_rotation_is_slerp_on_the_shorter_arc() {
        // Identity to 90° about Z; halfway is 45° about Z.
        let h = (0.5f64).sqrt() as f32;
        let s = sampler(
            Interpolation::Linear,
            &[0.0, 1.0],
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, h, h],
            4,
        );
        let half = DQuat::from_rotation_z(FRAC_PI_2 / 2.0).to_array();
        assert!(close(&at(&s, Values::Rotation, 0.5), &half));
        // The same end rotation with its sign flipped gives the same path,
        // not the 270° way round.
        let flipped = sampler(
            Interpolation::Linear,
            &[0.0, 1.0],
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0, -h, -h],
            4,
        );
        let q = at(&flipped, Values::Rotation, 0.5);
        let q = DQuat::from_slice(&q);
        let expected = DQuat::from_array(half);
        assert!(q.dot(expected).abs() > 1.0 - 1e-9, "{q}");
    }

    #[test]
    fn cubic_spline_with_zero_tangents_is_the_smoothstep_curve() {
        // p(s) = 3s² − 2s³ between 0 and 1 when both tangents are zero.
        let s = sampler(
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[0.0, 0.0, 0.0, 0.0, 1.0, 0.0],
            1,
        );
        for (t, expected) in [(0.5, 0.15625), (1.0, 0.5), (1.5, 0.84375)] {
            assert!(close(&at(&s, Values::Vector, t), &[expected]), "t = {t}");
        }
    }

    #[test]
    fn cubic_spline_tangents_are_scaled_by_the_key_interval() {
        // Flat values, out-tangent 1 at the start, interval 2 s: at s = 0.5
        // the curve is h10(0.5) · 2 · 1 = 0.125 · 2 = 0.25; an in-tangent of
        // 1 at the end gives h11(0.5) · 2 = −0.25.
        let s = sampler(
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[0.0, 0.0, 1.0, 0.0, 0.0, 0.0],
            1,
        );
        assert!(close(&at(&s, Values::Vector, 1.0), &[0.25]));
        let s = sampler(
            Interpolation::CubicSpline,
            &[0.0, 2.0],
            &[0.0, 0.0, 0.0, 1.0, 0.0, 0.0],
            1,
        );
        assert!(close(&at(&s, Values::Vector, 1.0), &[-0.25]));
    }

    #[test]
    fn cubic_spline_rotations_are_normalised() {
        let h = (0.5f64).sqrt() as f32;
        let zero = [0.0; 4];
        let mut values = Vec::new();
        for key in [[0.0, 0.0, 0.0, 1.0], [0.0, 0.0, h, h]] {
            values.extend(zero);
            values.extend(key);
            values.extend(zero);
        }
        let s = sampler(Interpolation::CubicSpline, &[0.0, 1.0], &values, 4);
        let q = at(&s, Values::Rotation, 0.5);
        // Halfway with zero tangents: the normalised mean of the two keys.
        let expected = DQuat::from_xyzw(0.0, 0.0, 0.5 * f64::from(h), 0.5 + 0.5 * f64::from(h))
            .normalize()
            .to_array();
        assert!(close(&q, &expected), "{q:?}");
    }
}
