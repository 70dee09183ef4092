//! The study scenes: four stills made to rank shadow methods by what they
//! get wrong (`lmanim study`, STUDY.md). Each stresses one case a fast soft
//! shadow can miss:
//!
//! - `box`: a box resting on a floor under a lamp of radius 0.2 m, the
//!   contact shadow, where nodes inside the box sit next to the floor
//!   points at its base;
//! - `leaves`: a canopy of leaves under a street lamp, occluders smaller
//!   than their penumbra, whose shadows a physical lamp all but dissolves;
//! - `street`: a street with 16 lamps, parked cars and bollards, many
//!   overlapping penumbrae;
//! - `wall`: a lamp grazing a long wall with pilasters, and a curb along
//!   the floor, long thin shadows at a low angle.
//!
//! `examples/make_animations.rs` writes them to `animations/study-*.gltf`
//! (see [`crate::samples`]).
//! Every solid is a closed box, wound outwards, so that "inside" is
//! well-defined.

use glam::{Quat, Vec2, Vec3};

use lmanim::scene::{Camera, Light, LightKind, Projection};

use crate::{
    look_at_rotation, matte, shapes, AuthoringError, GeometryId, GltfBuilder, MaterialId, MeshId,
    NodeDesc, Primitive,
};

/// One of the study's scenes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StudyScene {
    Box,
    Leaves,
    Street,
    Wall,
}

impl StudyScene {
    pub const ALL: [StudyScene; 4] = [
        StudyScene::Box,
        StudyScene::Leaves,
        StudyScene::Street,
        StudyScene::Wall,
    ];

    /// The scene's file stem under `animations/`.
    pub fn file_stem(self) -> &'static str {
        match self {
            StudyScene::Box => "study-box",
            StudyScene::Leaves => "study-leaves",
            StudyScene::Street => "study-street",
            StudyScene::Wall => "study-wall",
        }
    }

    /// The scene as a glTF document.
    pub fn build(self) -> Result<GltfBuilder, AuthoringError> {
        let mut set = Set::new()?;
        match self {
            StudyScene::Box => box_on_floor(&mut set)?,
            StudyScene::Leaves => leaves(&mut set)?,
            StudyScene::Street => street(&mut set)?,
            StudyScene::Wall => wall(&mut set)?,
        }
        Ok(set.builder)
    }
}

/// A builder with the materials and the unit cube every study scene uses.
struct Set {
    builder: GltfBuilder,
    cube: GeometryId,
    grey: MaterialId,
    stone: MaterialId,
    paint: MaterialId,
    leaf: MaterialId,
}

impl Set {
    fn new() -> Result<Set, AuthoringError> {
        let mut builder = GltfBuilder::new();
        let cube = builder.add_geometry(&shapes::cuboid(Vec3::splat(0.5)))?;
        let grey = builder.add_material(&matte("Grey", Vec3::splat(0.6), 0.9))?;
        let stone = builder.add_material(&matte("Stone", Vec3::new(0.55, 0.52, 0.48), 0.8))?;
        let paint = builder.add_material(&matte("Paint", Vec3::new(0.6, 0.2, 0.15), 0.5))?;
        let leaf = builder.add_material(&matte("Leaf", Vec3::new(0.2, 0.45, 0.15), 0.7))?;
        Ok(Set {
            builder,
            cube,
            grey,
            stone,
            paint,
            leaf,
        })
    }

    fn mesh(
        &mut self,
        name: &str,
        geometry: GeometryId,
        material: MaterialId,
    ) -> Result<MeshId, AuthoringError> {
        self.builder.add_mesh(
            name,
            &[Primitive {
                geometry,
                material: Some(material),
            }],
        )
    }

    /// A floor of `half_size` metres around the origin.
    fn floor(&mut self, half_size: Vec2) -> Result<(), AuthoringError> {
        let geometry = self.builder.add_geometry(&shapes::plane(half_size))?;
        let mesh = self.mesh("Floor", geometry, self.grey)?;
        self.builder.add_node(NodeDesc {
            mesh: Some(mesh),
            ..NodeDesc::named("Floor")
        })?;
        Ok(())
    }

    /// A box of `size` whose bottom face (before `rotation`) rests at
    /// height `base`, centred on `at` (x, z).
    fn block(
        &mut self,
        name: &str,
        mesh: MeshId,
        at: Vec2,
        base: f32,
        size: Vec3,
        rotation: Quat,
    ) -> Result<(), AuthoringError> {
        self.builder.add_node(NodeDesc {
            translation: Vec3::new(at.x, base + size.y / 2.0, at.y),
            rotation,
            scale: size,
            mesh: Some(mesh),
            ..NodeDesc::named(name)
        })?;
        Ok(())
    }

    /// A white point lamp of `radius` metres (`extras.radius`).
    fn lamp(
        &mut self,
        name: &str,
        at: Vec3,
        radius: f32,
        intensity: f32,
        range: Option<f32>,
    ) -> Result<(), AuthoringError> {
        let light = self.builder.add_light(&Light {
            name: Some(name.into()),
            kind: LightKind::Point,
            color: Vec3::new(1.0, 0.95, 0.85),
            intensity,
            range,
            radius: Some(radius),
            group: None,
        })?;
        self.builder.add_node(NodeDesc {
            translation: at,
            light: Some(light),
            ..NodeDesc::named(name)
        })?;
        Ok(())
    }

    /// The camera "main", 16:9, at `eye` looking at `target`.
    fn camera(&mut self, eye: Vec3, target: Vec3, yfov_degrees: f32) -> Result<(), AuthoringError> {
        let camera = self.builder.add_camera(&Camera {
            name: Some("main".into()),
            projection: Projection::Perspective {
                yfov: yfov_degrees.to_radians(),
                aspect_ratio: Some(16.0 / 9.0),
                znear: 0.05,
                zfar: Some(200.0),
            },
        })?;
        let rotation = look_at_rotation(eye, target, Vec3::Y).unwrap_or(Quat::IDENTITY);
        self.builder.add_node(NodeDesc {
            translation: eye,
            rotation,
            camera: Some(camera),
            ..NodeDesc::named("main")
        })?;
        Ok(())
    }
}

/// A box resting on a floor, lit from above and beside by a lamp of
/// radius 0.2 m: the contact case of issue "what accuracy costs".
fn box_on_floor(set: &mut Set) -> Result<(), AuthoringError> {
    set.floor(Vec2::splat(3.0))?;
    let crate_mesh = set.mesh("Box", set.cube, set.paint)?;
    set.block(
        "Box",
        crate_mesh,
        Vec2::ZERO,
        0.0,
        Vec3::new(0.6, 0.5, 0.6),
        Quat::from_rotation_y(0.35),
    )?;
    set.lamp("Lamp", Vec3::new(0.9, 1.5, 0.6), 0.2, 12.0, None)?;
    set.camera(Vec3::new(-0.4, 1.7, 2.6), Vec3::new(0.0, 0.15, 0.0), 45.0)
}

/// Leaves in a canopy between a street lamp and the pavement: each leaf is
/// far smaller than the penumbra it casts.
fn leaves(set: &mut Set) -> Result<(), AuthoringError> {
    set.floor(Vec2::splat(6.0))?;
    let pole = set.mesh("Pole", set.cube, set.stone)?;
    set.block(
        "Pole",
        pole,
        Vec2::new(-0.6, 0.0),
        0.0,
        Vec3::new(0.12, 4.2, 0.12),
        Quat::IDENTITY,
    )?;
    set.lamp("Lamp", Vec3::new(0.0, 4.0, 0.0), 0.15, 40.0, None)?;
    let leaf = set.mesh("Leaf", set.cube, set.leaf)?;
    // A deterministic scatter over an ellipsoidal crown beside the lamp.
    for i in 0..160u32 {
        let (u, v, w) = (unit(i, 1), unit(i, 2), unit(i, 3));
        let at =
            Vec3::new(0.9, 2.9, 0.0) + Vec3::new((u - 0.5) * 1.6, (v - 0.5) * 0.7, (w - 0.5) * 1.6);
        let rotation = Quat::from_rotation_y(unit(i, 4) * std::f32::consts::TAU)
            * Quat::from_rotation_x((unit(i, 5) - 0.5) * 0.8);
        set.block(
            &format!("Leaf.{i}"),
            leaf,
            Vec2::new(at.x, at.z),
            at.y,
            Vec3::new(0.12, 0.008, 0.07),
            rotation,
        )?;
    }
    set.camera(Vec3::new(-1.5, 3.0, 5.0), Vec3::new(0.9, 0.0, 0.0), 50.0)
}

/// A street 60 m long with 16 lamps on posts along both pavements, parked
/// cars, bollards and facades.
fn street(set: &mut Set) -> Result<(), AuthoringError> {
    set.floor(Vec2::new(10.0, 34.0))?;
    let facade = set.mesh("Facade", set.cube, set.stone)?;
    let car = set.mesh("Car", set.cube, set.paint)?;
    let post = set.mesh("Post", set.cube, set.grey)?;
    for (side, x) in [("West", -7.0), ("East", 7.0)] {
        set.block(
            &format!("Facade.{side}"),
            facade,
            Vec2::new(x, 0.0),
            0.0,
            Vec3::new(2.0, 9.0, 64.0),
            Quat::IDENTITY,
        )?;
    }
    for i in 0..8 {
        let z = -28.0 + 8.0 * i as f32;
        for (side, x) in [(0, -4.5f32), (1, 4.5)] {
            let name = format!("Lamp.{i}.{side}");
            set.block(
                &format!("Post.{i}.{side}"),
                post,
                Vec2::new(x * 1.1, z),
                0.0,
                Vec3::new(0.12, 4.8, 0.12),
                Quat::IDENTITY,
            )?;
            set.lamp(
                &name,
                Vec3::new(x, 4.6, z + 4.0 * side as f32),
                0.15,
                30.0,
                Some(16.0),
            )?;
        }
    }
    for i in 0..6 {
        let z = -22.0 + 8.5 * i as f32 + 1.5 * unit(i, 7);
        let x = if i % 2 == 0 { -3.2 } else { 3.2 };
        set.block(
            &format!("Car.{i}"),
            car,
            Vec2::new(x, z),
            0.25,
            Vec3::new(1.8, 1.3, 4.2),
            Quat::from_rotation_y((unit(i, 8) - 0.5) * 0.1),
        )?;
    }
    for i in 0..12 {
        let z = -25.0 + 4.6 * i as f32;
        set.block(
            &format!("Bollard.{i}"),
            post,
            Vec2::new(if i % 2 == 0 { -2.2 } else { 2.2 }, z),
            0.0,
            Vec3::new(0.2, 0.9, 0.2),
            Quat::IDENTITY,
        )?;
    }
    set.camera(Vec3::new(0.6, 2.2, 30.0), Vec3::new(0.0, 0.5, 0.0), 50.0)
}

/// A long wall with pilasters and a curb along its foot, lit by a lamp
/// close to the wall so that its light grazes both.
fn wall(set: &mut Set) -> Result<(), AuthoringError> {
    set.floor(Vec2::new(14.0, 5.0))?;
    let stone = set.mesh("Wall", set.cube, set.stone)?;
    set.block(
        "Wall",
        stone,
        Vec2::new(0.0, -1.0),
        0.0,
        Vec3::new(24.0, 3.0, 0.3),
        Quat::IDENTITY,
    )?;
    for i in 0..9 {
        let x = -10.0 + 2.5 * i as f32;
        set.block(
            &format!("Pilaster.{i}"),
            stone,
            Vec2::new(x, -0.78),
            0.0,
            Vec3::new(0.3, 2.7, 0.14),
            Quat::IDENTITY,
        )?;
    }
    let curb = set.mesh("Curb", set.cube, set.grey)?;
    set.block(
        "Curb",
        curb,
        Vec2::new(0.0, 0.9),
        0.0,
        Vec3::new(24.0, 0.15, 0.3),
        Quat::IDENTITY,
    )?;
    set.lamp("Lamp", Vec3::new(1.0, 2.2, -0.45), 0.1, 25.0, None)?;
    set.camera(Vec3::new(-6.0, 2.0, 4.0), Vec3::new(1.5, 0.5, -0.8), 50.0)
}

/// A number in [0, 1) that depends only on `index` and `salt`: a fixed
/// scatter that is the same on every platform.
fn unit(index: u32, salt: u32) -> f32 {
    let mut x = index.wrapping_mul(0x9E37_79B9) ^ salt.wrapping_mul(0x85EB_CA6B);
    x ^= x >> 16;
    x = x.wrapping_mul(0x7FEB_352D);
    x ^= x >> 15;
    x = x.wrapping_mul(0x846C_A68B);
    x ^= x >> 16;
    (x >> 8) as f32 / (1u32 << 24) as f32
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_study_scene_builds() {
        for scene in StudyScene::ALL {
            let builder = scene.build().expect("builds");
            let dir = tempfile::tempdir().unwrap();
            let path = dir.path().join(format!("{}.glb", scene.file_stem()));
            builder.write_glb(&path).unwrap();
            let loaded = lmanim::import::load(&path).unwrap();
            assert_eq!(loaded.cameras.len(), 1, "{scene:?}");
            let lamps = loaded.lights.len();
            let expected = if scene == StudyScene::Street { 16 } else { 1 };
            assert_eq!(lamps, expected, "{scene:?}");
        }
    }

    #[test]
    fn the_scatter_is_spread_over_the_unit_interval() {
        let values: Vec<f32> = (0..1000).map(|i| unit(i, 1)).collect();
        assert!(values.iter().all(|v| (0.0..1.0).contains(v)));
        let mean = values.iter().sum::<f32>() / values.len() as f32;
        assert!((mean - 0.5).abs() < 0.05, "{mean}");
    }
}
