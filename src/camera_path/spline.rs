//! The curve a camera path follows: a centripetal Catmull–Rom spline
//! (alpha 0.5) through the waypoints, the eases that warp its clock, and
//! the arc-length table that makes it play at constant speed. Plain `f64`
//! maths over `DVec3`; [`super::CameraPath`] decides what the values mean.
//!
//! Centripetal parameterisation (knot intervals the square root of the
//! chord lengths) is the one that never makes cusps or self-intersections
//! within a segment (Yuksel, Schaefer and Keyser 2011). Each segment is
//! evaluated in Hermite form, whose tangents are the Barry–Goldman
//! pyramid's derivatives at the segment's ends, so repeated points and
//! two-point paths are handled by explicit rules instead of divisions by a
//! zero knot interval.

use glam::DVec3;
use serde::Deserialize;

/// Knot intervals below this are a repeated point (the square root of a
/// chord of 1e-24 m): its neighbours' interval stands in for it.
const MIN_INTERVAL: f64 = 1e-12;

/// Arc-length samples per segment for constant speed. Within a sample
/// the parameter is taken linear in length, which is off where the
/// segment's speed changes; at 1/256 of a segment that leaves equal times
/// within 1e-4 of equal lengths on sharply bent paths (tested), at a
/// cost of 256 evaluations per segment once per run.
const ARC_SAMPLES: usize = 256;

/// A Catmull–Rom spline through `points`, with `values` (any other
/// per-point quantity) carried along on the same parameterisation. A path
/// whose last point is its first (and has another) is a loop, and closes
/// smoothly.
#[derive(Clone, Debug, PartialEq)]
pub struct Spline {
    /// The points, with a phantom point mirrored beyond each end so that
    /// the end segments have four points too.
    points: Vec<DVec3>,
    values: Vec<DVec3>,
    /// Centripetal knot interval between padded point i and i + 1.
    intervals: Vec<f64>,
}

impl Spline {
    /// The spline through `points` (at least two), carrying `values` (as
    /// many as `points`).
    pub fn new(points: &[DVec3], values: &[DVec3]) -> Spline {
        debug_assert!(points.len() >= 2 && points.len() == values.len());
        let closed = points.len() > 2 && points[0] == points[points.len() - 1];
        let points = padded(points, closed);
        let values = padded(values, closed);
        let intervals = points
            .windows(2)
            .map(|pair| pair[0].distance(pair[1]).sqrt())
            .collect();
        Spline {
            points,
            values,
            intervals,
        }
    }

    /// The number of segments (one less than the points).
    pub fn segments(&self) -> usize {
        self.points.len() - 3
    }

    /// Point and value on `segment` at `s` in [0, 1] (0 at its first
    /// waypoint, 1 at the next). A segment between two equal points stays
    /// at that point, whatever its neighbours: a hold, not a loop.
    pub fn at(&self, segment: usize, s: f64) -> (DVec3, DVec3) {
        let dt = self.guarded_intervals(segment);
        let p = &self.points[segment..segment + 4];
        let v = &self.values[segment..segment + 4];
        let point = if p[1] == p[2] {
            p[1]
        } else {
            hermite(p, dt, s)
        };
        (point, hermite(v, dt, s))
    }

    /// The three knot intervals around `segment`, none zero: a repeated
    /// point borrows the middle interval (or 1 where that is zero too).
    fn guarded_intervals(&self, segment: usize) -> [f64; 3] {
        let [d0, d1, d2] = [0, 1, 2].map(|k| self.intervals[segment + k]);
        let d1 = if d1 < MIN_INTERVAL { 1.0 } else { d1 };
        let d0 = if d0 < MIN_INTERVAL { d1 } else { d0 };
        let d2 = if d2 < MIN_INTERVAL { d1 } else { d2 };
        [d0, d1, d2]
    }

    /// The path's arc length at [`ARC_SAMPLES`] points per segment: the
    /// table [`ArcTable::clock_at`] inverts.
    pub fn arc_table(&self) -> ArcTable {
        let mut lengths = vec![0.0];
        let mut previous = self.points[1];
        for segment in 0..self.segments() {
            for k in 1..=ARC_SAMPLES {
                let (point, _) = self.at(segment, k as f64 / ARC_SAMPLES as f64);
                let last = *lengths.last().unwrap_or(&0.0);
                lengths.push(last + previous.distance(point));
                previous = point;
            }
        }
        ArcTable { lengths }
    }
}

/// `points` with a phantom point beyond each end. Open: the ends
/// mirrored (`2·p0 − p1` before the first point, likewise after the
/// last), so an end segment leaves its waypoint heading for the next one
/// and a two-point path is a straight line at even speed. Closed: the
/// points across the seam, shifted by the change from first to last
/// (zero for positions; a whole turn for the yaw of a loop that looks
/// round), so the loop has no corner where it starts.
fn padded(points: &[DVec3], closed: bool) -> Vec<DVec3> {
    let n = points.len();
    let (before, after) = match closed {
        true => {
            let shift = points[n - 1] - points[0];
            (points[n - 2] - shift, points[1] + shift)
        }
        false => (
            2.0 * points[0] - points[1],
            2.0 * points[n - 1] - points[n - 2],
        ),
    };
    let mut padded = Vec::with_capacity(n + 2);
    padded.push(before);
    padded.extend_from_slice(points);
    padded.push(after);
    padded
}

/// The segment from `p[1]` to `p[2]` at `s`: cubic Hermite with the
/// centripetal Catmull–Rom tangents for knot intervals `dt`, scaled to the
/// segment's own interval.
fn hermite(p: &[DVec3], dt: [f64; 3], s: f64) -> DVec3 {
    let [d0, d1, d2] = dt;
    let m1 = ((p[1] - p[0]) / d0 - (p[2] - p[0]) / (d0 + d1) + (p[2] - p[1]) / d1) * d1;
    let m2 = ((p[2] - p[1]) / d1 - (p[3] - p[1]) / (d1 + d2) + (p[3] - p[2]) / d2) * d1;
    let (s2, s3) = (s * s, s * s * s);
    (2.0 * s3 - 3.0 * s2 + 1.0) * p[1]
        + (s3 - 2.0 * s2 + s) * m1
        + (-2.0 * s3 + 3.0 * s2) * p[2]
        + (s3 - s2) * m2
}

/// Cumulative arc length at evenly spaced parameters of every segment.
#[derive(Clone, Debug, PartialEq)]
pub struct ArcTable {
    /// Entry `segment · ARC_SAMPLES + k`: the length up to `k / ARC_SAMPLES`
    /// of `segment`.
    lengths: Vec<f64>,
}

impl ArcTable {
    /// The whole path's length in metres.
    pub fn total(&self) -> f64 {
        *self.lengths.last().unwrap_or(&0.0)
    }

    /// The (segment, s) at which the path has come `length` metres, by
    /// linear interpolation between the table's samples.
    pub fn segment_at(&self, length: f64) -> (usize, f64) {
        let last = self.lengths.len() - 1;
        let length = length.clamp(0.0, self.total());
        let after = self.lengths.partition_point(|&l| l < length).clamp(1, last);
        let (l0, l1) = (self.lengths[after - 1], self.lengths[after]);
        let within = if l1 > l0 {
            (length - l0) / (l1 - l0)
        } else {
            0.0
        };
        let sample = (after - 1) as f64 + within;
        let segment = (after - 1) / ARC_SAMPLES;
        (segment, sample / ARC_SAMPLES as f64 - segment as f64)
    }
}

/// How the path's clock runs from its first waypoint's time to its last's.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Deserialize)]
#[serde(rename_all = "snake_case", rename = "ease")]
pub enum Ease {
    /// At the waypoints' own pace.
    #[default]
    Linear,
    /// Starting from rest.
    EaseIn,
    /// Coming to rest.
    EaseOut,
    /// Starting from rest and coming to rest.
    EaseInOut,
}

impl Ease {
    /// The eased share of the path at `x` in [0, 1] of its time; 0 at 0
    /// and 1 at 1, increasing, quadratic (so speed is continuous).
    pub fn apply(self, x: f64) -> f64 {
        let x = x.clamp(0.0, 1.0);
        match self {
            Ease::Linear => x,
            Ease::EaseIn => x * x,
            Ease::EaseOut => 1.0 - (1.0 - x) * (1.0 - x),
            Ease::EaseInOut if x < 0.5 => 2.0 * x * x,
            Ease::EaseInOut => 1.0 - 2.0 * (1.0 - x) * (1.0 - x),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points() -> Vec<DVec3> {
        [
            (0.0, 0.0, 0.0),
            (1.0, 3.0, 0.0),
            (1.5, 3.2, 0.0),
            (6.0, 0.0, 2.0),
            (7.0, -1.0, 2.0),
        ]
        .map(|(x, y, z)| DVec3::new(x, y, z))
        .to_vec()
    }

    fn spline(points: &[DVec3]) -> Spline {
        Spline::new(points, points)
    }

    #[test]
    fn the_spline_passes_through_every_waypoint() {
        let points = points();
        let spline = spline(&points);
        for segment in 0..spline.segments() {
            let (start, _) = spline.at(segment, 0.0);
            let (end, _) = spline.at(segment, 1.0);
            assert!(start.abs_diff_eq(points[segment], 1e-12), "{start}");
            assert!(end.abs_diff_eq(points[segment + 1], 1e-12), "{end}");
        }
    }

    /// The Barry–Goldman pyramid with knots t_{i+1} = t_i + |P_{i+1} −
    /// P_i|^alpha: the textbook definition the Hermite form must equal.
    fn barry_goldman(p: &[DVec3], alpha: f64, s: f64) -> DVec3 {
        let mut t = [0.0; 4];
        for i in 1..4 {
            t[i] = t[i - 1] + p[i].distance(p[i - 1]).powf(alpha);
        }
        let u = t[1] + s * (t[2] - t[1]);
        let lerp = |a: DVec3, b: DVec3, ta: f64, tb: f64| {
            a * ((tb - u) / (tb - ta)) + b * ((u - ta) / (tb - ta))
        };
        let a1 = lerp(p[0], p[1], t[0], t[1]);
        let a2 = lerp(p[1], p[2], t[1], t[2]);
        let a3 = lerp(p[2], p[3], t[2], t[3]);
        let b1 = lerp(a1, a2, t[0], t[2]);
        let b2 = lerp(a2, a3, t[1], t[3]);
        lerp(b1, b2, t[1], t[2])
    }

    #[test]
    fn segments_are_the_centripetal_catmull_rom_curve() {
        let points = points();
        let spline = spline(&points);
        let padded = padded(&points, false);
        for segment in 0..spline.segments() {
            for k in 0..=10 {
                let s = k as f64 / 10.0;
                let (got, _) = spline.at(segment, s);
                let want = barry_goldman(&padded[segment..segment + 4], 0.5, s);
                assert!(got.abs_diff_eq(want, 1e-9), "{segment} {s}: {got} {want}");
                // Uniform (alpha 0) parameterisation is a different curve
                // here, so the comparison tells the two apart.
                let uniform = barry_goldman(&padded[segment..segment + 4], 0.0, s);
                if k == 5 {
                    assert!(got.distance(uniform) > 1e-3, "{segment}");
                }
            }
        }
    }

    #[test]
    fn repeated_points_and_two_point_paths_give_finite_points() {
        let a = DVec3::new(1.0, 2.0, 3.0);
        let b = DVec3::new(4.0, 2.0, -1.0);
        let held = spline(&[a, a, b, b, b]);
        for segment in 0..held.segments() {
            for k in 0..=8 {
                let (point, value) = held.at(segment, k as f64 / 8.0);
                assert!(point.is_finite() && value.is_finite(), "{segment} {k}");
            }
        }
        assert_eq!(held.at(0, 0.5).0, a, "a hold stays put");
        let line = spline(&[a, b]);
        for k in 0..=8 {
            let s = k as f64 / 8.0;
            assert!(line.at(0, s).0.abs_diff_eq(a.lerp(b, s), 1e-12));
        }
        let still = spline(&[a, a]);
        assert_eq!(still.at(0, 0.3).0, a);
        assert_eq!(still.arc_table().segment_at(0.0), (0, 0.0));
    }

    #[test]
    fn the_arc_table_inverts_length_to_even_steps() {
        let spline = spline(&points());
        let table = spline.arc_table();
        let steps = 40;
        let sample = |length: f64| {
            let (segment, s) = table.segment_at(length);
            spline.at(segment, s).0
        };
        // Each step's length measured finely, apart from the table.
        let step_length = |i: usize| {
            let fine = 200;
            let at = |k: usize| {
                sample(table.total() * (i as f64 + k as f64 / fine as f64) / steps as f64)
            };
            (0..fine).map(|k| at(k).distance(at(k + 1))).sum::<f64>()
        };
        let even = table.total() / steps as f64;
        for i in 0..steps {
            let length = step_length(i);
            assert!((length - even).abs() < 1e-3 * even, "{i}: {length} {even}");
        }
        assert!(sample(table.total()).abs_diff_eq(points()[4], 1e-12));
    }

    #[test]
    fn a_loop_closes_without_a_corner() {
        let square = [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0), (0.0, 4.0), (0.0, 0.0)]
            .map(|(x, z)| DVec3::new(x, 0.0, z));
        let spline = spline(&square);
        let last = spline.segments() - 1;
        let leaving = spline.at(0, 1e-6).0 - spline.at(0, 0.0).0;
        let arriving = spline.at(last, 1.0).0 - spline.at(last, 1.0 - 1e-6).0;
        assert!(leaving.normalize().abs_diff_eq(arriving.normalize(), 1e-5));
        let open = Spline::new(&square[..4], &square[..4]);
        assert!(
            open.at(0, 0.5).0 != spline.at(0, 0.5).0,
            "the seam shapes the first segment"
        );
    }

    #[test]
    fn eases_start_at_zero_end_at_one_and_rest_where_named() {
        let slope = |ease: Ease, x: f64| (ease.apply(x + 1e-6) - ease.apply(x)) / 1e-6;
        for ease in [Ease::Linear, Ease::EaseIn, Ease::EaseOut, Ease::EaseInOut] {
            assert_eq!((ease.apply(0.0), ease.apply(1.0)), (0.0, 1.0), "{ease:?}");
            let values: Vec<f64> = (0..=100).map(|k| ease.apply(k as f64 / 100.0)).collect();
            assert!(values.windows(2).all(|w| w[1] > w[0]), "{ease:?} increases");
        }
        assert!(slope(Ease::EaseIn, 0.0) < 1e-5 && slope(Ease::EaseInOut, 0.0) < 1e-5);
        assert!(slope(Ease::EaseOut, 1.0 - 1e-6) < 1e-5);
        assert!(slope(Ease::EaseInOut, 1.0 - 1e-6) < 1e-5);
        assert!(
            (slope(Ease::EaseInOut, 0.5) - 2.0).abs() < 1e-4,
            "no jump mid-way"
        );
    }
}
