//! A ray or segment in render space: `origin + t * direction` for `t` in
//! `(0, t_max)`, both ends excluded. Every query of the ray tracing core takes
//! one of these; the open interval is what lets a shadow segment end on a light
//! or a lattice node without counting the end point as a hit.

use glam::Vec3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ray {
    pub origin: Vec3,
    /// Need not be unit length; `t` is measured in multiples of it, so a
    /// segment from `a` to `b` is `Ray { origin: a, direction: b - a, t_max: 1 }`.
    pub direction: Vec3,
    pub t_max: f32,
}

impl Ray {
    pub fn new(origin: Vec3, direction: Vec3, t_max: f32) -> Ray {
        Ray {
            origin,
            direction,
            t_max,
        }
    }

    /// The segment from `from` to `to`, both ends excluded: what a shadow
    /// test between a shading point (or lattice node) and a light needs.
    pub fn segment(from: Vec3, to: Vec3) -> Ray {
        Ray::new(from, to - from, 1.0)
    }

    /// The point at parameter `t`.
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + t * self.direction
    }
}
