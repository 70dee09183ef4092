//! A sampled KHR_animation_pointer value written into the light, camera or
//! material it animates, one step of posing a frame beside the node
//! channels. Values are clamped to what glTF allows the property, as import
//! checks the file's own values: keys outside it, or a CUBICSPLINE curve
//! overshooting between valid keys, still give a light, camera and
//! material the renderer can use.

use std::f32::consts::{FRAC_PI_2, PI};

use glam::{Vec3, Vec4};

use crate::scene::pose::Properties;
use crate::scene::{
    CameraProperty, Light, LightKind, LightProperty, Material, MaterialProperty, Projection, Target,
};

/// Writes `value` into the property `target` names. Node targets, indices
/// past the scene's arrays and values of the wrong width change nothing:
/// import routes node targets elsewhere and refuses the other two.
pub fn apply(properties: &mut Properties, target: Target, value: &[f64]) {
    let value: Vec<f32> = value.iter().map(|&v| v as f32).collect();
    match target {
        Target::Light(light, property) => {
            if let Some(light) = properties.lights.get_mut(light) {
                set_light(light, property, &value);
            }
        }
        Target::Camera(camera, property) => {
            if let Some(projection) = properties.cameras.get_mut(camera) {
                set_camera(projection, property, &value);
            }
        }
        Target::Material(material, property) => {
            if let Some(material) = properties.materials.get_mut(material) {
                set_material(material, property, &value);
            }
        }
        Target::Translation(_) | Target::Rotation(_) | Target::Scale(_) | Target::Weights(_) => {}
    }
}

fn set_light(light: &mut Light, property: LightProperty, value: &[f32]) {
    let cone = |angle: f32| angle.clamp(0.0, FRAC_PI_2);
    match (property, value, &mut light.kind) {
        (LightProperty::Color, &[r, g, b], _) => light.color = Vec3::new(r, g, b).max(Vec3::ZERO),
        (LightProperty::Intensity, &[intensity], _) => light.intensity = intensity.max(0.0),
        (LightProperty::Range, &[range], _) => light.range = Some(range.max(f32::MIN_POSITIVE)),
        (LightProperty::InnerConeAngle, &[angle], LightKind::Spot { inner_cone, .. }) => {
            *inner_cone = cone(angle)
        }
        (LightProperty::OuterConeAngle, &[angle], LightKind::Spot { outer_cone, .. }) => {
            *outer_cone = cone(angle)
        }
        _ => {}
    }
}

fn set_camera(projection: &mut Projection, property: CameraProperty, value: &[f32]) {
    let (
        Projection::Perspective {
            yfov, znear, zfar, ..
        },
        &[value],
    ) = (projection, value)
    else {
        return;
    };
    match property {
        CameraProperty::Yfov => *yfov = value.clamp(0.0, PI),
        CameraProperty::Zfar => *zfar = Some(value.max(*znear)),
    }
}

fn set_material(material: &mut Material, property: MaterialProperty, value: &[f32]) {
    let unit = |factor: f32| factor.clamp(0.0, 1.0);
    match (property, value) {
        (MaterialProperty::BaseColor, &[r, g, b, a]) => {
            material.base_color = Vec4::new(r, g, b, a).clamp(Vec4::ZERO, Vec4::ONE)
        }
        (MaterialProperty::Metallic, &[factor]) => material.metallic = unit(factor),
        (MaterialProperty::Roughness, &[factor]) => material.roughness = unit(factor),
        (MaterialProperty::Emissive, &[r, g, b]) => {
            material.emissive = Vec3::new(r, g, b).max(Vec3::ZERO)
        }
        (MaterialProperty::Transmission, &[factor]) => material.transmission = unit(factor),
        (MaterialProperty::Ior, &[ior]) => material.ior = ior.max(1.0),
        (MaterialProperty::Specular, &[factor]) => material.specular = unit(factor),
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn properties() -> Properties {
        Properties {
            lights: vec![Light {
                name: None,
                kind: LightKind::Spot {
                    inner_cone: 0.1,
                    outer_cone: 0.5,
                },
                color: Vec3::ONE,
                intensity: 1.0,
                range: None,
                radius: None,
                group: None,
            }],
            cameras: vec![Projection::Perspective {
                yfov: 1.0,
                aspect_ratio: None,
                znear: 0.5,
                zfar: None,
            }],
            materials: vec![Material::default()],
        }
    }

    #[test]
    fn values_land_in_their_property() {
        let mut p = properties();
        apply(
            &mut p,
            Target::Light(0, LightProperty::Color),
            &[0.5, 0.25, 1.0],
        );
        apply(&mut p, Target::Light(0, LightProperty::Range), &[4.0]);
        apply(
            &mut p,
            Target::Light(0, LightProperty::OuterConeAngle),
            &[0.75],
        );
        apply(&mut p, Target::Camera(0, CameraProperty::Yfov), &[0.5]);
        apply(&mut p, Target::Camera(0, CameraProperty::Zfar), &[100.0]);
        let base = [0.1, 0.2, 0.3, 0.4];
        apply(
            &mut p,
            Target::Material(0, MaterialProperty::BaseColor),
            &base,
        );
        apply(&mut p, Target::Material(0, MaterialProperty::Ior), &[1.33]);
        let light = &p.lights[0];
        assert_eq!(light.color, Vec3::new(0.5, 0.25, 1.0));
        assert_eq!(light.range, Some(4.0));
        assert_eq!(
            light.kind,
            LightKind::Spot {
                inner_cone: 0.1,
                outer_cone: 0.75
            }
        );
        let Projection::Perspective { yfov, zfar, .. } = p.cameras[0] else {
            unreachable!()
        };
        assert_eq!((yfov, zfar), (0.5, Some(100.0)));
        assert_eq!(p.materials[0].base_color, Vec4::new(0.1, 0.2, 0.3, 0.4));
        assert_eq!(p.materials[0].ior, 1.33);
    }

    #[test]
    fn values_outside_the_property_are_clamped_and_misfits_ignored() {
        let mut p = properties();
        apply(&mut p, Target::Light(0, LightProperty::Intensity), &[-3.0]);
        apply(&mut p, Target::Camera(0, CameraProperty::Zfar), &[0.1]);
        apply(
            &mut p,
            Target::Material(0, MaterialProperty::Roughness),
            &[1.2],
        );
        // Wrong width, index past the array, node target: nothing changes.
        let before = p.clone();
        apply(&mut p, Target::Light(0, LightProperty::Color), &[1.0]);
        apply(&mut p, Target::Light(3, LightProperty::Intensity), &[2.0]);
        apply(&mut p, Target::Translation(0), &[1.0, 2.0, 3.0]);
        assert_eq!(p, before);
        assert_eq!(p.lights[0].intensity, 0.0);
        assert!(matches!(
            p.cameras[0],
            Projection::Perspective {
                zfar: Some(0.5),
                ..
            }
        ));
        assert_eq!(p.materials[0].roughness, 1.0);
    }
}
