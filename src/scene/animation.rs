//! Animation clips as plain data: which property of which node, light,
//! camera or material a channel drives, and the keyframes of its sampler.
//! Import fills these from a file's `animations`, the authoring builder
//! writes them, and [`crate::anim`] samples them into a
//! [`super::pose::Pose`].

/// One glTF animation: channels that play together on one timeline.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct AnimationClip {
    pub name: Option<String>,
    pub channels: Vec<Channel>,
}

/// A sampler driving one property.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    pub target: Target,
    pub sampler: Sampler,
}

/// A quaternion shorter than this is no rotation at all (glTF's are unit
/// length; sampling normalises what exporters round a few ULPs off).
const SHORTEST_ROTATION: f32 = 1e-6;

impl Channel {
    /// Checks the sampler ([`Sampler::validate`]) and what the target asks
    /// of its values: a rotation's keys are quaternions that can be
    /// normalised. (CUBICSPLINE tangents may be zero: they are not keys.)
    pub fn validate(&self) -> Result<(), String> {
        self.sampler.validate()?;
        if !matches!(self.target, Target::Rotation(_)) {
            return Ok(());
        }
        let sampler = &self.sampler;
        let per_key = sampler.elements_per_key();
        // The key's value is the middle element of a CUBICSPLINE triple.
        let value = per_key / 2;
        let keys = sampler.values.chunks_exact(per_key * sampler.width);
        for (key, elements) in keys.enumerate() {
            let quaternion = &elements[value * sampler.width..][..sampler.width];
            let length = quaternion.iter().map(|c| c * c).sum::<f32>().sqrt();
            if length < SHORTEST_ROTATION {
                return Err(format!(
                    "output key {key} is the rotation {quaternion:?}, of length {length}; \
                     rotations must be unit quaternions"
                ));
            }
        }
        Ok(())
    }
}

/// What a channel drives. Node properties come from a channel's
/// `target.node` and `path` (or a KHR_animation_pointer to a node); light,
/// camera and material properties only from KHR_animation_pointer. Each
/// variant holds the index of the node, light, camera or material in the
/// scene's arrays.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Target {
    /// The node's translation (3 components).
    Translation(usize),
    /// The node's rotation, a quaternion (x, y, z, w).
    Rotation(usize),
    /// The node's scale (3 components).
    Scale(usize),
    /// The morph weights of the node's mesh (one per morph target).
    Weights(usize),
    /// A property of a KHR_lights_punctual light.
    Light(usize, LightProperty),
    /// A property of a camera's projection.
    Camera(usize, CameraProperty),
    /// A factor of a material.
    Material(usize, MaterialProperty),
}

impl Target {
    /// The kind of object the channel animates, and its index.
    pub fn object(self) -> (TargetKind, usize) {
        match self {
            Target::Translation(node)
            | Target::Rotation(node)
            | Target::Scale(node)
            | Target::Weights(node) => (TargetKind::Node, node),
            Target::Light(light, _) => (TargetKind::Light, light),
            Target::Camera(camera, _) => (TargetKind::Camera, camera),
            Target::Material(material, _) => (TargetKind::Material, material),
        }
    }

    /// The node whose property the channel drives; None for lights,
    /// cameras and materials, which move nothing.
    pub fn node(self) -> Option<usize> {
        match self.object() {
            (TargetKind::Node, node) => Some(node),
            _ => None,
        }
    }

    /// The node whose placement the channel moves (its translation,
    /// rotation or scale: it and its subtree move); None for morph
    /// weights, which deform a mesh in place, and for lights, cameras and
    /// materials.
    pub fn placed_node(self) -> Option<usize> {
        match self {
            Target::Translation(node) | Target::Rotation(node) | Target::Scale(node) => Some(node),
            _ => None,
        }
    }

    /// Components per value. Morph weights have one per morph target of
    /// the node's mesh, which `morph_targets(node)` tells.
    pub fn width(self, morph_targets: impl FnOnce(usize) -> usize) -> usize {
        match self {
            Target::Translation(_) | Target::Scale(_) => 3,
            Target::Rotation(_) => 4,
            Target::Weights(node) => morph_targets(node),
            Target::Light(_, property) => property.width(),
            Target::Camera(_, property) => property.width(),
            Target::Material(_, property) => property.width(),
        }
    }
}

/// The kinds of object a channel can animate.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum TargetKind {
    Node,
    Light,
    Camera,
    Material,
}

impl TargetKind {
    /// The word messages use: "node", "light", "camera", "material".
    pub fn name(self) -> &'static str {
        match self {
            TargetKind::Node => "node",
            TargetKind::Light => "light",
            TargetKind::Camera => "camera",
            TargetKind::Material => "material",
        }
    }
}

/// The animatable properties of a light (KHR_lights_punctual).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LightProperty {
    /// Linear RGB colour (3 components).
    Color,
    Intensity,
    Range,
    /// A spot light's cone angles, in radians.
    InnerConeAngle,
    OuterConeAngle,
}

impl LightProperty {
    pub const ALL: [LightProperty; 5] = [
        LightProperty::Color,
        LightProperty::Intensity,
        LightProperty::Range,
        LightProperty::InnerConeAngle,
        LightProperty::OuterConeAngle,
    ];

    pub fn width(self) -> usize {
        match self {
            LightProperty::Color => 3,
            _ => 1,
        }
    }
}

/// The animatable properties of a camera: those the render camera uses.
/// (A perspective camera's `znear` and `aspectRatio` play no part in
/// rendering, so animating them would change nothing.)
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CameraProperty {
    /// A perspective camera's vertical field of view, in radians.
    Yfov,
    /// A perspective camera's far plane, in metres.
    Zfar,
}

impl CameraProperty {
    pub const ALL: [CameraProperty; 2] = [CameraProperty::Yfov, CameraProperty::Zfar];

    pub fn width(self) -> usize {
        1
    }
}

/// The animatable factors of a material: those [`super::Material`] has.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum MaterialProperty {
    /// Linear RGBA (4 components).
    BaseColor,
    Metallic,
    Roughness,
    /// Linear RGB (3 components).
    Emissive,
    /// KHR_materials_transmission.
    Transmission,
    /// KHR_materials_ior.
    Ior,
    /// KHR_materials_specular.
    Specular,
}

impl MaterialProperty {
    pub const ALL: [MaterialProperty; 7] = [
        MaterialProperty::BaseColor,
        MaterialProperty::Metallic,
        MaterialProperty::Roughness,
        MaterialProperty::Emissive,
        MaterialProperty::Transmission,
        MaterialProperty::Ior,
        MaterialProperty::Specular,
    ];

    pub fn width(self) -> usize {
        match self {
            MaterialProperty::BaseColor => 4,
            MaterialProperty::Emissive => 3,
            _ => 1,
        }
    }
}

/// How values between two keys are found (glTF `interpolation`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Interpolation {
    /// The earlier key's value holds until the next key.
    Step,
    /// Straight lines; rotations by spherical interpolation on the
    /// shorter arc.
    #[default]
    Linear,
    /// Cubic Hermite spline with per-key in- and out-tangents.
    CubicSpline,
}

/// Keyframes: times in seconds and the values at them.
#[derive(Clone, Debug, PartialEq)]
pub struct Sampler {
    pub interpolation: Interpolation,
    /// Key times, finite and strictly increasing (at least one).
    pub times: Vec<f32>,
    /// `width` components per element, one element per key — or, for
    /// CUBICSPLINE, three per key: in-tangent, value, out-tangent.
    pub values: Vec<f32>,
    /// Components per element: [`Target::width`], or the number of morph
    /// targets (weights).
    pub width: usize,
}

impl Sampler {
    /// Elements stored per key.
    pub fn elements_per_key(&self) -> usize {
        match self.interpolation {
            Interpolation::CubicSpline => 3,
            Interpolation::Step | Interpolation::Linear => 1,
        }
    }

    /// The time of the last key: where the sampler comes to rest.
    pub fn end(&self) -> f32 {
        self.times.last().copied().unwrap_or(0.0)
    }

    /// Checks what sampling relies on: keys exist, times are finite,
    /// non-negative (glTF's timeline starts at 0) and strictly increasing, values are finite and there are as many as the
    /// keys, width and interpolation call for. Import and the authoring
    /// builder both check with this, so what one writes the other reads.
    pub fn validate(&self) -> Result<(), String> {
        if self.times.is_empty() {
            return Err("has no keyframe times".into());
        }
        if self.width == 0 {
            return Err("has values of width 0".into());
        }
        if let Some(key) = self.times.iter().position(|time| !time.is_finite()) {
            return Err(format!("key time {key} is not finite"));
        }
        if let Some(key) = self.times.iter().position(|&time| time < 0.0) {
            return Err(format!(
                "input key {key} is at {} s; animation times must not be negative",
                self.times[key]
            ));
        }
        if let Some(key) = self.times.windows(2).position(|pair| pair[0] >= pair[1]) {
            return Err(format!(
                "key times are not strictly increasing: key {} at {} s, key {} at {} s",
                key,
                self.times[key],
                key + 1,
                self.times[key + 1]
            ));
        }
        let expected = self.times.len() * self.elements_per_key() * self.width;
        if self.values.len() != expected {
            let cubic = if self.interpolation == Interpolation::CubicSpline {
                " (CUBICSPLINE stores 3 elements per key)"
            } else {
                ""
            };
            return Err(format!(
                "has {} output values for {} keys of width {}; expected {expected}{cubic}",
                self.values.len(),
                self.times.len(),
                self.width
            ));
        }
        if let Some(at) = self.values.iter().position(|value| !value.is_finite()) {
            return Err(format!("output value {at} is not finite"));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sampler(interpolation: Interpolation, times: &[f32], values: &[f32]) -> Sampler {
        Sampler {
            interpolation,
            times: times.to_vec(),
            values: values.to_vec(),
            width: 1,
        }
    }

    #[test]
    fn validation_names_the_fault() {
        let ok = sampler(Interpolation::Linear, &[0.0, 1.0], &[0.0, 1.0]);
        assert_eq!(ok.validate(), Ok(()));
        let cases = [
            (sampler(Interpolation::Linear, &[], &[]), "no keyframe"),
            (
                sampler(Interpolation::Step, &[0.0, 0.0], &[1.0, 2.0]),
                "strictly increasing",
            ),
            (
                sampler(Interpolation::Linear, &[f32::NAN], &[1.0]),
                "not finite",
            ),
            (
                sampler(Interpolation::CubicSpline, &[0.0, 1.0], &[0.0, 1.0]),
                "CUBICSPLINE",
            ),
            (
                sampler(Interpolation::Linear, &[0.0], &[f32::INFINITY]),
                "output value 0",
            ),
            (
                sampler(Interpolation::Linear, &[-1.0, 1.0], &[0.0, 1.0]),
                "input key 0 is at -1 s; animation times must not be negative",
            ),
        ];
        for (sampler, word) in cases {
            let message = sampler.validate().expect_err(word);
            assert!(message.contains(word), "{message}");
        }
    }

    fn rotation(interpolation: Interpolation, values: &[f32]) -> Channel {
        let keys = values.len()
            / 4
            / if interpolation == Interpolation::CubicSpline {
                3
            } else {
                1
            };
        Channel {
            target: Target::Rotation(0),
            sampler: Sampler {
                interpolation,
                times: (0..keys).map(|key| key as f32).collect(),
                values: values.to_vec(),
                width: 4,
            },
        }
    }

    #[test]
    fn a_zero_rotation_key_is_refused_but_zero_tangents_are_not() {
        let identity = [0.0, 0.0, 0.0, 1.0];
        let zero = [0.0; 4];
        let linear = rotation(Interpolation::Linear, &[identity, zero].concat());
        let message = linear.validate().expect_err("zero key");
        assert!(
            message.starts_with("output key 1 is the rotation [0.0, 0.0, 0.0, 0.0]"),
            "{message}"
        );
        let cubic = rotation(Interpolation::CubicSpline, &[zero, identity, zero].concat());
        assert_eq!(cubic.validate(), Ok(()));
        let cubic_zero = rotation(
            Interpolation::CubicSpline,
            &[identity, zero, identity].concat(),
        );
        assert!(cubic_zero.validate().is_err());
        // Only rotations are quaternions: zeros elsewhere are values.
        let translation = Channel {
            target: Target::Translation(0),
            sampler: Sampler {
                interpolation: Interpolation::Linear,
                times: vec![0.0, 1.0],
                values: vec![0.0; 6],
                width: 3,
            },
        };
        assert_eq!(translation.validate(), Ok(()));
    }
}
