//! KHR_lights_punctual lights, with lmanim's two extras: `extras.radius`,
//! the radius in metres of the lamp a point light stands for, which sets the
//! soft-shadow size (see ARCHITECTURE.md, "Conventions"), and
//! `extras.group`, the name of the layer of the `light` AOV it shares with
//! the other lights of its group.

use glam::Vec3;
use gltf::khr_lights_punctual::Kind;

use super::error::Fault;
use crate::scene::{Light, LightKind};

/// Every light of the file, in the file's order.
pub fn import(document: &gltf::Document) -> Result<Vec<Light>, Fault> {
    document
        .lights()
        .into_iter()
        .flatten()
        .map(|light| import_one(&light))
        .collect()
}

fn import_one(light: &gltf::khr_lights_punctual::Light) -> Result<Light, Fault> {
    let fault = |problem: String| Fault::Light {
        light: light.index(),
        problem,
    };
    let color = Vec3::from(light.color());
    if !color.is_finite() || color.min_element() < 0.0 {
        return Err(fault(format!(
            "color {color} is not finite and non-negative"
        )));
    }
    let intensity = light.intensity();
    if !intensity.is_finite() || intensity < 0.0 {
        return Err(fault(format!(
            "intensity {intensity} is not finite and non-negative"
        )));
    }
    let range = light.range();
    if let Some(range) = range.filter(|&range| !(range.is_finite() && range > 0.0)) {
        return Err(fault(format!("range {range} is not finite and positive")));
    }
    let extras = extras(light).map_err(fault)?;
    let kind = match light.kind() {
        Kind::Point => LightKind::Point,
        Kind::Directional => LightKind::Directional,
        Kind::Spot {
            inner_cone_angle,
            outer_cone_angle,
        } => {
            let ordered = 0.0 <= inner_cone_angle
                && inner_cone_angle <= outer_cone_angle
                && outer_cone_angle <= std::f32::consts::FRAC_PI_2;
            if !ordered {
                return Err(fault(format!(
                    "spot cone angles {inner_cone_angle}..{outer_cone_angle} are not within 0..π/2 in order"
                )));
            }
            LightKind::Spot {
                inner_cone: inner_cone_angle,
                outer_cone: outer_cone_angle,
            }
        }
    };
    Ok(Light {
        name: light.name().map(str::to_owned),
        kind,
        color,
        intensity,
        range,
        radius: radius(&extras).map_err(fault)?,
        group: group(&extras).map_err(fault)?,
    })
}

/// The light's extras as JSON (null where it has none). Extras lmanim does
/// not read belong to other tools and are left alone.
fn extras(light: &gltf::khr_lights_punctual::Light) -> Result<serde_json::Value, String> {
    match light.extras() {
        Some(raw) => serde_json::from_str(raw.get()).map_err(|error| format!("extras: {error}")),
        None => Ok(serde_json::Value::Null),
    }
}

/// `extras.group` when the extras are an object that has it.
fn group(extras: &serde_json::Value) -> Result<Option<String>, String> {
    match extras.get("group") {
        None => Ok(None),
        Some(serde_json::Value::String(group)) => Ok(Some(group.clone())),
        Some(other) => Err(format!("extras.group {other} is not a string")),
    }
}

/// `extras.radius` when the extras are an object that has it.
fn radius(extras: &serde_json::Value) -> Result<Option<f32>, String> {
    let Some(radius) = extras.get("radius") else {
        return Ok(None);
    };
    match radius.as_f64().map(|radius| radius as f32) {
        Some(radius) if radius.is_finite() && radius >= 0.0 => Ok(Some(radius)),
        _ => Err(format!(
            "extras.radius {radius} is not a finite, non-negative number of metres"
        )),
    }
}
