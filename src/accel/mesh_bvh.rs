//! One BVH over one list of triangles: the merged static geometry of the
//! [`World`](super::World) in render space, or one dynamic object in its own
//! object space. Built with obvhs' PLOC builder; triangles are stored in the
//! BVH's primitive order, so a leaf's primitive slot is the storage index
//! (no `primitive_indices` lookup per test). Closest hits are ordered by
//! `(t, object, triangle)`, so ties at exactly equal `t` (a ray through a
//! shared edge) resolve the same way whatever the tree's shape, the layout,
//! or the thread count.

use std::time::Duration;

use glam::{Vec2, Vec3};
use obvhs::{
    aabb::Aabb, bvh2::builder::build_bvh2, bvh2::Bvh2, cwbvh::builder::build_cwbvh, cwbvh::CwBvh,
    BvhBuildParams,
};

use super::node_test::TraversalRay;
use super::shaft::Shaft;
use super::traverse::{traverse_binary, traverse_wide, NodeTestPath, Order, Visit};
use super::triangle::WatertightRay;
use super::wide::WideBvh;
use super::Ray;
use hit_visitors::{AnyHit, ClosestHit};

mod hit_visitors;

/// Where a stored triangle came from: the object's index in the slice the
/// world was built from, and the triangle's index in that object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct TriangleRef {
    pub object: u32,
    pub triangle: u32,
}

/// A triangle to build from, already in the BVH's space.
#[derive(Clone, Copy, Debug)]
pub struct BuildTriangle {
    pub vertices: [Vec3; 3],
    pub source: TriangleRef,
}

/// Which tree to build. `Wide` (obvhs' CWBVH topology, eight children per
/// node, held as our [`WideBvh`] with exact boxes) traverses faster; `Binary`
/// (obvhs' BVH2) can be refitted after the triangles move.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Layout {
    Wide,
    Binary,
}

enum Tree {
    Wide(WideBvh),
    Binary(Bvh2),
}

/// What obvhs builds, before the wide tree is converted to ours.
enum Built {
    Wide(CwBvh),
    Binary(Bvh2),
}

/// The best hit found so far, in the space of the ray that found it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MeshHit {
    pub t: f32,
    pub source: TriangleRef,
    pub barycentric: Vec2,
    /// Unit `(b - a) × (c - a)` in the BVH's space.
    pub normal: Vec3,
}

impl MeshHit {
    /// The order closest hits are chosen by; see the module docs.
    fn precedes(&self, other: &Option<MeshHit>) -> bool {
        other.is_none_or(|o| (self.t, self.source) < (o.t, o.source))
    }
}

/// How far inside a triangle and its segments [`MeshBvh::crosses_well_inside`]
/// wants every crossing: far above the rounding of the watertight test
/// (about 1e-7 relative), far below the scale of a wall seen from a brick.
pub const HIDING_MARGIN: f32 = 1e-4;

pub struct MeshBvh {
    tree: Tree,
    /// Vertices in primitive-slot order.
    vertices: Vec<[[f32; 3]; 3]>,
    sources: Vec<TriangleRef>,
    /// How the wide tree's nodes are tested: the widest this CPU runs,
    /// found once at build.
    node_test: NodeTestPath,
}

impl MeshBvh {
    /// Builds over the triangles, dropping zero-area ones (their f64 cross
    /// product is exactly zero) and ones with non-finite vertices.
    ///
    /// obvhs' builder is parallel and parts of it (an unstable parallel radix
    /// sort of equal costs) may order ties differently from run to run, so
    /// the build runs on one thread: the same triangles give the same tree.
    pub fn build(triangles: &[BuildTriangle], layout: Layout, params: BvhBuildParams) -> MeshBvh {
        let kept: Vec<&BuildTriangle> =
            triangles.iter().filter(|t| has_area(&t.vertices)).collect();
        let aabbs: Vec<Aabb> = kept
            .iter()
            .map(|t| {
                let [a, b, c] = t.vertices.map(Into::into);
                Aabb::new(a, a)
                    .union(&Aabb::new(b, b))
                    .union(&Aabb::new(c, c))
            })
            .collect();
        let tree = if aabbs.is_empty() {
            match layout {
                Layout::Wide => Built::Wide(CwBvh::default()),
                Layout::Binary => Built::Binary(Bvh2::default()),
            }
        } else {
            single_threaded(|| match layout {
                Layout::Wide => Built::Wide(build_cwbvh(&aabbs, params, &mut Duration::default())),
                Layout::Binary => {
                    Built::Binary(build_bvh2(&aabbs, params, &mut Duration::default()))
                }
            })
        };
        let order = match &tree {
            Built::Wide(t) => &t.primitive_indices,
            Built::Binary(t) => &t.primitive_indices,
        };
        let vertices: Vec<[[f32; 3]; 3]> = order
            .iter()
            .map(|&i| kept[i as usize].vertices.map(|v| v.to_array()))
            .collect();
        let sources = order.iter().map(|&i| kept[i as usize].source).collect();
        let tree = match tree {
            Built::Wide(cwbvh) => Tree::Wide(WideBvh::from_cwbvh(&cwbvh, |slot| {
                aabbs[cwbvh.primitive_indices[slot] as usize]
            })),
            Built::Binary(bvh2) => Tree::Binary(bvh2),
        };
        MeshBvh {
            tree,
            vertices,
            sources,
            node_test: NodeTestPath::detect(),
        }
    }

    /// Triangles stored (zero-area ones were dropped).
    pub fn len(&self) -> usize {
        self.vertices.len()
    }

    pub fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }

    /// Triangles stored, with their sources, in storage order.
    pub fn triangles(&self) -> impl Iterator<Item = ([Vec3; 3], TriangleRef)> + '_ {
        self.vertices
            .iter()
            .zip(&self.sources)
            .map(|(v, s)| (v.map(Vec3::from_array), *s))
    }

    /// Vertices and sources in slot order: what the flat form uploads.
    pub fn slots(&self) -> (&[[[f32; 3]; 3]], &[TriangleRef]) {
        (&self.vertices, &self.sources)
    }

    /// The wide tree, for a mesh built with [`Layout::Wide`].
    pub(super) fn wide(&self) -> Option<&WideBvh> {
        match &self.tree {
            Tree::Wide(tree) => Some(tree),
            Tree::Binary(_) => None,
        }
    }

    /// The binary tree, for a mesh built with [`Layout::Binary`].
    pub(super) fn binary(&self) -> Option<&Bvh2> {
        match &self.tree {
            Tree::Binary(tree) => Some(tree),
            Tree::Wide(_) => None,
        }
    }

    /// The hit on the triangle in `slot` at `t` with `barycentric`, as
    /// [`MeshBvh::closest_hit`] would report it: for hits found elsewhere
    /// (a GPU) on this mesh's slots. None for a slot not in the mesh.
    pub fn hit_at(&self, slot: u32, t: f32, barycentric: Vec2) -> Option<MeshHit> {
        let vertices = self.vertices.get(slot as usize)?;
        Some(MeshHit {
            t,
            source: self.sources[slot as usize],
            barycentric,
            normal: normal(vertices),
        })
    }

    /// Lowers `best` to the closest hit of `ray` on this mesh, if any is
    /// closer (ties by [`TriangleRef`]). `ray` is in this BVH's space;
    /// `best.t` must be comparable, i.e. measured along the same parameter.
    pub fn closest_hit(&self, ray: &Ray, best: &mut Option<MeshHit>) {
        let traversal = TraversalRay::new(ray.origin, ray.direction);
        let t_cull = best.map_or(ray.t_max, |b| b.t);
        let visitor = ClosestHit {
            mesh: self,
            exact: WatertightRay::new(ray.origin, ray.direction, ray.t_max),
            best,
        };
        self.walk(&traversal, Order::Nearest, t_cull, visitor);
    }

    /// Whether anything lies on the ray in `(0, t_max)`; stops at the first
    /// hit found.
    pub fn occluded(&self, ray: &Ray) -> bool {
        self.occluder(ray, None).is_some()
    }

    /// The slot of a triangle on the ray in `(0, t_max)`, or None when
    /// nothing is. `hint`, a slot an earlier segment found, is tested first:
    /// neighbouring segments to one light usually cross the same wall, and
    /// one triangle test costs a small fraction of a walk. Whether a slot
    /// comes back is exactly [`MeshBvh::occluded`]; which slot it is depends
    /// on the hint.
    pub fn occluder(&self, ray: &Ray, hint: Option<u32>) -> Option<u32> {
        let exact = WatertightRay::new(ray.origin, ray.direction, ray.t_max);
        if let Some(slot) = hint.filter(|&slot| (slot as usize) < self.vertices.len()) {
            let [a, b, c] = &self.vertices[slot as usize];
            if exact.intersect(a, b, c).is_some() {
                return Some(slot);
            }
        }
        let traversal = TraversalRay::new(ray.origin, ray.direction);
        let mut found = None;
        let visitor = AnyHit {
            vertices: &self.vertices,
            exact,
            found: &mut found,
        };
        self.walk(&traversal, Order::Octant, ray.t_max, visitor);
        found
    }

    /// Whether the triangle in `slot` crosses every segment of `rays` well
    /// inside its edges and well inside the segment: every barycentric
    /// coordinate and `t / t_max` at least [`HIDING_MARGIN`] from its limit.
    ///
    /// For the segments from the eight corners of a box to one point, this
    /// proves that the triangle hides the whole box from that point: the
    /// points whose segment crosses a triangle (its shadow volume) form a
    /// convex set, so with the corners the box lies inside it, and the
    /// margins keep the rounded test of any segment from inside the box a
    /// hit as well.
    pub fn crosses_well_inside(&self, slot: u32, rays: &[Ray]) -> bool {
        let Some([a, b, c]) = self.vertices.get(slot as usize) else {
            return false;
        };
        rays.iter().all(|ray| {
            let exact = WatertightRay::new(ray.origin, ray.direction, ray.t_max);
            exact.intersect(a, b, c).is_some_and(|hit| {
                let weights = [
                    hit.barycentric.x,
                    hit.barycentric.y,
                    1.0 - hit.barycentric.x - hit.barycentric.y,
                ];
                let along = hit.t / ray.t_max;
                weights.iter().all(|&w| w >= HIDING_MARGIN)
                    && (HIDING_MARGIN..=1.0 - HIDING_MARGIN).contains(&along)
            })
        })
    }

    /// Whether no triangle may meet `shaft` (see [`Shaft`]). A binary tree
    /// is not walked: unless it is empty it answers "may meet", which is
    /// always safe.
    pub fn shaft_is_empty(&self, shaft: &Shaft) -> bool {
        match &self.tree {
            Tree::Wide(tree) => tree.visit_boxes(
                |min, max| shaft.may_meet_box(min.into(), max.into()),
                |slot| !shaft.may_meet_triangle(self.vertices[slot].map(Vec3::from_array)),
            ),
            Tree::Binary(_) => self.is_empty(),
        }
    }

    /// Visits candidate slots; `order` applies to the wide layout (the
    /// binary one always goes near child first).
    fn walk(&self, ray: &TraversalRay, order: Order, t_cull: f32, visit: impl Visit) {
        match &self.tree {
            Tree::Wide(t) => traverse_wide(t, ray, order, self.node_test, t_cull, visit),
            Tree::Binary(t) => traverse_binary(t, ray, t_cull, visit),
        }
    }

    /// Moves the stored triangles to `vertices_of(source)` and refits the
    /// boxes, keeping the tree's topology. Only a `Binary` tree refits;
    /// returns `false` (and changes nothing) for a `Wide` one or when a
    /// triangle would lose its area, in which case rebuild instead.
    pub fn refit(&mut self, vertices_of: impl Fn(TriangleRef) -> [Vec3; 3]) -> bool {
        let Tree::Binary(tree) = &mut self.tree else {
            return false;
        };
        let moved: Vec<[Vec3; 3]> = self.sources.iter().map(|&s| vertices_of(s)).collect();
        if !moved.iter().all(has_area) {
            return false;
        }
        for (stored, new) in self.vertices.iter_mut().zip(&moved) {
            *stored = new.map(|v| v.to_array());
        }
        for node in tree.nodes.iter_mut().filter(|n| n.is_leaf()) {
            let first = node.first_index as usize;
            let aabb = moved[first..first + node.prim_count as usize]
                .iter()
                .flatten()
                .fold(Aabb::empty(), |mut b, &v| {
                    b.extend(v.into());
                    b
                });
            node.set_aabb(aabb);
        }
        tree.refit_all();
        true
    }
}

/// Zero-area triangles must never be hit; the watertight test rejects a zero
/// determinant but rounding may make a collinear triangle's determinant
/// non-zero, so they are dropped here instead. Differences of f32 and their
/// products are exact in f64, so this is a collinearity test up to one
/// rounding.
fn has_area(v: &[Vec3; 3]) -> bool {
    let [a, b, c] = v.map(|p| p.as_dvec3());
    v.iter().all(|p| p.is_finite()) && (b - a).cross(c - a) != glam::DVec3::ZERO
}

/// Unit geometric normal, computed in f64 so that tiny triangles (whose f32
/// cross product may underflow) still get one.
fn normal(v: &[[f32; 3]; 3]) -> Vec3 {
    let [a, b, c] = v.map(|p| Vec3::from_array(p).as_dvec3());
    (b - a).cross(c - a).normalize().as_vec3()
}

fn single_threaded<R: Send>(build: impl FnOnce() -> R + Send) -> R {
    match rayon::ThreadPoolBuilder::new().num_threads(1).build() {
        Ok(pool) => pool.install(build),
        // Without a pool of our own, build on the caller's: hits stay the
        // same (ties are ordered by id), only the tree may differ.
        Err(e) => {
            log::warn!("no single-thread pool for the BVH build ({e}); building on the caller's");
            build()
        }
    }
}

#[cfg(test)]
mod node_test_paths;
