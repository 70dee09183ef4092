//! A procedural city block: a grid of box buildings of varied heights along
//! streets, a ground plane, street lamps at lamp-post height and a camera
//! looking down the main street. It is the "street" scene of the paper's
//! section 4 and the scene of the light-mesh benchmarks.
//!
//! The same block, with windowed facades, cars lapping the streets, trees
//! swaying along the main street and a camera flying through, is the
//! project's showcase animation (`animations/city.gltf`, written by
//! `examples/make_animations.rs`). The parts' geometry is in `parts`,
//! their keyframes in `motion`.

mod motion;
mod parts;

use glam::{DMat4, DVec3, Quat, Vec2, Vec3};

use super::{
    look_at_rotation, matte, shapes, AuthoringError, GeometryId, GltfBuilder, MaterialId, MeshId,
    NodeDesc, NodeId, Primitive,
};
use lmanim::scene::{AnimationClip, Camera, Channel, Light, LightKind, Projection, Skin, Target};
use motion::{FlyThrough, Route};

/// The shape of a generated city block.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CityParams {
    /// Buildings along each side of the square grid.
    pub blocks: u32,
    /// Street lamps, placed along the streets nearest the camera first.
    pub lamps: u32,
    /// Radius of each lamp's bulb, metres (`extras.radius`).
    pub lamp_radius: f32,
    /// Each lamp's `range`, metres (None: unlimited).
    pub lamp_range: Option<f32>,
    /// Windows along and up each wall (0: plain boxes, 12 triangles per
    /// building; n: 18 n² per wall).
    pub facade_detail: u32,
    /// Cars lapping rectangles of streets next to the main street.
    pub cars: u32,
    /// Swaying trees along the main street.
    pub trees: u32,
    /// Adds the camera "flythrough", flying over the block and down the
    /// main street.
    pub flythrough: bool,
}

impl Default for CityParams {
    fn default() -> Self {
        CityParams {
            blocks: 10,
            lamps: 16,
            lamp_radius: 0.25,
            lamp_range: None,
            facade_detail: 0,
            cars: 0,
            trees: 0,
            flythrough: false,
        }
    }
}

/// Metres from one building's centre to the next.
const PITCH: f32 = 20.0;
/// Building footprint edge, metres (the rest of the pitch is street).
const FOOTPRINT: f32 = 12.0;
const LAMP_HEIGHT: f32 = 5.0;

/// Metres between a street's centre line and a car's.
const LANE: f32 = 1.8;
/// Metres between the main street's centre line and its trees.
const TREE_OFFSET: f32 = 3.3;

/// A deterministic pseudo-random value in [0, 1) for grid cell `(i, j)`.
fn cell_noise(i: u32, j: u32, salt: u32) -> f32 {
    let mut x =
        i.wrapping_mul(0x9E37_79B1) ^ j.wrapping_mul(0x85EB_CA77) ^ salt.wrapping_mul(0xC2B2_AE3D);
    x ^= x >> 15;
    x = x.wrapping_mul(0x2C1B_3C6D);
    x ^= x >> 12;
    (x >> 8) as f32 / (1u32 << 24) as f32
}

/// Where things stand in a block of `blocks` × `blocks` buildings.
#[derive(Clone, Copy)]
struct Layout {
    blocks: u32,
}

impl Layout {
    /// The centre of building column (x) or row (z) `i`.
    fn centre(self, i: u32) -> f32 {
        (i as f32 - 0.5 * (self.blocks as f32 - 1.0)) * PITCH
    }

    /// The centre line of the street after building column or row `k`.
    fn street(self, k: u32) -> f32 {
        self.centre(k) + 0.5 * PITCH
    }

    /// The index of the main street, which lamps and trees line: the
    /// street before the middle column.
    fn main_street(self) -> u32 {
        (self.blocks / 2).saturating_sub(1)
    }

    /// The main street's centre line (x).
    fn main_street_x(self) -> f32 {
        self.centre(self.blocks / 2) - 0.5 * PITCH
    }

    /// Where along the main street (z) lamp row `row` stands, the row
    /// nearest the street camera 0, rows half a pitch apart.
    fn along_main(self, row: f32) -> f32 {
        self.centre(self.blocks - 1) - 0.5 * PITCH - row * 0.5 * PITCH
    }
}

/// Builds the city block of `params`. Its motion is three clips that play
/// together by default and can be rendered alone (`--clip`): "Traffic"
/// (the cars), "Wind" (the trees) and "Flythrough" (the camera).
pub fn city_block(params: &CityParams) -> Result<GltfBuilder, AuthoringError> {
    let mut b = GltfBuilder::new();
    let layout = Layout {
        blocks: params.blocks,
    };
    add_ground(&mut b, layout)?;
    add_buildings(&mut b, layout, params.facade_detail)?;
    add_lamps(&mut b, layout, params)?;
    add_street_camera(&mut b, layout)?;
    let traffic = add_cars(&mut b, layout, params.cars)?;
    let wind = add_trees(&mut b, layout, params.trees)?;
    let flythrough = match params.flythrough {
        true => add_flythrough(&mut b, layout)?,
        false => Vec::new(),
    };
    for (name, channels) in [
        ("Traffic", traffic),
        ("Wind", wind),
        ("Flythrough", flythrough),
    ] {
        if !channels.is_empty() {
            b.add_animation(&AnimationClip {
                name: Some(name.into()),
                channels,
            })?;
        }
    }
    Ok(b)
}

/// A mesh of one primitive per (geometry, material) pair.
fn add_mesh(
    b: &mut GltfBuilder,
    name: &str,
    parts: &[(GeometryId, MaterialId)],
) -> Result<MeshId, AuthoringError> {
    let primitives: Vec<Primitive> = parts
        .iter()
        .map(|&(geometry, material)| Primitive {
            geometry,
            material: Some(material),
        })
        .collect();
    b.add_mesh(name, &primitives)
}

fn add_ground(b: &mut GltfBuilder, layout: Layout) -> Result<NodeId, AuthoringError> {
    let asphalt = b.add_material(&matte("Asphalt", Vec3::new(0.18, 0.18, 0.19), 0.9))?;
    let ground_half = 0.5 * PITCH * layout.blocks as f32 + PITCH;
    let ground = b.add_geometry(&shapes::plane(Vec2::splat(ground_half)))?;
    let ground_mesh = add_mesh(b, "Ground", &[(ground, asphalt)])?;
    b.add_node(NodeDesc {
        mesh: Some(ground_mesh),
        ..NodeDesc::named("Ground")
    })
}

/// One mesh per facade material, a unit box each node scales to its
/// building: plain, or with `facade_detail`² windows per wall.
fn building_meshes(b: &mut GltfBuilder, facade_detail: u32) -> Result<Vec<MeshId>, AuthoringError> {
    let facades = [
        b.add_material(&matte("Brick", Vec3::new(0.55, 0.3, 0.22), 0.85))?,
        b.add_material(&matte("Concrete", Vec3::new(0.6, 0.6, 0.58), 0.8))?,
        b.add_material(&matte("Sandstone", Vec3::new(0.72, 0.62, 0.45), 0.9))?,
    ];
    let (walls, panes) = if facade_detail == 0 {
        (b.add_geometry(&shapes::cuboid(Vec3::splat(0.5)))?, None)
    } else {
        let facade = parts::facade(facade_detail);
        let glass = b.add_material(&matte("Window", Vec3::new(0.08, 0.1, 0.12), 0.15))?;
        let walls = b.add_geometry(&facade.walls)?;
        (walls, Some((b.add_geometry(&facade.panes)?, glass)))
    };
    facades
        .iter()
        .enumerate()
        .map(|(index, &material)| {
            let parts: Vec<_> = [(walls, material)].into_iter().chain(panes).collect();
            add_mesh(b, &format!("Building{index}"), &parts)
        })
        .collect()
}

fn add_buildings(
    b: &mut GltfBuilder,
    layout: Layout,
    facade_detail: u32,
) -> Result<(), AuthoringError> {
    let meshes = building_meshes(b, facade_detail)?;
    for j in 0..layout.blocks {
        for i in 0..layout.blocks {
            let height = 6.0 + 30.0 * cell_noise(i, j, 1).powi(2);
            let width = FOOTPRINT * (0.75 + 0.25 * cell_noise(i, j, 2));
            let depth = FOOTPRINT * (0.75 + 0.25 * cell_noise(i, j, 3));
            let style = (cell_noise(i, j, 4) * meshes.len() as f32) as usize;
            b.add_node(NodeDesc {
                translation: Vec3::new(layout.centre(i), 0.5 * height, layout.centre(j)),
                scale: Vec3::new(width, height, depth),
                mesh: Some(meshes[style.min(meshes.len() - 1)]),
                ..NodeDesc::named(&format!("Building.{i}.{j}"))
            })?;
        }
    }
    Ok(())
}

/// Lamps line the main street, alternating sides, nearest the street
/// camera first.
fn add_lamps(
    b: &mut GltfBuilder,
    layout: Layout,
    params: &CityParams,
) -> Result<(), AuthoringError> {
    let street_x = layout.main_street_x();
    for lamp in 0..params.lamps {
        let side = if lamp % 2 == 0 { -1.0 } else { 1.0 };
        let light = b.add_light(&Light {
            name: Some(format!("StreetLamp.{lamp}")),
            kind: LightKind::Point,
            color: Vec3::new(1.0, 0.85, 0.65),
            intensity: 300.0,
            range: params.lamp_range,
            radius: Some(params.lamp_radius),
            group: None,
        })?;
        b.add_node(NodeDesc {
            translation: Vec3::new(
                street_x + side * 3.0,
                LAMP_HEIGHT,
                layout.along_main((lamp / 2) as f32),
            ),
            light: Some(light),
            ..NodeDesc::named(&format!("StreetLamp.{lamp}"))
        })?;
    }
    Ok(())
}

fn perspective(name: &str, yfov_degrees: f32) -> Camera {
    Camera {
        name: Some(name.into()),
        projection: Projection::Perspective {
            yfov: yfov_degrees.to_radians(),
            aspect_ratio: None,
            znear: 0.1,
            zfar: None,
        },
    }
}

/// The camera "street", looking down the main street from its end.
fn add_street_camera(b: &mut GltfBuilder, layout: Layout) -> Result<NodeId, AuthoringError> {
    let camera = b.add_camera(&perspective("street", 55.0))?;
    let street_x = layout.main_street_x();
    let eye = Vec3::new(
        street_x + 1.5,
        9.0,
        layout.centre(layout.blocks - 1) + 0.5 * PITCH,
    );
    let target = Vec3::new(street_x - 1.0, 0.0, layout.centre(layout.blocks / 2));
    b.add_node(NodeDesc {
        translation: eye,
        rotation: look_at_rotation(eye, target, Vec3::Y).unwrap_or(Quat::IDENTITY),
        camera: Some(camera),
        ..NodeDesc::named("street")
    })
}

/// Cars "Car.n", each lapping a ring of streets with the main street on
/// one side, once in the clip, anticlockwise and clockwise in turn.
fn add_cars(
    b: &mut GltfBuilder,
    layout: Layout,
    cars: u32,
) -> Result<Vec<Channel>, AuthoringError> {
    let streets = layout.blocks.saturating_sub(1);
    if cars == 0 || streets < 3 {
        return Ok(Vec::new());
    }
    let car = parts::car();
    let body = b.add_geometry(&car.body)?;
    let cabin = b.add_geometry(&car.cabin)?;
    let wheels = b.add_geometry(&car.wheels)?;
    let glass = b.add_material(&matte("CarGlass", Vec3::new(0.05, 0.06, 0.08), 0.1))?;
    let rubber = b.add_material(&matte("Rubber", Vec3::splat(0.03), 0.9))?;
    let paints = [
        ("Red", Vec3::new(0.6, 0.05, 0.04)),
        ("Blue", Vec3::new(0.05, 0.15, 0.55)),
        ("White", Vec3::splat(0.8)),
        ("Yellow", Vec3::new(0.8, 0.6, 0.05)),
    ];
    let mut meshes = Vec::new();
    for (name, colour) in paints {
        let paint = b.add_material(&matte(&format!("{name}Paint"), colour, 0.35))?;
        meshes.push(add_mesh(
            b,
            &format!("Car{name}"),
            &[(body, paint), (cabin, glass), (wheels, rubber)],
        )?);
    }
    let mut channels = Vec::new();
    for index in 0..cars {
        let width = (1 + index % 2).min(streets - 1);
        let depth = (2 + index % 3).min(streets - 1);
        let main = layout.main_street();
        let west = if index % 2 == 0 {
            main
        } else {
            main.saturating_sub(width)
        };
        let west = west.min(streets - 1 - width);
        let south = (index * 3) % (streets - depth);
        let route = Route::block_ring(
            Vec2::new(layout.street(west), layout.street(south)),
            Vec2::new(layout.street(west + width), layout.street(south + depth)),
            LANE,
            index % 2 == 0,
        );
        let (translation, rotation) = route.drive(cell_noise(index, 0, 21) * route.length(), 1);
        let node = b.add_node(NodeDesc {
            mesh: Some(meshes[index as usize % meshes.len()]),
            ..NodeDesc::named(&format!("Car.{index}"))
        })?;
        channels.push(Channel {
            target: Target::Translation(node.index()),
            sampler: translation,
        });
        channels.push(Channel {
            target: Target::Rotation(node.index()),
            sampler: rotation,
        });
    }
    Ok(channels)
}

/// Trees "Tree.n" along both sides of the main street, between the lamps:
/// each a skinned mesh node at the scene's root and a chain of three
/// joints (root, crown base, crown top) whose upper two sway.
fn add_trees(
    b: &mut GltfBuilder,
    layout: Layout,
    trees: u32,
) -> Result<Vec<Channel>, AuthoringError> {
    if trees == 0 {
        return Ok(Vec::new());
    }
    let tree = parts::tree();
    let bark = b.add_material(&matte("Bark", Vec3::new(0.3, 0.2, 0.12), 0.9))?;
    let foliage = b.add_material(&matte("Foliage", Vec3::new(0.12, 0.3, 0.1), 0.8))?;
    let leaf = b.add_material(&matte("Leaf", Vec3::new(0.25, 0.45, 0.12), 0.7))?;
    let parts = [
        (b.add_geometry(&tree.trunk)?, bark),
        (b.add_geometry(&tree.crown)?, foliage),
        (b.add_geometry(&tree.leaves)?, leaf),
    ];
    let mesh = add_mesh(b, "Tree", &parts)?;
    let [_, low, high] = parts::TREE_JOINTS;
    let street_x = layout.main_street_x();
    let mut channels = Vec::new();
    for index in 0..trees {
        let side = if index % 2 == 0 { -1.0 } else { 1.0 };
        let name = format!("Tree.{index}");
        let top = b.add_node(NodeDesc {
            translation: Vec3::Y * (high - low),
            ..NodeDesc::named(&format!("{name}.Top"))
        })?;
        let crown = b.add_node(NodeDesc {
            translation: Vec3::Y * low,
            children: vec![top],
            ..NodeDesc::named(&format!("{name}.Crown"))
        })?;
        let root = b.add_node(NodeDesc {
            translation: Vec3::new(
                street_x + side * TREE_OFFSET,
                0.0,
                layout.along_main((index / 2) as f32 + 0.5),
            ),
            rotation: Quat::from_rotation_y(std::f32::consts::TAU * cell_noise(index, 0, 31)),
            children: vec![crown],
            ..NodeDesc::named(&name)
        })?;
        let skin = b.add_skin(&Skin {
            name: Some(name.clone()),
            joints: vec![root.index(), crown.index(), top.index()],
            inverse_bind: parts::TREE_JOINTS
                .map(|height| DMat4::from_translation(DVec3::new(0.0, -f64::from(height), 0.0)))
                .to_vec(),
            skeleton: Some(root.index()),
        })?;
        b.add_node(NodeDesc {
            mesh: Some(mesh),
            skin: Some(skin),
            ..NodeDesc::named(&format!("{name}.Mesh"))
        })?;
        let wind = std::f32::consts::TAU * cell_noise(index, 0, 32);
        let axis = Vec3::new(wind.cos(), 0.0, wind.sin());
        let phase = std::f32::consts::TAU * cell_noise(index, 0, 33);
        channels.push(Channel {
            target: Target::Rotation(crown.index()),
            sampler: motion::sway(axis, 0.05, 5, phase),
        });
        channels.push(Channel {
            target: Target::Rotation(top.index()),
            sampler: motion::sway(axis, 0.1, 5, phase - 0.7),
        });
    }
    Ok(channels)
}

/// The camera "flythrough": from high over the block's near corner down
/// into the main street, along it at lamp height, and up over its far end,
/// looking back.
fn add_flythrough(b: &mut GltfBuilder, layout: Layout) -> Result<Vec<Channel>, AuthoringError> {
    let camera = b.add_camera(&perspective("flythrough", 60.0))?;
    let x = layout.main_street_x();
    let z = layout.centre(layout.blocks - 1) + 0.5 * PITCH;
    let key = |eye: [f32; 3], target: [f32; 3]| {
        (
            Vec3::new(x + eye[0], eye[1], z + eye[2]),
            Vec3::new(x + target[0], target[1], z + target[2]),
        )
    };
    let path = FlyThrough {
        keys: vec![
            key([25.0, 45.0, 30.0], [0.0, 2.0, -50.0]),
            key([8.0, 25.0, 15.0], [0.0, 2.0, -45.0]),
            key([1.5, 7.0, -15.0], [-0.5, 3.0, -55.0]),
            key([-1.5, 6.0, -55.0], [0.0, 3.0, -95.0]),
            key([1.0, 8.0, -95.0], [0.0, 3.0, -135.0]),
            key([2.0, 60.0, -150.0], [20.0, 0.0, -60.0]),
        ],
    };
    let (translation, rotation) = path.samplers();
    let node = b.add_node(NodeDesc {
        translation: path.keys[0].0,
        rotation: look_at_rotation(path.keys[0].0, path.keys[0].1, Vec3::Y)
            .unwrap_or(Quat::IDENTITY),
        camera: Some(camera),
        ..NodeDesc::named("flythrough")
    })?;
    Ok(vec![
        Channel {
            target: Target::Translation(node.index()),
            sampler: translation,
        },
        Channel {
            target: Target::Rotation(node.index()),
            sampler: rotation,
        },
    ])
}
