//! The two-level world the renderer traces against, in render space: all
//! static objects merged into one BVH (built once), plus one object-space
//! BVH per dynamic object under a small top level over their render-space
//! bounds that is rebuilt whenever one of them moves. Static and dynamic
//! visibility can be asked separately, because the light mesh keeps them in
//! separate layers (static bits are cached; dynamic ones are re-tested).

use std::sync::atomic::{AtomicU64, Ordering};
use std::time::Duration;

use glam::{Affine3A, Vec2, Vec3};
use obvhs::{aabb::Aabb, bvh2::builder::build_bvh2, bvh2::Bvh2, BvhBuildParams};

use super::bounds::Bounds;
use super::flat::{FlatDynamic, FlatStatic};
use super::instance::Instance;
use super::mesh_bvh::{BuildTriangle, MeshBvh, MeshHit, TriangleRef};
use super::node_test::TraversalRay;
use super::shaft::Shaft;
use super::traverse::traverse_binary;
use super::{Ray, BUILD_PARAMS, STATIC_LAYOUT};

/// One mesh placed in render space, as the world is built from it.
#[derive(Clone, Copy, Debug)]
pub struct WorldObject<'a> {
    pub positions: &'a [Vec3],
    pub triangles: &'a [[u32; 3]],
    pub to_render: Affine3A,
    pub dynamic: bool,
}

/// The closest hit of a ray.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    /// Index into the slice the world was built from.
    pub object: u32,
    /// Index into that object's `triangles`.
    pub triangle: u32,
    /// `(u, v)` with `P = (1 - u - v) a + u b + v c`.
    pub barycentric: Vec2,
    /// Unit, render space, along `(b - a) × (c - a)` of the placed triangle;
    /// the side to offset new origins into is `±` this (see
    /// [`offset_ray_origin`](super::offset_ray_origin)).
    pub geometric_normal: Vec3,
}

impl From<MeshHit> for Hit {
    fn from(hit: MeshHit) -> Hit {
        Hit {
            t: hit.t,
            object: hit.source.object,
            triangle: hit.source.triangle,
            barycentric: hit.barycentric,
            geometric_normal: hit.normal,
        }
    }
}

#[derive(Debug, thiserror::Error, PartialEq, Eq)]
pub enum WorldError {
    #[error("object {0} is not in the world")]
    UnknownObject(usize),
    #[error("object {0} is static; only dynamic objects can move or deform")]
    NotDynamic(usize),
    #[error("object {object} has {expected} vertices, {given} positions were given")]
    PositionCount {
        object: usize,
        expected: usize,
        given: usize,
    },
}

enum Placement {
    /// Merged into the static BVH; its render-space bounds.
    Static(Bounds),
    /// Index into `World::instances`.
    Dynamic(usize),
}

/// A triangle of the static structure, as [`World::static_occluder`] names
/// it: only meaningful for the world that returned it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct StaticTriangle(u32);

pub struct World {
    static_bvh: MeshBvh,
    static_bounds: Bounds,
    placements: Vec<Placement>,
    instances: Vec<Instance>,
    top: TopLevel,
    /// Tells this world from every other built in the process, so a copy
    /// of it elsewhere (on a GPU) knows whether it still holds this one.
    id: u64,
    /// Counts the moves and deformations of dynamic objects.
    dynamic_revision: u64,
}

/// Which mesh of the world a flat hit lies on: what a GPU's closest-hit
/// record names beside the triangle's slot.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshId {
    Static,
    /// The dynamic object at this index of [`FlatDynamic::instances`].
    Instance(u32),
}

impl World {
    /// Builds the world. Triangles with out-of-range vertex indices are
    /// dropped (with a warning), zero-area ones silently: neither can be hit.
    pub fn build(objects: &[WorldObject]) -> World {
        let mut static_triangles = Vec::new();
        let mut placements = Vec::with_capacity(objects.len());
        let mut instances = Vec::new();
        for (index, object) in objects.iter().enumerate() {
            let triangles = valid_triangles(index, object);
            if object.dynamic {
                placements.push(Placement::Dynamic(instances.len()));
                let (positions, to_render) = (object.positions, object.to_render);
                instances.push(Instance::new(index as u32, positions, triangles, to_render));
                continue;
            }
            let placed: Vec<Vec3> = object
                .positions
                .iter()
                .map(|&p| object.to_render.transform_point3(p))
                .collect();
            let first = static_triangles.len();
            static_triangles.extend(triangles.iter().enumerate().map(|(i, tri)| BuildTriangle {
                vertices: tri.map(|v| placed[v as usize]),
                source: TriangleRef {
                    object: index as u32,
                    triangle: i as u32,
                },
            }));
            let bounds =
                Bounds::from_points(static_triangles[first..].iter().flat_map(|t| t.vertices));
            placements.push(Placement::Static(bounds));
        }
        let static_bvh = MeshBvh::build(&static_triangles, STATIC_LAYOUT, BUILD_PARAMS);
        let static_bounds = Bounds::from_points(static_bvh.triangles().flat_map(|(v, _)| v));
        let top = TopLevel::build(&instances);
        static NEXT_ID: AtomicU64 = AtomicU64::new(0);
        World {
            static_bvh,
            static_bounds,
            placements,
            instances,
            top,
            id: NEXT_ID.fetch_add(1, Ordering::Relaxed),
            dynamic_revision: 0,
        }
    }

    /// Tells this world from every other built in this process.
    pub fn id(&self) -> u64 {
        self.id
    }

    /// Changes whenever a dynamic object moves or deforms: a copy of
    /// [`World::flat_dynamic`] taken at an earlier revision is stale.
    pub fn dynamic_revision(&self) -> u64 {
        self.dynamic_revision
    }

    /// The static structure in flat form (it never changes).
    pub fn flat_static(&self) -> FlatStatic {
        FlatStatic::of(&self.static_bvh)
    }

    /// The dynamic objects, their placements and the top level over them,
    /// in flat form, as they stand now.
    pub fn flat_dynamic(&self) -> FlatDynamic {
        let mut flat = FlatDynamic::default();
        for instance in &self.instances {
            flat.push_instance(instance.placed_mesh());
        }
        let members = self.top.bvh.primitive_indices.iter();
        flat.push_top_level(
            &self.top.bvh,
            members.map(|&slot| self.top.members[slot as usize] as u32),
        );
        flat
    }

    /// The hit a flat traversal found on `slot` of `mesh` at `t` with
    /// `barycentric`, completed as [`World::closest_hit`] completes its
    /// own (source, render-space normal). None for a slot the world does
    /// not have.
    pub fn hit_at(&self, mesh: MeshId, slot: u32, t: f32, barycentric: Vec2) -> Option<Hit> {
        let hit = match mesh {
            MeshId::Static => self.static_bvh.hit_at(slot, t, barycentric),
            MeshId::Instance(i) => self.instances.get(i as usize)?.hit_at(slot, t, barycentric),
        }?;
        Some(Hit::from(hit))
    }

    /// The closest hit in `(0, t_max)`; of hits at exactly equal `t`, the one
    /// with the lowest `(object, triangle)`, so results never depend on tree
    /// shape or thread count.
    pub fn closest_hit(&self, ray: &Ray) -> Option<Hit> {
        let mut best = None;
        self.static_bvh.closest_hit(ray, &mut best);
        self.top
            .visit(ray, best.map_or(ray.t_max, |b| b.t), |i, t_cull| {
                self.instances[i].closest_hit(ray, &mut best);
                *t_cull = best.map_or(*t_cull, |b| b.t);
                true
            });
        best.map(Hit::from)
    }

    /// The closest hit in `(0, t_max)` on static geometry alone, with the
    /// tie rule of [`World::closest_hit`].
    pub fn closest_static_hit(&self, ray: &Ray) -> Option<Hit> {
        let mut best = None;
        self.static_bvh.closest_hit(ray, &mut best);
        best.map(Hit::from)
    }

    /// Whether no static triangle may meet `shaft`; false when unsure.
    pub fn shaft_is_clear_static(&self, shaft: &Shaft) -> bool {
        self.static_bvh.shaft_is_empty(shaft)
    }

    /// Whether the world has any dynamic object at all.
    pub fn has_dynamic(&self) -> bool {
        !self.instances.is_empty()
    }

    /// Whether no dynamic object's bounds may meet `shaft`.
    pub fn shaft_is_clear_dynamic(&self, shaft: &Shaft) -> bool {
        self.instances.iter().all(|instance| {
            let bounds = instance.render_bounds();
            !shaft.may_meet_box(bounds.min, bounds.max)
        })
    }

    /// Whether anything, static or dynamic, lies on the ray in `(0, t_max)`.
    pub fn occluded(&self, ray: &Ray) -> bool {
        // The dynamic part is the small one: try it first.
        self.occluded_dynamic(ray) || self.occluded_static(ray)
    }

    /// [`World::occluded`]'s answer, trying the static triangle in
    /// `blocker` (what a nearby segment crossed) before walking the
    /// static tree, and keeping there the one this ray crosses.
    pub fn occluded_near(&self, ray: &Ray, blocker: &mut Option<StaticTriangle>) -> bool {
        if self.occluded_dynamic(ray) {
            return true;
        }
        match self.static_occluder(ray, *blocker) {
            Some(triangle) => {
                *blocker = Some(triangle);
                true
            }
            None => false,
        }
    }

    /// Whether static geometry lies on the ray in `(0, t_max)`.
    pub fn occluded_static(&self, ray: &Ray) -> bool {
        self.static_bvh.occluded(ray)
    }

    /// A static triangle on the ray in `(0, t_max)`, or None: the same
    /// answer as [`World::occluded_static`], trying `hint` (what a nearby
    /// segment found) before walking the tree.
    pub fn static_occluder(
        &self,
        ray: &Ray,
        hint: Option<StaticTriangle>,
    ) -> Option<StaticTriangle> {
        self.static_bvh
            .occluder(ray, hint.map(|triangle| triangle.0))
            .map(StaticTriangle)
    }

    /// Whether the static triangle crosses every segment of `rays` well
    /// inside its edges and the segment (see
    /// [`MeshBvh::crosses_well_inside`]): given the segments from a box's
    /// corners to a light, the triangle hides the whole box from it.
    pub fn static_triangle_hides(&self, triangle: StaticTriangle, rays: &[Ray]) -> bool {
        self.static_bvh.crosses_well_inside(triangle.0, rays)
    }

    /// Whether a dynamic object lies on the ray in `(0, t_max)`.
    pub fn occluded_dynamic(&self, ray: &Ray) -> bool {
        let mut hit = false;
        self.top.visit(ray, ray.t_max, |i, _| {
            hit = self.instances[i].occluded(ray);
            !hit
        });
        hit
    }

    /// Places a dynamic object anew (a rigid move); rebuilds only the top
    /// level, `O(d log d)` for `d` dynamic objects.
    pub fn set_transform(&mut self, object: usize, to_render: Affine3A) -> Result<(), WorldError> {
        let i = self.dynamic_index(object)?;
        self.instances[i].set_transform(to_render);
        self.top = TopLevel::build(&self.instances);
        self.dynamic_revision += 1;
        Ok(())
    }

    /// New object-space positions for a deformed dynamic object (skinning,
    /// morph targets): its BVH is refitted, or rebuilt when triangles gain or
    /// lose area; then the top level is rebuilt. Returns where the object
    /// changed: the render-space boxes, at the old positions and at the new
    /// ones, of each of its fixed clusters of triangles that has a moved
    /// vertex ([`TriangleClusters`](super::clusters::TriangleClusters)),
    /// under the object's current transform; nothing when no vertex moved.
    pub fn set_positions(
        &mut self,
        object: usize,
        positions: &[Vec3],
    ) -> Result<Vec<Bounds>, WorldError> {
        let i = self.dynamic_index(object)?;
        let expected = self.instances[i].vertex_count();
        if positions.len() != expected {
            return Err(WorldError::PositionCount {
                object,
                expected,
                given: positions.len(),
            });
        }
        let changed = self.instances[i].set_positions(positions);
        self.top = TopLevel::build(&self.instances);
        self.dynamic_revision += 1;
        Ok(changed)
    }

    /// Brings dynamic object `object` to the render-space transform
    /// `to_render` and, when it deformed, to the object-space `positions`;
    /// `moved` says the transform changed. Returns where its geometry
    /// changed, for invalidation: a rigid move changes all of it, its old
    /// and its new bounds; a deformation in place only the old and new
    /// boxes of the clusters with a moved vertex ([`World::set_positions`]),
    /// much tighter around a swaying crown than its whole box.
    pub fn update_object(
        &mut self,
        object: usize,
        to_render: Affine3A,
        positions: Option<&[Vec3]>,
        moved: bool,
    ) -> Vec<Bounds> {
        let before = self.object_bounds(object);
        let update = match positions {
            Some(positions) => self.set_positions(object, positions),
            None => Ok(Vec::new()),
        }
        .and_then(|deformed| self.set_transform(object, to_render).map(|()| deformed));
        // Static objects never move; an update refused for one means the
        // scene model and the world disagree, which only a bug can cause.
        debug_assert!(
            update.is_ok(),
            "world update of object {object}: {update:?}"
        );
        match update {
            Ok(parts) if !moved => parts,
            // A rigid move changes everything; so, to stay safe, does an
            // update the world refused.
            _ => before
                .into_iter()
                .chain(self.object_bounds(object))
                .collect(),
        }
    }

    /// Render-space bounds of everything in the world now.
    pub fn bounds(&self) -> Bounds {
        (self.instances.iter()).fold(self.static_bounds, |b, i| b.union(i.render_bounds()))
    }

    /// Render-space bounds of one object's triangles now; `None` for an index
    /// not in the world. Empty ([`Bounds::is_empty`]) if it has no triangle.
    pub fn object_bounds(&self, object: usize) -> Option<Bounds> {
        match self.placements.get(object)? {
            Placement::Static(bounds) => Some(*bounds),
            Placement::Dynamic(i) => Some(self.instances[*i].render_bounds()),
        }
    }

    /// Triangles that can be hit (zero-area and invalid ones excluded).
    pub fn triangle_count(&self) -> usize {
        self.static_bvh.len()
            + self
                .instances
                .iter()
                .map(Instance::triangle_count)
                .sum::<usize>()
    }

    fn dynamic_index(&self, object: usize) -> Result<usize, WorldError> {
        match self.placements.get(object) {
            None => Err(WorldError::UnknownObject(object)),
            Some(Placement::Static(_)) => Err(WorldError::NotDynamic(object)),
            Some(Placement::Dynamic(i)) => Ok(*i),
        }
    }
}

/// The object's triangles whose indices are all in range.
fn valid_triangles(index: usize, object: &WorldObject) -> Vec<[u32; 3]> {
    let n = object.positions.len();
    let valid: Vec<[u32; 3]> = (object.triangles.iter())
        .filter(|t| t.iter().all(|&v| (v as usize) < n))
        .copied()
        .collect();
    let dropped = object.triangles.len() - valid.len();
    if dropped > 0 {
        log::warn!("object {index}: {dropped} triangles index past its {n} vertices; dropped");
    }
    valid
}

/// A BVH over the render-space bounds of the dynamic instances that have
/// triangles.
struct TopLevel {
    bvh: Bvh2,
    /// Instance index of each primitive of `bvh`.
    members: Vec<usize>,
}

impl TopLevel {
    fn build(instances: &[Instance]) -> TopLevel {
        let (members, aabbs): (Vec<usize>, Vec<Aabb>) = (instances.iter().enumerate())
            .map(|(i, inst)| (i, inst.render_bounds()))
            .filter(|(_, b)| !b.is_empty())
            .map(|(i, b)| (i, Aabb::new(b.min.into(), b.max.into())))
            .unzip();
        let bvh = if aabbs.is_empty() {
            Bvh2::default()
        } else {
            build_bvh2(&aabbs, TOP_LEVEL_PARAMS, &mut Duration::default())
        };
        TopLevel { bvh, members }
    }

    /// Calls `visit` with the index of each instance whose bounds the ray
    /// meets before `t_cull`, as [`traverse_binary`] does.
    fn visit(&self, ray: &Ray, t_cull: f32, mut visit: impl FnMut(usize, &mut f32) -> bool) {
        if self.members.is_empty() {
            return;
        }
        let traversal = TraversalRay::new(ray.origin, ray.direction);
        traverse_binary(&self.bvh, &traversal, t_cull, |slot, t_cull: &mut f32| {
            visit(
                self.members[self.bvh.primitive_indices[slot] as usize],
                t_cull,
            )
        });
    }
}

/// The top level is small and rebuilt often: build fast, one instance per
/// leaf.
const TOP_LEVEL_PARAMS: BvhBuildParams = BvhBuildParams::fastest_build();
