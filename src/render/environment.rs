//! What surrounds the scene, both off unless the settings ask: the
//! background a camera ray shows when it meets nothing, and a uniform sky
//! whose light every surface's diffuse part reflects (the ambient term).
//! Both enter at the last two stages of a frame, where a shaded point's
//! value goes to its sample and where samples become pixels, so every
//! method and both backends get them the same way
//! (`backend/gpu/shaders/accumulate.wgsl` and `resolve.wgsl` repeat this
//! file operation for operation).
//!
//! The sky is not shadowed: no ray tests it, so it costs a few products
//! per shading point and lights a street under an overhang as it lights an
//! open square. It stands for the light an unlit part of a frame would get
//! from the sky and from interreflection, which lmanim does not trace.

use glam::Vec3;

use super::material::SurfaceMaterial;
use super::surface::ShadingPoint;

/// The background and the ambient sky of a frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Environment {
    /// Radiance of a camera sample whose ray meets nothing, which makes
    /// every pixel opaque; None leaves such samples transparent black.
    pub background: Option<Vec3>,
    /// Radiance of a uniform, unshadowed sky over every surface; None: no
    /// ambient term.
    pub ambient: Option<Vec3>,
}

impl Environment {
    /// What `point` sends towards its sample that no light brought: its
    /// emission, plus the sky's light on its diffuse part where there is a
    /// sky.
    pub fn unlit(&self, point: &ShadingPoint) -> Vec3 {
        match self.ambient {
            Some(sky) => point.emitted() + sky * diffuse_albedo(&point.material),
            None => point.emitted(),
        }
    }

    /// What a shaded point sends towards its sample: what no light brought
    /// plus its `direct` light, times its path throughput.
    pub fn shaded_value(&self, point: &ShadingPoint, direct: Vec3) -> Vec3 {
        point.weight * (self.unlit(point) + direct)
    }

    /// A camera sample's radiance: what its points sent, or the background
    /// where its ray met nothing (and there is a background).
    pub fn sample_radiance(&self, sent: Vec3, covered: bool) -> Vec3 {
        match self.background {
            Some(background) if !covered => background,
            _ => sent,
        }
    }

    /// A pixel's alpha: its coverage, or 1 behind an opaque background.
    pub fn alpha(&self, coverage: f32) -> f32 {
        if self.background.is_some() {
            1.0
        } else {
            coverage
        }
    }
}

/// The share of a uniform sky's radiance the diffuse lobe reflects: the
/// Lambert term ρ/π integrated over the hemisphere (π) leaves ρ, the base
/// colour less what the surface transmits and what a metal reflects
/// specularly.
pub fn diffuse_albedo(material: &SurfaceMaterial) -> Vec3 {
    material.base_color * ((1.0 - material.transmission) * (1.0 - material.metallic))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn matte(base_color: Vec3) -> SurfaceMaterial {
        SurfaceMaterial {
            base_color,
            metallic: 0.0,
            roughness: 0.8,
            specular: 1.0,
            transmission: 0.0,
            ior: 1.5,
            emissive: Vec3::ZERO,
        }
    }

    #[test]
    fn a_matte_surface_reflects_its_base_colour_of_the_sky() {
        assert_eq!(
            diffuse_albedo(&matte(Vec3::new(0.5, 0.25, 1.0))),
            Vec3::new(0.5, 0.25, 1.0)
        );
    }

    #[test]
    fn metal_and_glass_take_no_diffuse_sky() {
        let metal = SurfaceMaterial {
            metallic: 1.0,
            ..matte(Vec3::ONE)
        };
        let glass = SurfaceMaterial {
            transmission: 1.0,
            ..matte(Vec3::ONE)
        };
        assert_eq!(diffuse_albedo(&metal), Vec3::ZERO);
        assert_eq!(diffuse_albedo(&glass), Vec3::ZERO);
    }

    #[test]
    fn without_a_background_a_miss_stays_transparent_black() {
        let none = Environment::default();
        assert_eq!(none.sample_radiance(Vec3::ZERO, false), Vec3::ZERO);
        assert_eq!(none.alpha(0.25), 0.25);
        let blue = Environment {
            background: Some(Vec3::new(0.1, 0.2, 0.4)),
            ..Environment::default()
        };
        assert_eq!(
            blue.sample_radiance(Vec3::ZERO, false),
            Vec3::new(0.1, 0.2, 0.4)
        );
        assert_eq!(blue.sample_radiance(Vec3::ONE, true), Vec3::ONE);
        assert_eq!(blue.alpha(0.25), 1.0);
    }
}
