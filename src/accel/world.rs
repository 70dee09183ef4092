//! STUB: to be written (two-level world).

use glam::{Affine3A, Vec2, Vec3};

use super::Ray;

/// One mesh placed in render space, as the world is built from it.
#[derive(Clone, Copy, Debug)]
pub struct WorldObject<'a> {
    pub positions: &'a [Vec3],
    pub triangles: &'a [[u32; 3]],
    pub to_render: Affine3A,
    pub dynamic: bool,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub object: u32,
    pub triangle: u32,
    pub barycentric: Vec2,
    pub geometric_normal: Vec3,
}

pub struct World {}

impl World {
    pub fn build(_objects: &[WorldObject]) -> World {
        todo!()
    }
    pub fn closest_hit(&self, _ray: &Ray) -> Option<Hit> {
        todo!()
    }
    pub fn occluded(&self, _ray: &Ray) -> bool {
        todo!()
    }
}
