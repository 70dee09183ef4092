//! KHR_animation_pointer channels as the file writes them. The glTF crate
//! requires every channel to name a node, so `container.rs` takes these out
//! of the raw JSON before the crate parses it; what the JSON alone can tell
//! (a sampler of their own animation, a pointer string) is checked here.
//! Their samplers stay in the document, so the crate validates the
//! samplers' accessors, and `animation.rs` reads them like any other.

use serde_json::Value;

use super::error::Fault;
use crate::scene::{pointer, LightKind, LightProperty, Projection, Target, TargetKind};

use super::animation::Animatable;

/// One KHR_animation_pointer channel.
#[derive(Clone, Debug, PartialEq)]
pub struct PointerChannel {
    /// Its index in its animation's `channels`, as the file counts them.
    pub channel: usize,
    /// Index into its animation's `samplers`, checked.
    pub sampler: usize,
    /// The JSON pointer to the animated property.
    pub pointer: String,
}

/// The pointer channels of every animation, in file order.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct PointerChannels {
    by_animation: Vec<Vec<PointerChannel>>,
}

impl PointerChannels {
    /// Takes every channel whose `target.path` is `"pointer"` out of the
    /// raw document's animations.
    pub fn take(document: &mut Value) -> Result<PointerChannels, Fault> {
        let Some(animations) = document.get_mut("animations").and_then(Value::as_array_mut) else {
            return Ok(PointerChannels::default());
        };
        let by_animation = animations
            .iter_mut()
            .enumerate()
            .map(|(index, animation)| take_from(index, animation))
            .collect::<Result<_, _>>()?;
        Ok(PointerChannels { by_animation })
    }

    /// Animation `animation`'s pointer channels, by channel index.
    pub fn of(&self, animation: usize) -> &[PointerChannel] {
        self.by_animation.get(animation).map_or(&[], Vec::as_slice)
    }

    pub fn is_empty(&self) -> bool {
        self.by_animation.iter().all(Vec::is_empty)
    }
}

/// The pointer channels of one raw animation, removed from it.
fn take_from(index: usize, animation: &mut Value) -> Result<Vec<PointerChannel>, Fault> {
    let samplers = animation
        .get("samplers")
        .and_then(Value::as_array)
        .map_or(0, Vec::len);
    let Some(channels) = animation.get_mut("channels").and_then(Value::as_array_mut) else {
        return Ok(Vec::new());
    };
    let mut taken = Vec::new();
    for (channel, raw) in channels.iter().enumerate() {
        if raw.pointer("/target/path").and_then(Value::as_str) != Some("pointer") {
            continue;
        }
        let fault = |problem: String| Fault::Animation {
            animation: index,
            channel,
            problem,
        };
        let sampler = match raw.get("sampler").and_then(Value::as_u64) {
            Some(sampler) if sampler < samplers as u64 => sampler as usize,
            Some(sampler) => {
                return Err(fault(format!(
                    "names sampler {sampler}, but the animation has {samplers}"
                )))
            }
            None => return Err(fault("has no sampler index".into())),
        };
        let pointer = raw
            .pointer("/target/extensions/KHR_animation_pointer/pointer")
            .and_then(Value::as_str)
            .ok_or_else(|| {
                fault("has path \"pointer\" but no KHR_animation_pointer pointer string".into())
            })?;
        taken.push(PointerChannel {
            channel,
            sampler,
            pointer: pointer.to_owned(),
        });
    }
    let mut channel = 0;
    channels.retain(|_| {
        let keep = taken.iter().all(|taken| taken.channel != channel);
        channel += 1;
        keep
    });
    Ok(taken)
}

impl PointerChannel {
    /// The target the pointer names in `scene`, or why the channel is
    /// skipped: a property lmanim does not animate, an index the file does
    /// not have, or a property the named object lacks.
    pub fn target(&self, scene: &Animatable) -> Result<Target, String> {
        let target = pointer::parse(&self.pointer)
            .ok_or_else(|| "names a property lmanim does not animate".to_owned())?;
        let (kind, index) = target.object();
        let count = match kind {
            TargetKind::Node => scene.nodes.len(),
            TargetKind::Light => scene.lights.len(),
            TargetKind::Camera => scene.cameras.len(),
            TargetKind::Material => scene.materials,
        };
        if index >= count {
            let plural = if count == 1 { "" } else { "s" };
            let kind = kind.name();
            return Err(format!(
                "names {kind} {index}, but the file has {count} {kind}{plural}"
            ));
        }
        // Indexing is safe: the index was checked against the count.
        match target {
            Target::Light(light, LightProperty::InnerConeAngle | LightProperty::OuterConeAngle)
                if !matches!(scene.lights[light].kind, LightKind::Spot { .. }) =>
            {
                Err(format!(
                    "names a cone angle of light {light}, not a spot light"
                ))
            }
            Target::Camera(camera, _)
                if matches!(
                    scene.cameras[camera].projection,
                    Projection::Orthographic { .. }
                ) =>
            {
                Err(format!(
                    "names a perspective property of camera {camera}, an orthographic one"
                ))
            }
            _ => Ok(target),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::scene::{Camera, CameraProperty};
    use serde_json::json;

    #[test]
    fn targets_must_exist_and_fit_their_object() {
        let camera = |projection| Camera {
            name: None,
            projection,
        };
        let cameras = [
            camera(Projection::Perspective {
                yfov: 1.0,
                aspect_ratio: None,
                znear: 0.1,
                zfar: None,
            }),
            camera(Projection::Orthographic {
                xmag: 1.0,
                ymag: 1.0,
                znear: 0.0,
                zfar: 10.0,
            }),
        ];
        let scene = Animatable {
            nodes: &[],
            meshes: &[],
            lights: &[],
            cameras: &cameras,
            materials: 1,
        };
        let target = |pointer: &str| {
            PointerChannel {
                channel: 0,
                sampler: 0,
                pointer: pointer.into(),
            }
            .target(&scene)
        };
        assert_eq!(
            target("/cameras/0/perspective/yfov"),
            Ok(Target::Camera(0, CameraProperty::Yfov))
        );
        let cases = [
            (
                "/cameras/1/perspective/yfov",
                "camera 1, an orthographic one",
            ),
            (
                "/cameras/2/perspective/zfar",
                "camera 2, but the file has 2 cameras",
            ),
            (
                "/materials/1/emissiveFactor",
                "material 1, but the file has 1 material",
            ),
            ("/nodes/0/rotation", "node 0, but the file has 0 nodes"),
            ("/materials/0/alphaCutoff", "does not animate"),
        ];
        for (pointer, words) in cases {
            let reason = target(pointer).expect_err(pointer);
            assert!(reason.contains(words), "{pointer}: {reason}");
        }
    }

    #[test]
    fn pointer_channels_are_taken_and_the_rest_kept_in_order() {
        let pointer = |path: &str| {
            json!({ "sampler": 1, "target": { "path": "pointer",
                "extensions": { "KHR_animation_pointer": { "pointer": path } } } })
        };
        let node = json!({ "sampler": 0, "target": { "node": 0, "path": "scale" } });
        let mut document = json!({ "animations": [
            { "samplers": [{}, {}], "channels": [
                pointer("/materials/0/emissiveFactor"), node.clone(), pointer("/cameras/0/perspective/yfov")
            ] },
            { "samplers": [{}], "channels": [node.clone()] },
        ] });
        let taken = PointerChannels::take(&mut document).expect("well formed");
        assert_eq!(
            taken.of(0),
            &[
                PointerChannel {
                    channel: 0,
                    sampler: 1,
                    pointer: "/materials/0/emissiveFactor".into()
                },
                PointerChannel {
                    channel: 2,
                    sampler: 1,
                    pointer: "/cameras/0/perspective/yfov".into()
                },
            ]
        );
        assert!(taken.of(1).is_empty() && taken.of(7).is_empty());
        assert_eq!(document["animations"][0]["channels"], json!([node]));
        assert_eq!(document["animations"][1]["channels"], json!([node]));
    }

    #[test]
    fn a_pointer_channel_needs_a_sampler_of_its_animation_and_a_pointer() {
        let cases = [
            (
                json!({ "sampler": 2, "target": { "path": "pointer",
                "extensions": { "KHR_animation_pointer": { "pointer": "/x" } } } }),
                "names sampler 2, but the animation has 1",
            ),
            (
                json!({ "target": { "path": "pointer" } }),
                "no sampler index",
            ),
            (
                json!({ "sampler": 0, "target": { "path": "pointer" } }),
                "no KHR_animation_pointer",
            ),
        ];
        for (channel, word) in cases {
            let mut document =
                json!({ "animations": [{ "samplers": [{}], "channels": [channel] }] });
            let message = PointerChannels::take(&mut document)
                .expect_err(word)
                .to_string();
            assert!(
                message.contains("animation 0 channel 0") && message.contains(word),
                "{message}"
            );
        }
    }
}
