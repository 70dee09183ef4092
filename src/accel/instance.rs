//! One dynamic object of the [`World`](super::World): its own BVH in object
//! space, placed in render space by an affine map that may change every
//! frame. Rays are taken into object space rather than the triangles into
//! render space, so a rigid move costs nothing here; only the world's small
//! top level over instance bounds is rebuilt.

use glam::{Affine3A, Mat3, Vec3};

use super::bounds::Bounds;
use super::clusters::TriangleClusters;
use super::flat::PlacedMesh;
use super::mesh_bvh::{BuildTriangle, Layout, MeshBvh, MeshHit, TriangleRef};
use super::Ray;
use super::BUILD_PARAMS;

pub struct Instance {
    object: u32,
    bvh: MeshBvh,
    /// The object's triangles as given (valid indices only), for rebuilds.
    triangles: Vec<[u32; 3]>,
    positions: Vec<Vec3>,
    to_render: Affine3A,
    /// Inverse of `to_render`; `None` while that is singular, and then the
    /// instance is hit by nothing.
    to_object: Option<Affine3A>,
    /// [`cofactor_map`] of `to_render`.
    normal_to_render: Mat3,
    object_bounds: Bounds,
    /// Fixed clusters of `triangles`, to tell where a deformation changed
    /// the object.
    clusters: TriangleClusters,
}

impl Instance {
    pub fn new(
        object: u32,
        positions: &[Vec3],
        triangles: Vec<[u32; 3]>,
        to_render: Affine3A,
    ) -> Instance {
        let bvh = build(object, &triangles, positions);
        let mut instance = Instance {
            object,
            object_bounds: bounds_of(&bvh),
            clusters: TriangleClusters::new(positions, &triangles),
            bvh,
            triangles,
            positions: positions.to_vec(),
            to_render,
            to_object: None,
            normal_to_render: Mat3::ZERO,
        };
        instance.set_transform(to_render);
        instance
    }

    pub fn triangle_count(&self) -> usize {
        self.bvh.len()
    }

    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    pub fn render_bounds(&self) -> Bounds {
        self.object_bounds.transformed(&self.to_render)
    }

    pub fn set_transform(&mut self, to_render: Affine3A) {
        let det = Mat3::from(to_render.matrix3).determinant();
        self.to_render = to_render;
        self.to_object = (det != 0.0 && to_render.is_finite()).then(|| to_render.inverse());
        self.normal_to_render = cofactor_map(&to_render);
    }

    /// New object-space positions (same count): refits when every kept
    /// triangle still has area and no dropped one gained some, else rebuilds.
    /// Returns the render-space boxes that hold the clusters with a moved
    /// vertex, before and after (see [`TriangleClusters::changed`]), under
    /// the current placement.
    pub fn set_positions(&mut self, positions: &[Vec3]) -> Vec<Bounds> {
        let changed = (self.clusters.changed(&self.positions, positions).iter())
            .map(|bounds| bounds.transformed(&self.to_render))
            .collect();
        self.positions.copy_from_slice(positions);
        let p = &self.positions;
        let vertices = |tri: [u32; 3]| tri.map(|i| p[i as usize]);
        let kept_all = self.bvh.len() == self.triangles.len();
        let refitted = kept_all
            && self
                .bvh
                .refit(|s: TriangleRef| vertices(self.triangles[s.triangle as usize]));
        if !refitted {
            self.bvh = build(self.object, &self.triangles, &self.positions);
        }
        self.object_bounds = bounds_of(&self.bvh);
        changed
    }

    /// The instance in flat form: its BVH and its map into object space.
    pub fn placed_mesh(&self) -> PlacedMesh<'_> {
        PlacedMesh {
            bvh: &self.bvh,
            to_object: self.to_object,
        }
    }

    /// The hit on the triangle in `slot` of this instance's BVH, with its
    /// normal in render space, as [`Instance::closest_hit`] reports it.
    pub fn hit_at(&self, slot: u32, t: f32, barycentric: glam::Vec2) -> Option<MeshHit> {
        let mut hit = self.bvh.hit_at(slot, t, barycentric)?;
        hit.normal = self.normal_in_render(hit.normal);
        Some(hit)
    }

    fn object_ray(&self, ray: &Ray) -> Option<Ray> {
        let m = self.to_object?;
        // The direction is mapped, not normalised, so `t` means the same
        // point in both spaces and hits compare with render-space ones.
        Some(Ray::new(
            m.transform_point3(ray.origin),
            m.transform_vector3(ray.direction),
            ray.t_max,
        ))
    }

    /// Lowers `best` to this instance's closest hit; the hit's `normal` is
    /// mapped into render space.
    pub fn closest_hit(&self, ray: &Ray, best: &mut Option<MeshHit>) {
        let Some(local) = self.object_ray(ray) else {
            return;
        };
        let before = *best;
        self.bvh.closest_hit(&local, best);
        if *best != before {
            if let Some(hit) = best.as_mut() {
                hit.normal = self.normal_in_render(hit.normal);
            }
        }
    }

    /// An object-space triangle normal `(b - a) × (c - a)`, unit, in
    /// render space.
    fn normal_in_render(&self, normal: Vec3) -> Vec3 {
        (self.normal_to_render * normal).normalize()
    }

    pub fn occluded(&self, ray: &Ray) -> bool {
        self.object_ray(ray)
            .is_some_and(|local| self.bvh.occluded(&local))
    }
}

/// The map from an object-space `(b - a) × (c - a)` to the direction of
/// the cross product of the edges `to_render` places: the cofactor matrix
/// `det(M) M^-T`, which keeps orientation under mirroring maps. The GPU's
/// shading points turn an instance's normals with the same matrix.
pub fn cofactor_map(to_render: &Affine3A) -> Mat3 {
    let m = Mat3::from(to_render.matrix3);
    m.inverse().transpose() * m.determinant()
}

/// A refittable BVH over the object's triangles in object space.
fn build(object: u32, triangles: &[[u32; 3]], positions: &[Vec3]) -> MeshBvh {
    let build: Vec<BuildTriangle> = triangles
        .iter()
        .enumerate()
        .map(|(i, tri)| BuildTriangle {
            vertices: tri.map(|v| positions[v as usize]),
            source: TriangleRef {
                object,
                triangle: i as u32,
            },
        })
        .collect();
    MeshBvh::build(&build, Layout::Binary, BUILD_PARAMS)
}

fn bounds_of(bvh: &MeshBvh) -> Bounds {
    Bounds::from_points(bvh.triangles().flat_map(|(v, _)| v))
}
