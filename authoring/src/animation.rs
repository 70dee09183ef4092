//! The animated parts of a [`GltfBuilder`] scene: skins, default morph
//! weights of meshes and animation clips. They are given as the scene
//! model's types, checked as import checks them (samplers by
//! [`Sampler::validate`]), so that a written file imports as written.
//! Channels of lights, cameras and materials are written as
//! KHR_animation_pointer channels.

use serde_json::{json, Value};

use lmanim::scene::{pointer, AnimationClip, Interpolation, Sampler, Skin, Target, TargetKind};

use super::json::ANIMATION_POINTER;
use super::{AuthoringError, GltfBuilder, MeshId, SkinId};

impl GltfBuilder {
    /// A skin; its joints (and skeleton) are nodes of this builder, by
    /// index. One inverse bind matrix per joint.
    pub fn add_skin(&mut self, skin: &Skin) -> Result<SkinId, AuthoringError> {
        let fault = |fault: String| AuthoringError::Skin {
            name: skin
                .name
                .clone()
                .unwrap_or_else(|| format!("#{}", self.skins.len())),
            fault,
        };
        if skin.joints.is_empty() || skin.inverse_bind.len() != skin.joints.len() {
            return Err(fault(
                "needs joints and one inverse bind matrix per joint".into(),
            ));
        }
        let nodes = self.nodes.len();
        if let Some(node) = skin
            .joints
            .iter()
            .chain(&skin.skeleton)
            .find(|&&node| node >= nodes)
        {
            return Err(fault(format!("node #{node} is not in this builder")));
        }
        let matrices: Vec<f32> = skin
            .inverse_bind
            .iter()
            .flat_map(|matrix| matrix.as_mat4().to_cols_array())
            .collect();
        if !matrices.iter().all(|v| v.is_finite()) {
            return Err(fault("inverse bind matrices must be finite".into()));
        }
        let accessor = self.add_floats(&matrices, 16, None, false);
        // add_floats names widths up to VEC4; 16 floats per element are MAT4.
        self.accessors[accessor]["type"] = json!("MAT4");
        let mut object = json!({ "joints": skin.joints, "inverseBindMatrices": accessor });
        if let Some(name) = &skin.name {
            object["name"] = json!(name);
        }
        if let Some(skeleton) = skin.skeleton {
            object["skeleton"] = json!(skeleton);
        }
        self.skins.push(object);
        Ok(SkinId(self.skins.len() - 1))
    }

    /// The default morph weights of a mesh, one per morph target.
    pub fn set_mesh_weights(
        &mut self,
        mesh: MeshId,
        weights: &[f32],
    ) -> Result<(), AuthoringError> {
        let targets = self.morph_targets_of(mesh);
        let Some(object) = self.meshes.get_mut(mesh.0) else {
            return Err(AuthoringError::Mesh {
                name: format!("#{}", mesh.0),
                fault: "is not in this builder".into(),
            });
        };
        if weights.len() != targets || !weights.iter().all(|w| w.is_finite()) {
            return Err(AuthoringError::Mesh {
                name: object["name"].as_str().unwrap_or_default().to_owned(),
                fault: format!("{} weights for {targets} morph targets", weights.len()),
            });
        }
        object["weights"] = json!(weights);
        Ok(())
    }

    /// An animation clip; each channel gets a sampler of its own. Target
    /// nodes, lights, cameras and materials must exist already; a weights
    /// channel's width must match the node's mesh's morph targets.
    pub fn add_animation(&mut self, clip: &AnimationClip) -> Result<usize, AuthoringError> {
        let name = clip
            .name
            .clone()
            .unwrap_or_else(|| format!("#{}", self.animations.len()));
        let fault = |fault: String| AuthoringError::Animation {
            name: name.clone(),
            fault,
        };
        if clip.channels.is_empty() {
            return Err(fault("needs at least one channel".into()));
        }
        for (index, channel) in clip.channels.iter().enumerate() {
            let (kind, object) = channel.target.object();
            let count = match kind {
                TargetKind::Node => self.nodes.len(),
                TargetKind::Light => self.lights.len(),
                TargetKind::Camera => self.cameras.len(),
                TargetKind::Material => self.materials.len(),
            };
            if object >= count {
                return Err(fault(format!(
                    "channel {index}: {} #{object} is not in this builder",
                    kind.name()
                )));
            }
            let width = channel.target.width(|node| {
                self.nodes[node]["mesh"]
                    .as_u64()
                    .map_or(0, |mesh| self.morph_targets_of(MeshId(mesh as usize)))
            });
            if channel.sampler.width != width || width == 0 {
                return Err(fault(format!(
                    "channel {index}: values of width {} where the target takes {width}",
                    channel.sampler.width
                )));
            }
            channel
                .validate()
                .map_err(|problem| fault(format!("channel {index}: sampler {problem}")))?;
        }
        let mut samplers = Vec::new();
        let mut channels = Vec::new();
        for channel in &clip.channels {
            samplers.push(self.add_sampler(&channel.sampler, channel.target));
            let target = match channel.target.node() {
                Some(node) => json!({ "node": node, "path": pointer::property(channel.target) }),
                None => {
                    self.extensions_used.insert(ANIMATION_POINTER);
                    json!({ "path": "pointer", "extensions": { ANIMATION_POINTER: {
                        "pointer": pointer::pointer(channel.target) } } })
                }
            };
            channels.push(json!({ "sampler": channels.len(), "target": target }));
        }
        let mut object = json!({ "channels": channels, "samplers": samplers });
        if let Some(name) = &clip.name {
            object["name"] = json!(name);
        }
        self.animations.push(object);
        Ok(self.animations.len() - 1)
    }

    /// Input (with the min/max the spec requires) and output accessors of
    /// a checked sampler. Weights are written as SCALARs, as glTF has them.
    fn add_sampler(&mut self, sampler: &Sampler, target: Target) -> Value {
        let input = self.add_floats(&sampler.times, 1, None, true);
        let output_width = match target {
            Target::Weights(_) => 1,
            _ => sampler.width,
        };
        let output = self.add_floats(&sampler.values, output_width, None, false);
        let interpolation = match sampler.interpolation {
            Interpolation::Step => "STEP",
            Interpolation::Linear => "LINEAR",
            Interpolation::CubicSpline => "CUBICSPLINE",
        };
        json!({ "input": input, "output": output, "interpolation": interpolation })
    }

    /// How many morph targets the mesh's primitives have (0 for a mesh
    /// this builder lacks).
    pub(super) fn morph_targets_of(&self, mesh: MeshId) -> usize {
        self.meshes
            .get(mesh.0)
            .and_then(|mesh| mesh["primitives"][0]["targets"].as_array())
            .map_or(0, Vec::len)
    }
}
