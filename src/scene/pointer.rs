//! KHR_animation_pointer paths: the JSON pointer a channel names and the
//! [`Target`] it stands for. One table serves both directions, so what the
//! authoring builder writes is what import reads.

use super::animation::{CameraProperty, LightProperty, MaterialProperty, Target};

const NODES: &str = "/nodes";
const LIGHTS: &str = "/extensions/KHR_lights_punctual/lights";
const CAMERAS: &str = "/cameras";
const MATERIALS: &str = "/materials";

/// The JSON pointer of `target`, e.g.
/// `/extensions/KHR_lights_punctual/lights/0/color`.
pub fn pointer(target: Target) -> String {
    let (collection, index, property) = parts(target);
    format!("{collection}/{index}/{property}")
}

/// The path of `target`'s property inside its object, e.g.
/// `spot/outerConeAngle`. For a node's `translation`, `rotation`, `scale`
/// and `weights` it is also the `path` of a plain glTF channel.
pub fn property(target: Target) -> &'static str {
    parts(target).2
}

/// The target `pointer` names, or None when it names a property lmanim
/// does not animate (or is no pointer to a property at all). Whether the
/// index exists is the caller's question: only it knows the scene.
pub fn parse(pointer: &str) -> Option<Target> {
    [NODES, LIGHTS, CAMERAS, MATERIALS]
        .into_iter()
        .find_map(|collection| {
            let rest = pointer.strip_prefix(collection)?.strip_prefix('/')?;
            let (index, property) = rest.split_once('/')?;
            let index = array_index(index)?;
            targets_of(index).find(|&target| parts(target) == (collection, index, property))
        })
}

/// An array index as JSON pointers write it: decimal digits, no sign and
/// no leading zero (RFC 6901).
fn array_index(text: &str) -> Option<usize> {
    let canonical =
        text.bytes().all(|b| b.is_ascii_digit()) && (text == "0" || !text.starts_with('0'));
    canonical.then(|| text.parse().ok()).flatten()
}

/// Every target with index `index`.
fn targets_of(index: usize) -> impl Iterator<Item = Target> {
    let nodes = [
        Target::Translation(index),
        Target::Rotation(index),
        Target::Scale(index),
        Target::Weights(index),
    ];
    nodes
        .into_iter()
        .chain(LightProperty::ALL.map(|property| Target::Light(index, property)))
        .chain(CameraProperty::ALL.map(|property| Target::Camera(index, property)))
        .chain(MaterialProperty::ALL.map(|property| Target::Material(index, property)))
}

/// The glTF array a target's object lives in, its index there, and the
/// property's path inside the object.
fn parts(target: Target) -> (&'static str, usize, &'static str) {
    match target {
        Target::Translation(node) => (NODES, node, "translation"),
        Target::Rotation(node) => (NODES, node, "rotation"),
        Target::Scale(node) => (NODES, node, "scale"),
        Target::Weights(node) => (NODES, node, "weights"),
        Target::Light(light, property) => (
            LIGHTS,
            light,
            match property {
                LightProperty::Color => "color",
                LightProperty::Intensity => "intensity",
                LightProperty::Range => "range",
                LightProperty::InnerConeAngle => "spot/innerConeAngle",
                LightProperty::OuterConeAngle => "spot/outerConeAngle",
            },
        ),
        Target::Camera(camera, property) => (
            CAMERAS,
            camera,
            match property {
                CameraProperty::Yfov => "perspective/yfov",
                CameraProperty::Zfar => "perspective/zfar",
            },
        ),
        Target::Material(material, property) => (
            MATERIALS,
            material,
            match property {
                MaterialProperty::BaseColor => "pbrMetallicRoughness/baseColorFactor",
                MaterialProperty::Metallic => "pbrMetallicRoughness/metallicFactor",
                MaterialProperty::Roughness => "pbrMetallicRoughness/roughnessFactor",
                MaterialProperty::Emissive => "emissiveFactor",
                MaterialProperty::Transmission => {
                    "extensions/KHR_materials_transmission/transmissionFactor"
                }
                MaterialProperty::Ior => "extensions/KHR_materials_ior/ior",
                MaterialProperty::Specular => "extensions/KHR_materials_specular/specularFactor",
            },
        ),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_target_reads_back_from_its_pointer() {
        for index in [0, 7, 120] {
            for target in targets_of(index) {
                assert_eq!(parse(&pointer(target)), Some(target), "{target:?}");
            }
        }
        assert_eq!(
            pointer(Target::Light(2, LightProperty::Color)),
            "/extensions/KHR_lights_punctual/lights/2/color"
        );
    }

    #[test]
    fn other_pointers_are_not_targets() {
        for text in [
            "",
            "/",
            "/materials/0/alphaCutoff",
            "/cameras/0/perspective/znear",
            "/cameras/0/orthographic/ymag",
            "/materials/+1/emissiveFactor",
            "/materials/01/emissiveFactor",
            "/materials/-1/emissiveFactor",
            "/materials//emissiveFactor",
            "/materials/0/emissiveFactor/0",
            "/materialsX/0/emissiveFactor",
            "/extensions/KHR_lights_punctual/lights/0",
            "/nodes/99999999999999999999999/translation",
            "nodes/0/translation",
        ] {
            assert_eq!(parse(text), None, "{text}");
        }
    }
}
