//! A material evaluated at one surface point: factors times textures, the
//! numbers the BRDF and the Whitted recursion read.

use glam::{Vec2, Vec3, Vec4};

use crate::scene::{Material, Texture, TextureRef, Wrap};

/// Below this roughness a surface is a mirror for the Whitted recursion:
/// it reflects a sharp image, which a delta direction represents well.
/// Rougher surfaces keep only their direct highlight.
pub const MIRROR_ROUGHNESS: f32 = 0.1;

/// GGX has no finite value for roughness 0; the direct highlight of a point
/// light on a perfect mirror is drawn as if the surface had this roughness.
const MIN_HIGHLIGHT_ROUGHNESS: f32 = 0.03;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SurfaceMaterial {
    pub base_color: Vec3,
    pub metallic: f32,
    /// Perceptual roughness as in glTF (α = roughness²).
    pub roughness: f32,
    /// KHR_materials_specular weight of the dielectric specular lobe.
    pub specular: f32,
    pub transmission: f32,
    pub ior: f32,
    pub emissive: Vec3,
}

impl SurfaceMaterial {
    pub fn at(material: &Material, textures: &[Texture], uv: Vec2) -> SurfaceMaterial {
        let sample = |slot: Option<TextureRef>| {
            slot.and_then(|slot| textures.get(slot.texture))
                .map_or(Vec4::ONE, |texture| sample_bilinear(texture, uv))
        };
        let base = material.base_color * sample(material.base_color_texture);
        SurfaceMaterial {
            base_color: base.truncate(),
            metallic: material.metallic.clamp(0.0, 1.0),
            roughness: material.roughness.clamp(0.0, 1.0),
            specular: material.specular.clamp(0.0, 1.0),
            transmission: material.transmission.clamp(0.0, 1.0),
            ior: material.ior,
            emissive: material.emissive * sample(material.emissive_texture).truncate(),
        }
    }

    /// Roughness used for point-light highlights (see
    /// [`MIN_HIGHLIGHT_ROUGHNESS`]).
    pub fn highlight_roughness(&self) -> f32 {
        self.roughness.max(MIN_HIGHLIGHT_ROUGHNESS)
    }

    /// Whether the Whitted recursion traces a mirror reflection here.
    pub fn reflects(&self) -> bool {
        self.roughness < MIRROR_ROUGHNESS && (self.metallic > 0.0 || self.specular > 0.0)
    }

    /// Whether the Whitted recursion traces a refracted ray here.
    pub fn transmits(&self) -> bool {
        self.transmission > 0.0 && self.metallic < 1.0
    }
}

/// Bilinear filtering with the sampler's wrap modes; texel centres sit at
/// half-integer coordinates as in GPU samplers, so results match viewers.
fn sample_bilinear(texture: &Texture, uv: Vec2) -> Vec4 {
    let (width, height) = (texture.width as i64, texture.height as i64);
    if width == 0 || height == 0 || !uv.is_finite() {
        return Vec4::ONE;
    }
    let x = uv.x * width as f32 - 0.5;
    let y = uv.y * height as f32 - 0.5;
    let (x0, y0) = (x.floor(), y.floor());
    let (fx, fy) = (x - x0, y - y0);
    let texel = |ix: i64, iy: i64| {
        let column = wrap(ix, width, texture.wrap_s);
        let row = wrap(iy, height, texture.wrap_t);
        texture.texels[(row * width + column) as usize]
    };
    let (ix, iy) = (x0 as i64, y0 as i64);
    let top = texel(ix, iy).lerp(texel(ix + 1, iy), fx);
    let bottom = texel(ix, iy + 1).lerp(texel(ix + 1, iy + 1), fx);
    top.lerp(bottom, fy)
}

fn wrap(i: i64, n: i64, mode: Wrap) -> i64 {
    match mode {
        Wrap::ClampToEdge => i.clamp(0, n - 1),
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::MirroredRepeat => {
            let period = i.rem_euclid(2 * n);
            if period < n {
                period
            } else {
                2 * n - 1 - period
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn checker(wrap: Wrap) -> Texture {
        Texture {
            width: 2,
            height: 1,
            texels: vec![Vec4::ZERO, Vec4::ONE],
            wrap_s: wrap,
            wrap_t: wrap,
        }
    }

    #[test]
    fn texel_centres_return_texels_and_midpoints_blend() {
        let texture = checker(Wrap::ClampToEdge);
        assert_eq!(sample_bilinear(&texture, Vec2::new(0.25, 0.5)), Vec4::ZERO);
        assert_eq!(sample_bilinear(&texture, Vec2::new(0.75, 0.5)), Vec4::ONE);
        assert_eq!(
            sample_bilinear(&texture, Vec2::new(0.5, 0.5)),
            Vec4::splat(0.5)
        );
    }

    #[test]
    fn wrap_modes_differ_past_the_edge() {
        assert_eq!(wrap(-1, 4, Wrap::ClampToEdge), 0);
        assert_eq!(wrap(-1, 4, Wrap::Repeat), 3);
        assert_eq!(wrap(-1, 4, Wrap::MirroredRepeat), 0);
        assert_eq!(wrap(5, 4, Wrap::MirroredRepeat), 2);
        assert_eq!(wrap(8, 4, Wrap::MirroredRepeat), 0);
    }

    #[test]
    fn texture_multiplies_the_base_colour_factor() {
        let material = Material {
            base_color: Vec4::new(0.5, 1.0, 1.0, 1.0),
            base_color_texture: Some(TextureRef {
                texture: 0,
                tex_coord: 0,
            }),
            ..Material::default()
        };
        let at = SurfaceMaterial::at(&material, &[checker(Wrap::Repeat)], Vec2::new(0.75, 0.5));
        assert_eq!(at.base_color, Vec3::new(0.5, 1.0, 1.0));
    }
}
