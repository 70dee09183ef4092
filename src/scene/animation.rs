//! Animation clips as plain data: which property of which node a channel
//! drives, and the keyframes of its sampler. Import fills these from a
//! file's `animations`, the authoring builder writes them, and
//! [`crate::anim`] samples them into a [`super::pose::Pose`].

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

/// What a channel drives; each variant holds the node index.
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
}

impl Target {
    /// The node whose property the channel drives.
    pub fn node(self) -> usize {
        match self {
            Target::Translation(node)
            | Target::Rotation(node)
            | Target::Scale(node)
            | Target::Weights(node) => node,
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
    /// Components per element: 3 (translation, scale), 4 (rotation), or
    /// the number of morph targets (weights).
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

    /// Checks what sampling relies on: keys exist, times are finite and
    /// strictly increasing, values are finite and there are as many as the
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
        ];
        for (sampler, word) in cases {
            let message = sampler.validate().expect_err(word);
            assert!(message.contains(word), "{message}");
        }
    }
}
