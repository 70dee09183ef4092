//! The watertight ray/triangle test (Woop, Benthin, Wald, "Watertight
//! Ray/Triangle Intersection", JCGT 2013). Every BVH leaf and every brute-force
//! reference in the tests ends here. Rays through a shared edge or vertex of a
//! closed mesh always hit at least one of the triangles that share it, which is
//! what keeps shadow rays from leaking through seams.

use glam::{Vec2, Vec3};

/// A hit on one triangle: `P = (1 - u - v) a + u b + v c` at `origin + t dir`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub barycentric: Vec2,
}

/// The per-ray part of the test, computed once per ray: the axis permutation
/// that makes the ray's dominant axis `z` and the shear that maps the ray onto
/// the `+z` axis through the origin.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    origin: [f32; 3],
    /// The permutation `(kx, ky, kz)`.
    axes: [usize; 3],
    shear: [f32; 3],
    t_max: f32,
}

impl WatertightRay {
    pub fn new(origin: Vec3, direction: Vec3, t_max: f32) -> WatertightRay {
        let dir = direction.to_array();
        let kz = direction.abs().max_position();
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        // Keeps the winding of the projected triangle, so the sign of the edge
        // functions does not depend on the ray's direction along kz.
        if dir[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        WatertightRay {
            origin: origin.to_array(),
            axes: [kx, ky, kz],
            shear: [dir[kx] / dir[kz], dir[ky] / dir[kz], 1.0 / dir[kz]],
            t_max,
        }
    }

    /// Intersects the triangle `(a, b, c)`, front or back, for `t` in
    /// `(0, t_max)`. Degenerate triangles (zero determinant) never hit.
    #[inline(always)]
    pub fn intersect(&self, a: &[f32; 3], b: &[f32; 3], c: &[f32; 3]) -> Option<TriangleHit> {
        let [kx, ky, kz] = self.axes;
        let [sx, sy, sz] = self.shear;
        let o = &self.origin;
        let rel = |p: &[f32; 3]| [p[kx] - o[kx], p[ky] - o[ky], p[kz] - o[kz]];
        let (a, b, c) = (rel(a), rel(b), rel(c));
        // Shear and project onto the plane perpendicular to the ray.
        let ax = a[0] - sx * a[2];
        let ay = a[1] - sy * a[2];
        let bx = b[0] - sx * b[2];
        let by = b[1] - sy * b[2];
        let cx = c[0] - sx * c[2];
        let cy = c[1] - sy * c[2];

        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        // An edge function of exactly zero may be a rounding artefact on a
        // shared edge; redo all three exactly enough in f64 so both
        // neighbours agree on which side the ray passes.
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let f =
                |p: f32, q: f32, r: f32, s: f32| (p as f64 * q as f64 - r as f64 * s as f64) as f32;
            u = f(cx, by, cy, bx);
            v = f(ax, cy, ay, cx);
            w = f(bx, ay, by, ax);
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let t_scaled = u * (sz * a[2]) + v * (sz * b[2]) + w * (sz * c[2]);
        // Same sign as det means t > 0; rejects before paying the division.
        if t_scaled == 0.0 || (t_scaled < 0.0) != (det < 0.0) {
            return None;
        }
        let rcp_det = 1.0 / det;
        let t = t_scaled * rcp_det;
        if !(t > 0.0 && t < self.t_max) {
            return None;
        }
        Some(TriangleHit {
            t,
            barycentric: Vec2::new(v * rcp_det, w * rcp_det),
        })
    }
}

/// One ray against one triangle; the BVHs precompute [`WatertightRay`] once
/// per ray instead.
pub fn intersect_triangle(
    ray: &crate::accel::Ray,
    a: Vec3,
    b: Vec3,
    c: Vec3,
) -> Option<TriangleHit> {
    WatertightRay::new(ray.origin, ray.direction, ray.t_max).intersect(
        &a.to_array(),
        &b.to_array(),
        &c.to_array(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::accel::Ray;

    #[test]
    fn barycentrics_reconstruct_the_hit_point() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let ray = Ray::new(Vec3::new(0.2, 0.3, 1.0), Vec3::new(0.0, 0.0, -2.0), 10.0);
        let hit = intersect_triangle(&ray, a, b, c).expect("hit");
        assert_eq!(hit.t, 0.5);
        let p = (1.0 - hit.barycentric.x - hit.barycentric.y) * a
            + hit.barycentric.x * b
            + hit.barycentric.y * c;
        assert!((p - ray.at(hit.t)).length() < 1e-6);
    }

    #[test]
    fn both_faces_hit_and_interval_is_open() {
        let (a, b, c) = (Vec3::ZERO, Vec3::X, Vec3::Y);
        let down = Ray::new(Vec3::new(0.2, 0.2, 1.0), Vec3::NEG_Z, 10.0);
        let up = Ray::new(Vec3::new(0.2, 0.2, -1.0), Vec3::Z, 10.0);
        assert!(intersect_triangle(&down, a, b, c).is_some());
        assert!(intersect_triangle(&up, a, b, c).is_some());
        // Hit exactly at t_max, and exactly at the origin: both excluded.
        assert!(intersect_triangle(&Ray { t_max: 1.0, ..down }, a, b, c).is_none());
        let on = Ray::new(Vec3::new(0.2, 0.2, 0.0), Vec3::Z, 10.0);
        assert!(intersect_triangle(&on, a, b, c).is_none());
    }

    #[test]
    fn point_triangle_never_hits() {
        let p = Vec3::new(0.5, 0.5, 0.0);
        let ray = Ray::new(Vec3::new(0.5, 0.5, 1.0), Vec3::NEG_Z, 10.0);
        assert!(intersect_triangle(&ray, p, p, p).is_none());
    }
}
