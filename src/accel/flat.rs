//! The [`World`](super::World) in flat form: plain arrays of `Pod` records
//! that a GPU backend uploads as they are, and that the shaders in
//! `backend/gpu/shaders/scene.wgsl` declare field for field. The static
//! part (the merged wide BVH and its triangles) never changes after the
//! world is built; the dynamic part (each dynamic object's binary BVH and
//! triangles, the instance placements and the top level over them) changes
//! whenever an object moves or deforms, and [`World::dynamic_revision`]
//! says when.
//!
//! The trees are the CPU's own, box for box and slot for slot, so a ray
//! that reaches a different triangle on the GPU points at a shader bug,
//! not at a different build.
//!
//! [`World::dynamic_revision`]: super::World::dynamic_revision

use bytemuck::{Pod, Zeroable};
use obvhs::bvh2::Bvh2;

use super::mesh_bvh::{MeshBvh, TriangleRef};

/// One node of the static wide BVH: the children's boxes as
/// `planes[(axis * 2 + side) * 8 + child]` (side 0 the min planes), where
/// each child leads (a node, or a leaf's first slot), the leaf counts four
/// to a word, and a bit per slot that holds a child. Empty slots have zero
/// planes and no bit: the shaders never rely on infinite planes.
#[repr(C)]
#[derive(Clone, Copy, Debug, Pod, Zeroable)]
pub struct FlatWideNode {
    pub planes: [f32; 48],
    pub child: [u32; 8],
    pub counts: [u32; 2],
    pub valid: u32,
    pub _pad: [u32; 5],
}

/// One node of a binary BVH (a dynamic object's, or the top level):
/// obvhs' layout, children of an inner node at `first_index` and
/// `first_index + 1`, a leaf's slots from `first_index`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FlatBinaryNode {
    pub min: [f32; 3],
    pub prim_count: u32,
    pub max: [f32; 3],
    pub first_index: u32,
}

/// A dynamic object as the shaders see it: the affine map from render to
/// object space by columns (translation last), where its nodes start in
/// the dynamic node array and its triangles in the dynamic slot arrays.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct FlatInstance {
    pub to_object: [[f32; 4]; 4],
    pub node_offset: u32,
    pub slot_offset: u32,
    /// 0 while the placement is singular: then nothing hits the instance.
    pub valid: u32,
    pub _pad: u32,
}

/// A mesh's triangles in slot order: nine floats and a source each.
#[derive(Clone, Debug, Default)]
pub struct FlatTriangles {
    pub vertices: Vec<[[f32; 3]; 3]>,
    /// `(object, triangle)` per slot: what closest hits are tied by.
    pub sources: Vec<[u32; 2]>,
}

impl FlatTriangles {
    fn extend_from(&mut self, bvh: &MeshBvh) {
        let (vertices, sources) = bvh.slots();
        self.vertices.extend_from_slice(vertices);
        self.sources.extend(
            sources
                .iter()
                .map(|&TriangleRef { object, triangle }| [object, triangle]),
        );
    }
}

/// The static part: built once with the world.
#[derive(Clone, Debug, Default)]
pub struct FlatStatic {
    pub nodes: Vec<FlatWideNode>,
    pub triangles: FlatTriangles,
    /// Nodes on the longest root-to-leaf path.
    pub depth: usize,
}

/// The dynamic part, as it stands after the last move or deformation.
#[derive(Clone, Debug, Default)]
pub struct FlatDynamic {
    /// Every instance's nodes, then the top level's.
    pub nodes: Vec<FlatBinaryNode>,
    pub triangles: FlatTriangles,
    pub instances: Vec<FlatInstance>,
    /// Where the top level starts in `nodes`, and how many nodes it has
    /// (0: no dynamic object has a triangle).
    pub top_offset: u32,
    pub top_count: u32,
    /// The instance index of each top-level primitive slot.
    pub top_members: Vec<u32>,
    /// Nodes on the longest root-to-leaf path of any of its trees.
    pub depth: usize,
}

impl FlatStatic {
    pub(super) fn of(bvh: &MeshBvh) -> FlatStatic {
        let mut triangles = FlatTriangles::default();
        triangles.extend_from(bvh);
        let (nodes, depth) = match bvh.wide() {
            Some(tree) => (tree.nodes.iter().map(flat_wide_node).collect(), tree.depth),
            None => (Vec::new(), 0),
        };
        FlatStatic {
            nodes,
            triangles,
            depth,
        }
    }
}

/// One dynamic object, as [`FlatDynamic::push_instance`] takes it.
pub(super) struct PlacedMesh<'a> {
    pub bvh: &'a MeshBvh,
    pub to_object: Option<glam::Affine3A>,
}

impl FlatDynamic {
    pub(super) fn push_instance(&mut self, placed: PlacedMesh) {
        let node_offset = self.nodes.len() as u32;
        let slot_offset = self.triangles.vertices.len() as u32;
        if let Some(tree) = placed.bvh.binary() {
            self.nodes.extend(tree.nodes.iter().map(flat_binary_node));
            self.depth = self.depth.max(binary_depth(tree));
        }
        self.triangles.extend_from(placed.bvh);
        let has_nodes = self.nodes.len() as u32 > node_offset;
        let to_object = placed.to_object.filter(|_| has_nodes);
        self.instances.push(FlatInstance {
            to_object: to_object.map_or([[0.0; 4]; 4], |m| {
                let c = |v: glam::Vec3A| [v.x, v.y, v.z, 0.0];
                [
                    c(m.matrix3.x_axis),
                    c(m.matrix3.y_axis),
                    c(m.matrix3.z_axis),
                    c(m.translation),
                ]
            }),
            node_offset,
            slot_offset,
            valid: to_object.is_some() as u32,
            _pad: 0,
        });
    }

    /// Appends the top level: `members` maps its primitive slots to
    /// instance indices.
    pub(super) fn push_top_level(&mut self, tree: &Bvh2, members: impl Iterator<Item = u32>) {
        self.top_offset = self.nodes.len() as u32;
        self.top_count = tree.nodes.len() as u32;
        self.nodes.extend(tree.nodes.iter().map(flat_binary_node));
        self.top_members = members.collect();
        if !tree.nodes.is_empty() {
            self.depth = self.depth.max(binary_depth(tree));
        }
    }
}

fn flat_wide_node(node: &super::wide::WideNode) -> FlatWideNode {
    let mut flat = FlatWideNode::zeroed();
    for child in 0..8 {
        let Some(corners) = node.child_box(child) else {
            continue;
        };
        flat.valid |= 1 << child;
        for axis in 0..3 {
            for (side, corner) in corners.iter().enumerate() {
                flat.planes[(axis * 2 + side) * 8 + child] = corner[axis];
            }
        }
        flat.child[child] = node.child[child];
        flat.counts[child / 4] |= u32::from(node.prim_count[child]) << (8 * (child % 4));
    }
    flat
}

fn flat_binary_node(node: &obvhs::bvh2::node::Bvh2Node) -> FlatBinaryNode {
    FlatBinaryNode {
        min: node.aabb().min.to_array(),
        prim_count: node.prim_count,
        max: node.aabb().max.to_array(),
        first_index: node.first_index,
    }
}

/// Nodes on the longest root-to-leaf path of a binary tree.
fn binary_depth(tree: &Bvh2) -> usize {
    let mut deepest = 0;
    let mut stack = vec![(0usize, 1usize)];
    while let Some((index, depth)) = stack.pop() {
        let Some(node) = tree.nodes.get(index) else {
            continue;
        };
        deepest = deepest.max(depth);
        if !node.is_leaf() {
            let first = node.first_index as usize;
            stack.extend([(first, depth + 1), (first + 1, depth + 1)]);
        }
    }
    deepest
}
