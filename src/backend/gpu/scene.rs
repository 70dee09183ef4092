//! The world on the GPU: the flat arrays of `accel::flat` in storage
//! buffers. The static part goes up once per world; the dynamic part again
//! only when the world's dynamic revision moved (an object moved or
//! deformed), so a fly-through over a still city uploads nothing.

use bytemuck::{Pod, Zeroable};

use super::context::{GpuContext, GpuError};
use super::contract::{
    BINARY_NODES, DYNAMIC_IDS, DYNAMIC_VERTICES, INSTANCES, STATIC_IDS, STATIC_VERTICES, WIDE_NODES,
};
use crate::accel::flat::{FlatDynamic, FlatStatic, FlatTriangles};
use crate::accel::World;

/// Deepest static wide tree the shader's stack holds (`WIDE_STACK` = 96
/// entries, seven a level plus one).
const WIDE_DEPTH_LIMIT: usize = 13;
/// Deepest binary tree the shader's stacks hold (`BINARY_STACK`).
const BINARY_DEPTH_LIMIT: usize = 64;

/// The parameters every pass reads (binding 0); `common.wgsl`'s `Params`.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, Pod, Zeroable)]
pub struct Params {
    /// Rays or points in the batch.
    pub item_count: u32,
    pub static_node_count: u32,
    pub top_node_offset: u32,
    pub top_node_count: u32,
    pub top_members_offset: u32,
    pub binary_scale: f32,
    pub inv_limit: f32,
    /// Lights of the direct-light pass.
    pub light_count: u32,
    /// Light layers of the `light` AOV's passes (0 elsewhere).
    pub layer_count: u32,
}

struct StaticBuffers {
    nodes: wgpu::Buffer,
    vertices: wgpu::Buffer,
    ids: wgpu::Buffer,
    node_count: u32,
}

struct DynamicBuffers {
    nodes: wgpu::Buffer,
    vertices: wgpu::Buffer,
    ids: wgpu::Buffer,
    instances: wgpu::Buffer,
    top_offset: u32,
    top_count: u32,
    top_members_offset: u32,
}

/// One world's buffers, and which world and revision they hold.
pub struct GpuScene {
    world: u64,
    revision: u64,
    static_part: StaticBuffers,
    dynamic_part: DynamicBuffers,
}

impl GpuScene {
    pub fn upload(context: &GpuContext, world: &World) -> Result<GpuScene, GpuError> {
        context.checked("uploading the scene", || {
            Ok(GpuScene {
                world: world.id(),
                revision: world.dynamic_revision(),
                static_part: upload_static(context, &world.flat_static())?,
                dynamic_part: upload_dynamic(context, &world.flat_dynamic())?,
            })
        })
    }

    /// Brings the buffers up to `world`: everything for another world, the
    /// dynamic part for a newer revision of this one, else nothing.
    pub fn update(&mut self, context: &GpuContext, world: &World) -> Result<(), GpuError> {
        if world.id() != self.world {
            *self = GpuScene::upload(context, world)?;
        } else if world.dynamic_revision() != self.revision {
            self.dynamic_part = context.checked("uploading the moved objects", || {
                upload_dynamic(context, &world.flat_dynamic())
            })?;
            self.revision = world.dynamic_revision();
        }
        Ok(())
    }

    /// The parameters for a batch of `item_count` items and `light_count`
    /// lights over this scene.
    pub fn params(&self, item_count: u32, light_count: u32, layer_count: u32) -> Params {
        Params {
            item_count,
            static_node_count: self.static_part.node_count,
            top_node_offset: self.dynamic_part.top_offset,
            top_node_count: self.dynamic_part.top_count,
            top_members_offset: self.dynamic_part.top_members_offset,
            binary_scale: crate::accel::node_test::BINARY_SCALE,
            inv_limit: crate::accel::node_test::INV_LIMIT,
            light_count,
            layer_count,
        }
    }

    /// The bindings of `scene.wgsl`'s arrays.
    pub const BINDINGS: [u32; 7] = [
        WIDE_NODES,
        BINARY_NODES,
        STATIC_VERTICES,
        STATIC_IDS,
        INSTANCES,
        DYNAMIC_VERTICES,
        DYNAMIC_IDS,
    ];

    /// The world's buffers at their [`GpuScene::BINDINGS`].
    pub fn buffers(&self) -> [(u32, &wgpu::Buffer); 7] {
        let (s, d) = (&self.static_part, &self.dynamic_part);
        [
            (WIDE_NODES, &s.nodes),
            (BINARY_NODES, &d.nodes),
            (STATIC_VERTICES, &s.vertices),
            (STATIC_IDS, &s.ids),
            (INSTANCES, &d.instances),
            (DYNAMIC_VERTICES, &d.vertices),
            (DYNAMIC_IDS, &d.ids),
        ]
    }
}

/// Fails when a tree is deeper than the shader's stack for it holds.
fn check_depth(what: &'static str, depth: usize, limit: usize) -> Result<(), GpuError> {
    if depth > limit {
        return Err(GpuError::TooDeep { what, depth, limit });
    }
    Ok(())
}

fn upload_static(context: &GpuContext, flat: &FlatStatic) -> Result<StaticBuffers, GpuError> {
    check_depth("the static BVH", flat.depth, WIDE_DEPTH_LIMIT)?;
    Ok(StaticBuffers {
        nodes: storage(context, "static BVH nodes", &flat.nodes)?,
        vertices: storage(context, "static triangles", &flat.triangles.vertices)?,
        ids: storage(context, "static triangle ids", &flat.triangles.sources)?,
        node_count: flat.nodes.len() as u32,
    })
}

fn upload_dynamic(context: &GpuContext, flat: &FlatDynamic) -> Result<DynamicBuffers, GpuError> {
    check_depth("a dynamic object's BVH", flat.depth, BINARY_DEPTH_LIMIT)?;
    let FlatTriangles { vertices, sources } = &flat.triangles;
    let mut ids: Vec<u32> = bytemuck::cast_slice(sources).to_vec();
    let top_members_offset = ids.len() as u32;
    ids.extend(&flat.top_members);
    Ok(DynamicBuffers {
        nodes: storage(context, "dynamic BVH nodes", &flat.nodes)?,
        vertices: storage(context, "dynamic triangles", vertices)?,
        ids: storage(context, "dynamic triangle ids", &ids)?,
        instances: storage(context, "dynamic instances", &flat.instances)?,
        top_offset: flat.top_offset,
        top_count: flat.top_count,
        top_members_offset,
    })
}

/// A read-only storage buffer holding `items`; one zeroed item when there
/// are none, since a binding cannot be empty.
pub fn storage<T: Pod>(
    context: &GpuContext,
    what: &'static str,
    items: &[T],
) -> Result<wgpu::Buffer, GpuError> {
    let zero = [T::zeroed()];
    let items = if items.is_empty() { &zero[..] } else { items };
    let contents: &[u8] = bytemuck::cast_slice(items);
    context.check_binding(what, contents.len() as u64)?;
    Ok(context.upload(what, contents, wgpu::BufferUsages::STORAGE))
}
