//! Shafts: the convex hull of an axis-aligned box and a point, the region
//! that every segment from a point of the box to the point sweeps. A shaft
//! that meets no triangle settles the visibility of a whole group of points
//! from a light with one query (Haines and Wallace's shaft culling), which
//! is how the light mesh fills a brick of node masks at once.
//!
//! Every test here may answer "may meet" for things that do not (the caller
//! then traces the segments one by one), never the reverse: separation is
//! only claimed with a margin larger than the rounding of the coordinates.

use glam::Vec3;

/// The hull of a box and an apex, as bounding planes `n·x <= d`.
#[derive(Clone, Debug)]
pub struct Shaft {
    planes: Vec<(Vec3, f32)>,
    min: Vec3,
    max: Vec3,
    vertices: [Vec3; 9],
    /// Separation must exceed this, in metres.
    margin: f32,
}

impl Shaft {
    pub fn new(box_min: Vec3, box_max: Vec3, apex: Vec3) -> Shaft {
        let corners: [Vec3; 8] = std::array::from_fn(|i| {
            Vec3::new(
                if i & 1 == 0 { box_min.x } else { box_max.x },
                if i & 2 == 0 { box_min.y } else { box_max.y },
                if i & 4 == 0 { box_min.z } else { box_max.z },
            )
        });
        let mut vertices = [apex; 9];
        vertices[..8].copy_from_slice(&corners);
        let scale = vertices
            .iter()
            .fold(0.0f32, |m, v| m.max(v.abs().max_element()));
        let margin = 64.0 * f32::EPSILON * scale.max(1.0);
        let mut planes = Vec::with_capacity(18);
        // A box face is a face of the hull when the apex is on its inner side.
        for axis in 0..3 {
            let mut normal = Vec3::ZERO;
            normal[axis] = -1.0;
            if apex[axis] >= box_min[axis] {
                planes.push((normal, -box_min[axis]));
            }
            normal[axis] = 1.0;
            if apex[axis] <= box_max[axis] {
                planes.push((normal, box_max[axis]));
            }
        }
        // The plane through the apex and a box edge is a face of the hull
        // when every corner lies on one side of it (a silhouette edge).
        for i in 0..8usize {
            for axis in 0..3 {
                let j = i | 1 << axis;
                if j == i {
                    continue;
                }
                let (a, b) = (corners[i], corners[j]);
                let normal = (a - apex).cross(b - apex);
                let length = normal.length();
                if length.is_nan() || length <= 0.0 {
                    continue;
                }
                let normal = normal / length;
                let d = normal.dot(apex);
                let (low, high) =
                    corners
                        .iter()
                        .fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), c| {
                            let s = normal.dot(*c) - d;
                            (lo.min(s), hi.max(s))
                        });
                if high <= margin {
                    planes.push((normal, d));
                } else if low >= -margin {
                    planes.push((-normal, -d));
                }
            }
        }
        Shaft {
            planes,
            min: box_min.min(apex),
            max: box_max.max(apex),
            vertices,
            margin,
        }
    }

    /// Whether the box `min..max` may meet the shaft.
    pub fn may_meet_box(&self, min: Vec3, max: Vec3) -> bool {
        if (min - self.max).max_element() > self.margin
            || (self.min - max).max_element() > self.margin
        {
            return false;
        }
        // Outside a hull plane: even the box's corner deepest along the
        // plane's normal lies beyond it.
        !self.planes.iter().any(|&(normal, d)| {
            let nearest = Vec3::select(normal.cmpge(Vec3::ZERO), min, max);
            normal.dot(nearest) - d > self.margin
        })
    }

    /// Whether the triangle may meet the shaft.
    pub fn may_meet_triangle(&self, [a, b, c]: [Vec3; 3]) -> bool {
        if !self.may_meet_box(a.min(b).min(c), a.max(b).max(c)) {
            return false;
        }
        if self
            .planes
            .iter()
            .any(|&(normal, d)| [a, b, c].iter().all(|v| normal.dot(*v) - d > self.margin))
        {
            return false;
        }
        // The triangle's own plane, with the whole shaft on one side.
        let normal = (b - a).cross(c - a);
        let length = normal.length();
        if length.is_nan() || length <= 0.0 {
            return true;
        }
        let normal = normal / length;
        let d = normal.dot(a);
        let sides = self.vertices.iter().map(|v| normal.dot(*v) - d);
        let (low, high) = sides.fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), s| {
            (lo.min(s), hi.max(s))
        });
        !(low > self.margin || high < -self.margin)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lamp_shaft() -> Shaft {
        Shaft::new(
            Vec3::new(0.0, 0.1, 0.0),
            Vec3::new(1.0, 0.5, 1.0),
            Vec3::new(5.0, 5.0, 0.5),
        )
    }

    #[test]
    fn the_floor_below_and_a_wall_behind_are_outside() {
        let shaft = lamp_shaft();
        let floor = [
            Vec3::new(-10.0, 0.0, -10.0),
            Vec3::new(10.0, 0.0, -10.0),
            Vec3::new(0.0, 0.0, 10.0),
        ];
        assert!(!shaft.may_meet_triangle(floor));
        let wall = [
            Vec3::new(-0.5, 0.0, -5.0),
            Vec3::new(-0.5, 5.0, 0.0),
            Vec3::new(-0.5, 0.0, 5.0),
        ];
        assert!(!shaft.may_meet_triangle(wall));
    }

    #[test]
    fn a_blocker_between_box_and_apex_is_inside() {
        let shaft = lamp_shaft();
        let centre = Vec3::new(3.0, 3.0, 0.5);
        let blocker = [
            centre + Vec3::new(-0.2, 0.0, -0.2),
            centre + Vec3::new(0.2, 0.0, -0.2),
            centre + Vec3::new(0.0, 0.0, 0.3),
        ];
        assert!(shaft.may_meet_triangle(blocker));
        assert!(shaft.may_meet_box(centre - Vec3::splat(0.1), centre + Vec3::splat(0.1)));
    }

    /// Brute force: any triangle that some box-to-apex segment crosses is
    /// reported as possibly meeting the shaft.
    #[test]
    fn no_triangle_crossed_by_a_segment_is_called_outside() {
        let shaft = lamp_shaft();
        let apex = Vec3::new(5.0, 5.0, 0.5);
        let mut crossed = 0;
        for i in 0..400u32 {
            let f = |k: u32| {
                ((i.wrapping_mul(2_654_435_761).wrapping_add(k * 40_503)) % 10_007) as f32
                    / 10_007.0
            };
            let centre = Vec3::new(f(1) * 7.0 - 1.0, f(2) * 6.0 - 0.5, f(3) * 3.0 - 1.0);
            let tri = [
                centre,
                centre + Vec3::new(f(4), f(5) - 0.5, f(6)) * 0.8,
                centre + Vec3::new(f(7) - 0.5, f(8), f(9) - 0.5) * 0.8,
            ];
            for s in 0..64u32 {
                let x = Vec3::new(
                    (s % 4) as f32 / 3.0,
                    0.1 + (s / 4 % 4) as f32 * 0.4 / 3.0,
                    (s / 16) as f32 / 3.0,
                );
                let ray = crate::accel::triangle::intersect_triangle(
                    &crate::accel::Ray::new(x, apex - x, 1.0),
                    tri[0],
                    tri[1],
                    tri[2],
                );
                if ray.is_some() {
                    crossed += 1;
                    assert!(
                        shaft.may_meet_triangle(tri),
                        "triangle {tri:?} crossed by the segment from {x}"
                    );
                    break;
                }
            }
        }
        assert!(crossed > 10, "{crossed}");
    }
}
