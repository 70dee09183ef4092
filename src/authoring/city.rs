//! A procedural city block: a grid of box buildings of varied heights along
//! streets, a ground plane, street lamps at lamp-post height and a camera
//! looking down the main street. It is the "street" scene of the paper's
//! section 4 and the scene of the light-mesh benchmarks; the animation work
//! adds cars and trees to it.

use glam::{Quat, Vec2, Vec3};

use super::{look_at_rotation, shapes, AuthoringError, GltfBuilder, NodeDesc, Primitive};
use crate::scene::{Camera, Light, LightKind, Material, Projection};

/// The shape of a generated city block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CityParams {
    /// Buildings along each side of the square grid.
    pub blocks: u32,
    /// Street lamps, placed along the streets nearest the camera first.
    pub lamps: u32,
    /// Radius of each lamp's bulb, metres (`extras.radius`).
    pub lamp_radius: f32,
}

impl Default for CityParams {
    fn default() -> Self {
        CityParams {
            blocks: 10,
            lamps: 16,
            lamp_radius: 0.25,
        }
    }
}

/// Metres from one building's centre to the next.
const PITCH: f32 = 20.0;
/// Building footprint edge, metres (the rest of the pitch is street).
const FOOTPRINT: f32 = 12.0;
const LAMP_HEIGHT: f32 = 5.0;

/// A deterministic pseudo-random value in [0, 1) for grid cell `(i, j)`.
fn cell_noise(i: u32, j: u32, salt: u32) -> f32 {
    let mut x =
        i.wrapping_mul(0x9E37_79B1) ^ j.wrapping_mul(0x85EB_CA77) ^ salt.wrapping_mul(0xC2B2_AE3D);
    x ^= x >> 15;
    x = x.wrapping_mul(0x2C1B_3C6D);
    x ^= x >> 12;
    (x >> 8) as f32 / (1u32 << 24) as f32
}

/// Builds the city block of `params`.
pub fn city_block(params: &CityParams) -> Result<GltfBuilder, AuthoringError> {
    let mut b = GltfBuilder::new();
    let matte = |name: &str, colour: Vec3, roughness: f32| Material {
        name: Some(name.into()),
        base_color: colour.extend(1.0),
        metallic: 0.0,
        roughness,
        ..Material::default()
    };
    let asphalt = b.add_material(&matte("Asphalt", Vec3::new(0.18, 0.18, 0.19), 0.9))?;
    let facades = [
        b.add_material(&matte("Brick", Vec3::new(0.55, 0.3, 0.22), 0.85))?,
        b.add_material(&matte("Concrete", Vec3::new(0.6, 0.6, 0.58), 0.8))?,
        b.add_material(&matte("Sandstone", Vec3::new(0.72, 0.62, 0.45), 0.9))?,
    ];
    let cube = b.add_geometry(&shapes::cuboid(Vec3::splat(0.5)))?;
    let ground_half = 0.5 * PITCH * params.blocks as f32 + PITCH;
    let ground = b.add_geometry(&shapes::plane(Vec2::splat(ground_half)))?;
    let ground_mesh = b.add_mesh(
        "Ground",
        &[Primitive {
            geometry: ground,
            material: Some(asphalt),
        }],
    )?;
    b.add_node(NodeDesc {
        mesh: Some(ground_mesh),
        ..NodeDesc::named("Ground")
    })?;

    let building_meshes = facades
        .iter()
        .enumerate()
        .map(|(index, &material)| {
            b.add_mesh(
                &format!("Building{index}"),
                &[Primitive {
                    geometry: cube,
                    material: Some(material),
                }],
            )
        })
        .collect::<Result<Vec<_>, _>>()?;
    let centre = |i: u32| (i as f32 - 0.5 * (params.blocks - 1) as f32) * PITCH;
    for j in 0..params.blocks {
        for i in 0..params.blocks {
            let height = 6.0 + 30.0 * cell_noise(i, j, 1).powi(2);
            let width = FOOTPRINT * (0.75 + 0.25 * cell_noise(i, j, 2));
            let depth = FOOTPRINT * (0.75 + 0.25 * cell_noise(i, j, 3));
            let style = (cell_noise(i, j, 4) * facades.len() as f32) as usize;
            b.add_node(NodeDesc {
                translation: Vec3::new(centre(i), 0.5 * height, centre(j)),
                scale: Vec3::new(width, height, depth),
                mesh: Some(building_meshes[style.min(facades.len() - 1)]),
                ..NodeDesc::named(&format!("Building.{i}.{j}"))
            })?;
        }
    }

    // Lamps line the street the camera looks down (x = centre of a street
    // between building columns), alternating sides, nearest first.
    let street_x = centre(params.blocks / 2) - 0.5 * PITCH;
    for lamp in 0..params.lamps {
        let side = if lamp % 2 == 0 { -1.0 } else { 1.0 };
        let along = centre(params.blocks - 1) - 0.5 * PITCH - (lamp / 2) as f32 * 0.5 * PITCH;
        let light = b.add_light(&Light {
            name: Some(format!("StreetLamp.{lamp}")),
            kind: LightKind::Point,
            color: Vec3::new(1.0, 0.85, 0.65),
            intensity: 300.0,
            range: None,
            radius: Some(params.lamp_radius),
        })?;
        b.add_node(NodeDesc {
            translation: Vec3::new(street_x + side * 3.0, LAMP_HEIGHT, along),
            light: Some(light),
            ..NodeDesc::named(&format!("StreetLamp.{lamp}"))
        })?;
    }

    let camera = b.add_camera(&Camera {
        name: Some("street".into()),
        projection: Projection::Perspective {
            yfov: 55f32.to_radians(),
            aspect_ratio: None,
            znear: 0.1,
            zfar: None,
        },
    })?;
    let eye = Vec3::new(street_x + 1.5, 9.0, centre(params.blocks - 1) + 0.5 * PITCH);
    let target = Vec3::new(street_x - 1.0, 0.0, centre(params.blocks / 2));
    b.add_node(NodeDesc {
        translation: eye,
        rotation: look_at_rotation(eye, target, Vec3::Y).unwrap_or(Quat::IDENTITY),
        camera: Some(camera),
        ..NodeDesc::named("street")
    })?;
    Ok(b)
}
