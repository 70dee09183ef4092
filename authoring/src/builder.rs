//! [`GltfBuilder`]: collects the parts of one glTF scene and their binary
//! data. Every `add_*` checks its input, so what [`GltfBuilder`] writes is
//! valid glTF or nothing.

use std::collections::BTreeSet;

use serde_json::{json, Map, Value};

use lmanim::scene::{Camera, Light, Material};

use super::{
    json, AuthoringError, CameraId, Geometry, GeometryId, LightId, MaterialId, MeshId, NodeDesc,
    NodeId, Primitive,
};

/// glTF `componentType` codes.
const FLOAT: u32 = 5126;
const UNSIGNED_INT: u32 = 5125;
const UNSIGNED_SHORT: u32 = 5123;
/// glTF buffer-view `target` codes.
const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;

/// Builds one glTF scene in memory; see the module docs of
/// [the crate](crate). Add parts bottom-up (geometry, then meshes, then
/// nodes, children before parents); nodes nobody lists as a child become
/// the scene's roots.
#[derive(Clone, Debug, Default)]
pub struct GltfBuilder {
    /// The one binary buffer, every view aligned to 4 bytes.
    pub(super) buffer: Vec<u8>,
    pub(super) buffer_views: Vec<Value>,
    pub(super) accessors: Vec<Value>,
    /// Accessor objects of each geometry's attributes and indices.
    geometries: Vec<Value>,
    pub(super) meshes: Vec<Value>,
    pub(super) materials: Vec<Value>,
    pub(super) nodes: Vec<Value>,
    /// Whether each node already has a parent (a tree allows one).
    has_parent: Vec<bool>,
    pub(super) lights: Vec<Value>,
    pub(super) cameras: Vec<Value>,
    pub(super) skins: Vec<Value>,
    pub(super) animations: Vec<Value>,
    pub(super) extensions_used: BTreeSet<&'static str>,
}

impl GltfBuilder {
    pub fn new() -> GltfBuilder {
        GltfBuilder::default()
    }

    /// Stores a geometry's attributes and indices; several meshes may use
    /// it with different materials. POSITION gets the min/max the glTF
    /// spec requires.
    pub fn add_geometry(&mut self, geometry: &Geometry) -> Result<GeometryId, AuthoringError> {
        let index = self.geometries.len();
        check_geometry(geometry).map_err(|fault| AuthoringError::Geometry { index, fault })?;
        let positions: Vec<f32> = geometry
            .positions
            .iter()
            .flat_map(|p| p.to_array())
            .collect();
        let normals: Vec<f32> = geometry.normals.iter().flat_map(|n| n.to_array()).collect();
        let mut attributes = Map::new();
        attributes.insert(
            "POSITION".into(),
            json!(self.add_floats(&positions, 3, Some(ARRAY_BUFFER), true)),
        );
        attributes.insert(
            "NORMAL".into(),
            json!(self.add_floats(&normals, 3, Some(ARRAY_BUFFER), false)),
        );
        if !geometry.uvs.is_empty() {
            let uvs: Vec<f32> = geometry.uvs.iter().flat_map(|uv| uv.to_array()).collect();
            attributes.insert(
                "TEXCOORD_0".into(),
                json!(self.add_floats(&uvs, 2, Some(ARRAY_BUFFER), false)),
            );
        }
        for (n, set) in geometry.joint_sets.iter().enumerate() {
            let joints: Vec<u16> = set.joints.iter().flatten().copied().collect();
            let weights: Vec<f32> = set.weights.iter().flatten().copied().collect();
            attributes.insert(format!("JOINTS_{n}"), json!(self.add_joints(&joints)));
            attributes.insert(
                format!("WEIGHTS_{n}"),
                json!(self.add_floats(&weights, 4, Some(ARRAY_BUFFER), false)),
            );
        }
        let targets: Vec<Value> = geometry
            .morph_targets
            .iter()
            .map(|target| {
                let positions: Vec<f32> =
                    target.positions.iter().flat_map(|p| p.to_array()).collect();
                let mut object = json!({
                    "POSITION": self.add_floats(&positions, 3, Some(ARRAY_BUFFER), true)
                });
                if !target.normals.is_empty() {
                    let normals: Vec<f32> =
                        target.normals.iter().flat_map(|n| n.to_array()).collect();
                    object["NORMAL"] =
                        json!(self.add_floats(&normals, 3, Some(ARRAY_BUFFER), false));
                }
                object
            })
            .collect();
        let indices = self.add_indices(&geometry.indices);
        let mut primitive = json!({ "attributes": attributes, "indices": indices });
        if !targets.is_empty() {
            primitive["targets"] = json!(targets);
        }
        self.geometries.push(primitive);
        Ok(GeometryId(index))
    }

    /// A mesh of one or more primitives, each a geometry with a material.
    pub fn add_mesh(
        &mut self,
        name: &str,
        primitives: &[Primitive],
    ) -> Result<MeshId, AuthoringError> {
        let fault = |fault: String| AuthoringError::Mesh {
            name: name.to_owned(),
            fault,
        };
        if primitives.is_empty() {
            return Err(fault("a mesh needs at least one primitive".into()));
        }
        let mut objects = Vec::with_capacity(primitives.len());
        for primitive in primitives {
            let Some(geometry) = self.geometries.get(primitive.geometry.0) else {
                return Err(fault(format!(
                    "geometry #{} is not in this builder",
                    primitive.geometry.0
                )));
            };
            let mut object = geometry.clone();
            if let Some(material) = primitive.material {
                if material.0 >= self.materials.len() {
                    return Err(fault(format!(
                        "material #{} is not in this builder",
                        material.0
                    )));
                }
                object["material"] = json!(material.0);
            }
            objects.push(object);
        }
        let targets = |primitive: &Value| primitive["targets"].as_array().map_or(0, Vec::len);
        if objects
            .iter()
            .any(|object| targets(object) != targets(&objects[0]))
        {
            return Err(fault(
                "every primitive of a mesh needs the same number of morph targets".into(),
            ));
        }
        self.meshes
            .push(json!({ "name": name, "primitives": objects }));
        Ok(MeshId(self.meshes.len() - 1))
    }

    /// A metallic-roughness material; transmission and an IOR other than
    /// 1.5 add their extensions. Textures are not supported.
    pub fn add_material(&mut self, material: &Material) -> Result<MaterialId, AuthoringError> {
        let (object, used) =
            json::material(material).map_err(|fault| AuthoringError::Material {
                name: display_name(&material.name, self.materials.len()),
                fault,
            })?;
        self.extensions_used.extend(used);
        self.materials.push(object);
        Ok(MaterialId(self.materials.len() - 1))
    }

    /// A KHR_lights_punctual light; place it with a node.
    pub fn add_light(&mut self, light: &Light) -> Result<LightId, AuthoringError> {
        let object = json::light(light).map_err(|fault| AuthoringError::Light {
            name: display_name(&light.name, self.lights.len()),
            fault,
        })?;
        self.extensions_used.insert(json::LIGHTS_PUNCTUAL);
        self.lights.push(object);
        Ok(LightId(self.lights.len() - 1))
    }

    /// A camera; place it with a node (it looks down the node's −Z).
    pub fn add_camera(&mut self, camera: &Camera) -> Result<CameraId, AuthoringError> {
        let object = json::camera(camera).map_err(|fault| AuthoringError::Camera {
            name: display_name(&camera.name, self.cameras.len()),
            fault,
        })?;
        self.cameras.push(object);
        Ok(CameraId(self.cameras.len() - 1))
    }

    /// A node. Its children must exist already and have no other parent;
    /// its mesh, light and camera must come from this builder.
    pub fn add_node(&mut self, node: NodeDesc) -> Result<NodeId, AuthoringError> {
        let fault = |fault: String| AuthoringError::Node {
            name: display_name(&node.name, self.nodes.len()),
            fault,
        };
        let missing = [
            ("mesh", node.mesh.map(|id| id.0), self.meshes.len()),
            ("light", node.light.map(|id| id.0), self.lights.len()),
            ("camera", node.camera.map(|id| id.0), self.cameras.len()),
            ("skin", node.skin.map(|id| id.0), self.skins.len()),
        ]
        .into_iter()
        .find(|&(_, id, count)| id.is_some_and(|id| id >= count));
        if let Some((kind, Some(id), _)) = missing {
            return Err(fault(format!("{kind} #{id} is not in this builder")));
        }
        let mut children = BTreeSet::new();
        for child in &node.children {
            match self.has_parent.get(child.0) {
                None => return Err(fault(format!("child node #{} does not exist", child.0))),
                Some(true) => {
                    return Err(fault(format!(
                        "child node #{} already has a parent",
                        child.0
                    )))
                }
                Some(false) if !children.insert(child.0) => {
                    return Err(fault(format!("child node #{} is listed twice", child.0)))
                }
                Some(false) => {}
            }
        }
        if let Some(weights) = &node.weights {
            let targets = node.mesh.map_or(0, |mesh| self.morph_targets_of(mesh));
            if weights.len() != targets {
                return Err(fault(format!(
                    "{} morph weights for a mesh with {targets} morph targets",
                    weights.len()
                )));
            }
        }
        let object = json::node(&node).map_err(fault)?;
        for child in children {
            self.has_parent[child] = true;
        }
        self.nodes.push(object);
        self.has_parent.push(false);
        Ok(NodeId(self.nodes.len() - 1))
    }

    /// Nodes without a parent, in the order they were added.
    pub(super) fn roots(&self) -> Vec<usize> {
        (0..self.nodes.len())
            .filter(|&node| !self.has_parent[node])
            .collect()
    }

    /// Appends `values` (`width` floats per element) as a FLOAT accessor;
    /// with `bounds`, the per-component min/max that POSITION and animation
    /// inputs must carry. Returns the accessor index.
    pub(super) fn add_floats(
        &mut self,
        values: &[f32],
        width: usize,
        target: Option<u32>,
        bounds: bool,
    ) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|v| v.to_le_bytes()).collect();
        let view = self.add_view(&bytes, target);
        let count = values.len() / width;
        let kind = match width {
            1 => "SCALAR",
            2 => "VEC2",
            3 => "VEC3",
            _ => "VEC4",
        };
        let mut accessor = json!({
            "bufferView": view,
            "componentType": FLOAT,
            "count": count,
            "type": kind,
        });
        if bounds {
            let mut min = vec![f32::INFINITY; width];
            let mut max = vec![f32::NEG_INFINITY; width];
            for element in values.chunks_exact(width) {
                for (component, &value) in element.iter().enumerate() {
                    min[component] = min[component].min(value);
                    max[component] = max[component].max(value);
                }
            }
            accessor["min"] = json!(min);
            accessor["max"] = json!(max);
        }
        self.accessors.push(accessor);
        self.accessors.len() - 1
    }

    /// Appends joint indices, four per vertex, as a VEC4 UNSIGNED_SHORT
    /// accessor (JOINTS_n).
    fn add_joints(&mut self, joints: &[u16]) -> usize {
        let bytes: Vec<u8> = joints.iter().flat_map(|j| j.to_le_bytes()).collect();
        let view = self.add_view(&bytes, Some(ARRAY_BUFFER));
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": UNSIGNED_SHORT,
            "count": joints.len() / 4,
            "type": "VEC4",
        }));
        self.accessors.len() - 1
    }

    /// Appends triangle indices as an UNSIGNED_INT accessor.
    fn add_indices(&mut self, indices: &[u32]) -> usize {
        let bytes: Vec<u8> = indices.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.add_view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        self.accessors.push(json!({
            "bufferView": view,
            "componentType": UNSIGNED_INT,
            "count": indices.len(),
            "type": "SCALAR",
        }));
        self.accessors.len() - 1
    }

    /// Appends bytes to the buffer at a 4-byte boundary (every component
    /// type must be aligned to its size) and returns the buffer view index.
    fn add_view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        self.buffer.resize(self.buffer.len().next_multiple_of(4), 0);
        let mut view = json!({
            "buffer": 0,
            "byteOffset": self.buffer.len(),
            "byteLength": bytes.len(),
        });
        if let Some(target) = target {
            view["target"] = json!(target);
        }
        self.buffer.extend_from_slice(bytes);
        self.buffer_views.push(view);
        self.buffer_views.len() - 1
    }
}

/// A name for error messages: the item's own, or its future index.
fn display_name(name: &Option<String>, index: usize) -> String {
    name.clone().unwrap_or_else(|| format!("#{index}"))
}

fn check_geometry(geometry: &Geometry) -> Result<(), String> {
    let vertices = geometry.positions.len();
    if vertices == 0 || geometry.indices.is_empty() {
        return Err("a geometry needs positions and indices".into());
    }
    if geometry.normals.len() != vertices {
        return Err(format!(
            "{} normals for {vertices} positions",
            geometry.normals.len()
        ));
    }
    if !geometry.uvs.is_empty() && geometry.uvs.len() != vertices {
        return Err(format!(
            "{} uvs for {vertices} positions",
            geometry.uvs.len()
        ));
    }
    if !geometry.indices.len().is_multiple_of(3) {
        return Err(format!(
            "{} indices do not make whole triangles",
            geometry.indices.len()
        ));
    }
    for (n, set) in geometry.joint_sets.iter().enumerate() {
        if set.joints.len() != vertices || set.weights.len() != vertices {
            return Err(format!(
                "JOINTS_{n}/WEIGHTS_{n} need one element per position"
            ));
        }
        if set
            .weights
            .iter()
            .flatten()
            .any(|w| !w.is_finite() || *w < 0.0)
        {
            return Err(format!("WEIGHTS_{n} must be finite and >= 0"));
        }
    }
    for (t, target) in geometry.morph_targets.iter().enumerate() {
        let normals = target.normals.len();
        if target.positions.len() != vertices || (normals != 0 && normals != vertices) {
            return Err(format!("morph target {t} needs one offset per position"));
        }
        if !target
            .positions
            .iter()
            .chain(&target.normals)
            .all(|v| v.is_finite())
        {
            return Err(format!("morph target {t} offsets must be finite"));
        }
    }
    if let Some(index) = geometry.indices.iter().find(|&&i| i as usize >= vertices) {
        return Err(format!(
            "index {index} is out of range for {vertices} positions"
        ));
    }
    let finite = geometry.positions.iter().all(|p| p.is_finite())
        && geometry.normals.iter().all(|n| n.is_finite())
        && geometry.uvs.iter().all(|uv| uv.is_finite());
    if !finite {
        return Err("positions, normals and uvs must be finite".into());
    }
    Ok(())
}
