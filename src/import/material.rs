//! glTF materials → [`scene::Material`], with the textures they use.
//!
//! Factors come from the core metallic-roughness model and from
//! KHR_materials_transmission, _ior and _specular. Only the base-colour and emissive textures are imported (the renderer
//! shades with factors otherwise), each decoded once however many materials
//! share it. Texture indices in the result are the scene's, not the file's.

use std::collections::HashMap;
use std::path::Path;

use glam::{Vec3, Vec4};

use super::error::Fault;
use super::texture;
use crate::scene::{Material, Texture, TextureRef};

/// Materials in the file's order, then the default material when
/// `append_default` (some primitive names none), and the textures they use.
pub fn import(
    document: &gltf::Document,
    buffers: &[Vec<u8>],
    base: &Path,
    append_default: bool,
) -> Result<(Vec<Material>, Vec<Texture>), Fault> {
    let mut textures = Textures {
        buffers,
        base,
        decoded: Vec::new(),
        by_file_index: HashMap::new(),
    };
    let mut materials = document
        .materials()
        .map(|material| import_one(&material, &mut textures))
        .collect::<Result<Vec<_>, _>>()?;
    if append_default {
        materials.push(Material::default());
    }
    Ok((materials, textures.decoded))
}

fn import_one(material: &gltf::Material, textures: &mut Textures) -> Result<Material, Fault> {
    let index = material.index().unwrap_or_default();
    let fault = |problem: String| Fault::Material {
        material: index,
        problem,
    };
    let pbr = material.pbr_metallic_roughness();
    let imported = Material {
        name: material.name().map(str::to_owned),
        base_color: Vec4::from(pbr.base_color_factor()),
        base_color_texture: textures.use_texture(index, pbr.base_color_texture())?,
        metallic: pbr.metallic_factor(),
        roughness: pbr.roughness_factor(),
        specular: material
            .specular()
            .map_or(1.0, |specular| specular.specular_factor()),
        emissive: Vec3::from(material.emissive_factor()),
        emissive_texture: textures.use_texture(index, material.emissive_texture())?,
        double_sided: material.double_sided(),
        transmission: material
            .transmission()
            .map_or(0.0, |transmission| transmission.transmission_factor()),
        ior: material.ior().unwrap_or(1.5),
    };
    let unit = |value: f32| (0.0..=1.0).contains(&value);
    let checks = [
        (
            imported.base_color.to_array().into_iter().all(unit),
            "baseColorFactor is not within 0..1",
        ),
        (unit(imported.metallic), "metallicFactor is not within 0..1"),
        (
            unit(imported.roughness),
            "roughnessFactor is not within 0..1",
        ),
        (unit(imported.specular), "specularFactor is not within 0..1"),
        (
            imported.emissive.is_finite() && imported.emissive.min_element() >= 0.0,
            "emissiveFactor is not finite and non-negative",
        ),
        (
            unit(imported.transmission),
            "transmissionFactor is not within 0..1",
        ),
        (
            imported.ior.is_finite() && imported.ior >= 1.0,
            "ior is not a finite value of at least 1",
        ),
    ];
    match checks.into_iter().find(|(ok, _)| !ok) {
        Some((_, problem)) => Err(fault(problem.to_owned())),
        None => Ok(imported),
    }
}

/// The scene's textures, filled as materials ask for them.
struct Textures<'a> {
    buffers: &'a [Vec<u8>],
    base: &'a Path,
    decoded: Vec<Texture>,
    /// glTF texture index → index into `decoded`.
    by_file_index: HashMap<usize, usize>,
}

impl Textures<'_> {
    fn use_texture(
        &mut self,
        material: usize,
        info: Option<gltf::texture::Info>,
    ) -> Result<Option<TextureRef>, Fault> {
        let Some(info) = info else { return Ok(None) };
        if info.tex_coord() != 0 {
            log::warn!(
                "material {material} uses TEXCOORD_{}; only set 0 is imported, so it is used instead",
                info.tex_coord()
            );
        }
        let file_texture = info.texture();
        let texture = match self.by_file_index.get(&file_texture.index()) {
            Some(&texture) => texture,
            None => {
                let decoded = texture::import(&file_texture, self.buffers, self.base)?;
                self.decoded.push(decoded);
                self.by_file_index
                    .insert(file_texture.index(), self.decoded.len() - 1);
                self.decoded.len() - 1
            }
        };
        Ok(Some(TextureRef {
            texture,
            tex_coord: info.tex_coord(),
        }))
    }
}
