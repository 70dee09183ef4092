//! Scene-model items as glTF JSON objects: materials, KHR_lights_punctual
//! lights, cameras and nodes. Each checks its numbers first, because
//! serde_json silently writes NaN and infinity as `null`, which no reader
//! accepts.

use serde_json::{json, Map, Value};

use lmanim::scene::{Camera, Light, LightKind, Material, Projection};

use super::NodeDesc;

/// Extension names, as written in `extensionsUsed`.
pub(super) const LIGHTS_PUNCTUAL: &str = "KHR_lights_punctual";
pub(super) const TRANSMISSION: &str = "KHR_materials_transmission";
pub(super) const IOR: &str = "KHR_materials_ior";
pub(super) const EMISSIVE_STRENGTH: &str = "KHR_materials_emissive_strength";
pub(super) const ANIMATION_POINTER: &str = "KHR_animation_pointer";

/// The glTF default index of refraction, written only when it differs.
const DEFAULT_IOR: f32 = 1.5;

fn all_finite(values: &[f32]) -> bool {
    values.iter().all(|v| v.is_finite())
}

/// A material object and the extensions it uses.
pub(super) fn material(material: &Material) -> Result<(Value, Vec<&'static str>), String> {
    if material.base_color_texture.is_some() || material.emissive_texture.is_some() {
        return Err("textures are not supported by the glTF builder".into());
    }
    let numbers = [
        material.base_color.to_array().as_slice(),
        material.emissive.to_array().as_slice(),
        &[
            material.metallic,
            material.roughness,
            material.transmission,
            material.ior,
        ],
    ]
    .concat();
    if !all_finite(&numbers) || numbers.iter().any(|&v| v < 0.0) {
        return Err("every factor must be a finite number >= 0".into());
    }
    let mut object = Map::new();
    if let Some(name) = &material.name {
        object.insert("name".into(), json!(name));
    }
    object.insert(
        "pbrMetallicRoughness".into(),
        json!({
            "baseColorFactor": material.base_color.to_array(),
            "metallicFactor": material.metallic,
            "roughnessFactor": material.roughness,
        }),
    );
    let mut extensions = Map::new();
    let mut used = Vec::new();
    // emissiveFactor is limited to [0, 1]; brighter emission is scaled by
    // KHR_materials_emissive_strength.
    let strength = material.emissive.max_element();
    if strength > 1.0 {
        object.insert(
            "emissiveFactor".into(),
            json!((material.emissive / strength).to_array()),
        );
        extensions.insert(
            EMISSIVE_STRENGTH.into(),
            json!({ "emissiveStrength": strength }),
        );
        used.push(EMISSIVE_STRENGTH);
    } else if strength > 0.0 {
        object.insert("emissiveFactor".into(), json!(material.emissive.to_array()));
    }
    if material.double_sided {
        object.insert("doubleSided".into(), json!(true));
    }
    if material.transmission > 0.0 {
        extensions.insert(
            TRANSMISSION.into(),
            json!({ "transmissionFactor": material.transmission }),
        );
        used.push(TRANSMISSION);
    }
    if material.ior != DEFAULT_IOR {
        extensions.insert(IOR.into(), json!({ "ior": material.ior }));
        used.push(IOR);
    }
    if !extensions.is_empty() {
        object.insert("extensions".into(), Value::Object(extensions));
    }
    Ok((Value::Object(object), used))
}

/// A KHR_lights_punctual light object; the lamp radius goes to
/// `extras.radius`, the group to `extras.group`.
pub(super) fn light(light: &Light) -> Result<Value, String> {
    let mut numbers = light.color.to_array().to_vec();
    numbers.push(light.intensity);
    numbers.extend(light.range);
    numbers.extend(light.radius);
    if !all_finite(&numbers) || numbers.iter().any(|&v| v < 0.0) {
        return Err("colour, intensity, range and radius must be finite and >= 0".into());
    }
    let mut object = Map::new();
    if let Some(name) = &light.name {
        object.insert("name".into(), json!(name));
    }
    object.insert("color".into(), json!(light.color.to_array()));
    object.insert("intensity".into(), json!(light.intensity));
    let kind = match light.kind {
        LightKind::Point => "point",
        LightKind::Directional => "directional",
        LightKind::Spot {
            inner_cone,
            outer_cone,
        } => {
            let valid = all_finite(&[inner_cone, outer_cone])
                && 0.0 <= inner_cone
                && inner_cone < outer_cone
                && outer_cone <= std::f32::consts::FRAC_PI_2;
            if !valid {
                return Err(format!(
                    "spot cone angles {inner_cone} and {outer_cone} must satisfy \
                     0 <= inner < outer <= pi/2"
                ));
            }
            object.insert(
                "spot".into(),
                json!({ "innerConeAngle": inner_cone, "outerConeAngle": outer_cone }),
            );
            "spot"
        }
    };
    object.insert("type".into(), json!(kind));
    if let Some(range) = light.range {
        if range == 0.0 {
            return Err("range must be greater than 0".into());
        }
        object.insert("range".into(), json!(range));
    }
    let mut extras = Map::new();
    if let Some(radius) = light.radius {
        extras.insert("radius".into(), json!(radius));
    }
    if let Some(group) = &light.group {
        extras.insert("group".into(), json!(group));
    }
    if !extras.is_empty() {
        object.insert("extras".into(), Value::Object(extras));
    }
    Ok(Value::Object(object))
}

/// A camera object.
pub(super) fn camera(camera: &Camera) -> Result<Value, String> {
    let mut object = Map::new();
    if let Some(name) = &camera.name {
        object.insert("name".into(), json!(name));
    }
    match camera.projection {
        Projection::Perspective {
            yfov,
            aspect_ratio,
            znear,
            zfar,
        } => {
            let mut numbers = vec![yfov, znear];
            numbers.extend(aspect_ratio);
            numbers.extend(zfar);
            if !all_finite(&numbers) || numbers.iter().any(|&v| v <= 0.0) {
                return Err("yfov, aspect ratio, znear and zfar must be > 0".into());
            }
            if zfar.is_some_and(|zfar| zfar <= znear) {
                return Err("zfar must be greater than znear".into());
            }
            let mut perspective = Map::new();
            perspective.insert("yfov".into(), json!(yfov));
            perspective.insert("znear".into(), json!(znear));
            if let Some(aspect_ratio) = aspect_ratio {
                perspective.insert("aspectRatio".into(), json!(aspect_ratio));
            }
            if let Some(zfar) = zfar {
                perspective.insert("zfar".into(), json!(zfar));
            }
            object.insert("type".into(), json!("perspective"));
            object.insert("perspective".into(), Value::Object(perspective));
        }
        Projection::Orthographic {
            xmag,
            ymag,
            znear,
            zfar,
        } => {
            let valid = all_finite(&[xmag, ymag, znear, zfar])
                && xmag != 0.0
                && ymag != 0.0
                && znear >= 0.0
                && zfar > znear;
            if !valid {
                return Err("xmag and ymag must be non-zero, 0 <= znear < zfar".into());
            }
            object.insert("type".into(), json!("orthographic"));
            object.insert(
                "orthographic".into(),
                json!({ "xmag": xmag, "ymag": ymag, "znear": znear, "zfar": zfar }),
            );
        }
    }
    Ok(Value::Object(object))
}

/// A node object; identity parts of the transform are left out.
pub(super) fn node(node: &NodeDesc) -> Result<Value, String> {
    let numbers = [
        node.translation.to_array().as_slice(),
        node.rotation.to_array().as_slice(),
        node.scale.to_array().as_slice(),
    ]
    .concat();
    if !all_finite(&numbers) {
        return Err("translation, rotation and scale must be finite".into());
    }
    if !node.rotation.is_normalized() {
        return Err(format!(
            "rotation {} is not a unit quaternion",
            node.rotation
        ));
    }
    let mut object = Map::new();
    if let Some(name) = &node.name {
        object.insert("name".into(), json!(name));
    }
    if node.translation != glam::Vec3::ZERO {
        object.insert("translation".into(), json!(node.translation.to_array()));
    }
    if node.rotation != glam::Quat::IDENTITY {
        object.insert("rotation".into(), json!(node.rotation.to_array()));
    }
    if node.scale != glam::Vec3::ONE {
        object.insert("scale".into(), json!(node.scale.to_array()));
    }
    if !node.children.is_empty() {
        let children: Vec<usize> = node.children.iter().map(|child| child.0).collect();
        object.insert("children".into(), json!(children));
    }
    if let Some(mesh) = node.mesh {
        object.insert("mesh".into(), json!(mesh.0));
    }
    if let Some(camera) = node.camera {
        object.insert("camera".into(), json!(camera.0));
    }
    if let Some(skin) = node.skin {
        object.insert("skin".into(), json!(skin.0));
    }
    if let Some(weights) = &node.weights {
        if !all_finite(weights) {
            return Err("morph weights must be finite".into());
        }
        object.insert("weights".into(), json!(weights));
    }
    if let Some(light) = node.light {
        object.insert(
            "extensions".into(),
            json!({ LIGHTS_PUNCTUAL: { "light": light.0 } }),
        );
    }
    Ok(Value::Object(object))
}
