//! Axis-aligned bounds in render or object space: what the scheduler's
//! `FrameDelta` reports for moved objects (their old and new bounds drive the
//! light-mesh invalidation) and what the top level of the [`World`] is built
//! over.
//!
//! [`World`]: super::World

use glam::{Affine3A, Vec3};

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: Vec3,
    pub max: Vec3,
}

impl Bounds {
    /// Contains nothing; the identity of [`Bounds::union`].
    pub const EMPTY: Bounds = Bounds {
        min: Vec3::INFINITY,
        max: Vec3::NEG_INFINITY,
    };

    pub fn from_points(points: impl IntoIterator<Item = Vec3>) -> Bounds {
        points.into_iter().fold(Bounds::EMPTY, Bounds::including)
    }

    pub fn is_empty(&self) -> bool {
        self.min.cmpgt(self.max).any()
    }

    pub fn including(self, p: Vec3) -> Bounds {
        Bounds {
            min: self.min.min(p),
            max: self.max.max(p),
        }
    }

    pub fn union(self, other: Bounds) -> Bounds {
        Bounds {
            min: self.min.min(other.min),
            max: self.max.max(other.max),
        }
    }

    /// Bounds of the eight transformed corners: exact for the box, so at most
    /// as loose as the box itself for what it contains.
    pub fn transformed(self, m: &Affine3A) -> Bounds {
        if self.is_empty() {
            return self;
        }
        Bounds::from_points((0..8).map(|i| {
            let pick = |bit: usize, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
            m.transform_point3(Vec3::new(
                pick(1, self.min.x, self.max.x),
                pick(2, self.min.y, self.max.y),
                pick(4, self.min.z, self.max.z),
            ))
        }))
    }
}
