//! A ray or segment: `origin + t * direction` for `t` in `(0, t_max)`.

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
}
