//! The default lattice step. A spherical lamp of radius R, with an occluder
//! halfway to the receiver, casts a penumbra about 2R wide; the light mesh's
//! transition is about 2r = 2·kI·h wide (paper, section 2). So by default
//! `h = R / kI`, with R the median lamp radius of the positional lights,
//! times the settings' coarseness (h·kI/R, 1 unless asked: `--preview`
//! takes 1.5).
//! Lights without a radius are ideal points: then h follows the scene's size
//! (1/400 of its diameter), giving penumbrae narrow against the scene. In
//! both cases h is kept within [diameter / 4000, diameter / 20], so a tiny
//! lamp in a city or a huge one in a room still gives a usable lattice.

use super::super::render::light::RenderLight;

pub fn default_h(lights: &[RenderLight], ki: f32, coarseness: f32, scene_diameter: f32) -> f32 {
    let diameter = if scene_diameter.is_finite() && scene_diameter > 0.0 {
        scene_diameter
    } else {
        1.0
    };
    let h = match median_lamp_radius(lights) {
        Some(median) => median * coarseness / ki,
        None => diameter / 400.0 * coarseness,
    };
    h.clamp(diameter / 4000.0, diameter / 20.0)
}

/// The median radius of the positional lights that have one: the R that
/// the default lattice step follows. None when no such light has a radius.
pub fn median_lamp_radius(lights: &[RenderLight]) -> Option<f32> {
    let mut radii: Vec<f32> = lights
        .iter()
        .filter(|light| light.position().is_some() && light.lamp_radius > 0.0)
        .map(|light| light.lamp_radius)
        .collect();
    radii.sort_by(f32::total_cmp);
    radii.get(radii.len() / 2).copied()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::light::LightSource;
    use glam::Vec3;

    fn lamp(radius: f32) -> RenderLight {
        RenderLight {
            source: LightSource::Point {
                position: Vec3::ZERO,
            },
            power: Vec3::ONE,
            range: None,
            lamp_radius: radius,
        }
    }

    #[test]
    fn h_follows_the_median_lamp_radius() {
        let lights = [lamp(0.1), lamp(0.2), lamp(0.9)];
        assert!((default_h(&lights, 2.5, 1.0, 50.0) - 0.2 / 2.5).abs() < 1e-7);
        assert!((default_h(&lights, 2.1, 1.5, 50.0) - 0.2 * 1.5 / 2.1).abs() < 1e-7);
    }

    #[test]
    fn ideal_points_use_the_scene_size_and_extremes_are_clamped() {
        assert_eq!(default_h(&[lamp(0.0)], 2.5, 1.0, 40.0), 0.1);
        assert_eq!(default_h(&[lamp(100.0)], 2.5, 1.0, 40.0), 2.0);
        assert_eq!(default_h(&[lamp(1e-6)], 2.5, 1.0, 40.0), 0.01);
        assert!(default_h(&[], 2.5, 1.0, f32::NAN) > 0.0);
    }
}
