//! Omega(i, P) for eight lights at a time. Formulas (1) and (2) both
//! evaluate the light's falloff and the BRDF at P for every light that
//! reaches P — dozens in a street of lamps. One light at a time that was the
//! largest single cost of a light-mesh frame after the masks were cheap
//! (a chain of square roots and divisions per light, ≈ 40 ns); across eight
//! lights in SIMD lanes the same arithmetic costs little more than one.
//!
//! [`ShadingPoint::omega`](super::surface::ShadingPoint) stays the scalar,
//! obviously-right twin (the Monte Carlo lamp reference uses it, with a
//! sampled lamp point instead of the light's centre); a test checks that
//! every lane agrees with it for every kind of light.

use glam::Vec3;
use wide::f32x8;

use super::brdf::PointBrdf;
use super::lanes::{dot, each3, splat3, Lanes3};
use super::light::{LightSource, RenderLight};
use super::surface::ShadingPoint;

/// Lights per block: the lanes of one SIMD evaluation.
pub const LANES: usize = 8;

/// A frame's lights, regrouped by eights into SIMD lanes. Every kind of
/// light goes through the same arithmetic: a directional light is a
/// "position" one unit away along its direction with no falloff, a light
/// without a range has an infinite one, and a light without a cone has one
/// that lets everything through; padding lanes have no power.
#[derive(Clone, Debug, Default)]
pub struct LightLanes {
    lights: Vec<RenderLight>,
    blocks: Vec<LightBlock>,
}

/// The fields of [`OmegaLight`] for eight lights, a lane each.
#[derive(Clone, Copy, Debug)]
struct LightBlock {
    origin: Lanes3,
    /// All bits set in directional lanes.
    directional: f32x8,
    power: Lanes3,
    range_squared: f32x8,
    axis: Lanes3,
    cos_outer: f32x8,
    cos_inner: f32x8,
    /// Whether some lane has a range, and whether some lane is a spot:
    /// where none does, the range window and the cone are 1 in every lane
    /// that can reach a point, and their divisions are skipped
    /// ([`LightLanes::arrival`]).
    ranged: bool,
    coned: bool,
}

impl LightLanes {
    pub fn new(lights: &[RenderLight]) -> LightLanes {
        let blocks = lights
            .chunks(LANES)
            .map(|chunk| {
                let mut lanes = [OmegaLight::PADDING; LANES];
                for (lane, light) in lanes.iter_mut().zip(chunk) {
                    *lane = OmegaLight::from(light);
                }
                let lane =
                    |value: &dyn Fn(&OmegaLight) -> f32| f32x8::new(lanes.map(|l| value(&l)));
                let lane3 = |value: &dyn Fn(&OmegaLight) -> Vec3| {
                    [0, 1, 2].map(|axis| lane(&|light| value(light)[axis]))
                };
                LightBlock {
                    origin: lane3(&|light| light.origin),
                    directional: lane(&|light| all_bits(light.directional)),
                    power: lane3(&|light| light.power),
                    range_squared: lane(&|light| light.range_squared),
                    axis: lane3(&|light| light.axis),
                    cos_outer: lane(&|light| light.cos_outer),
                    cos_inner: lane(&|light| light.cos_inner),
                    ranged: lanes.iter().any(|light| light.range_squared.is_finite()),
                    coned: lanes
                        .iter()
                        .any(|light| light.cos_outer != OmegaLight::PADDING.cos_outer),
                }
            })
            .collect();
        LightLanes {
            lights: lights.to_vec(),
            blocks,
        }
    }

    /// The lights, in the order of their lanes.
    pub fn lights(&self) -> &[RenderLight] {
        &self.lights
    }

    /// Blocks of [`LANES`] lights: light i is lane i % 8 of block i / 8.
    pub fn blocks(&self) -> usize {
        self.blocks.len()
    }

    /// Omega of the lights of `block` at the point.
    #[inline]
    pub fn omega(&self, point: &PointLanes, block: usize) -> OmegaBlock {
        self.arrival(point, block).omega(point)
    }

    /// What the lights of `block` send towards the point, as
    /// `RenderLight::incidence` and `ShadingPoint::reaching` compute it:
    /// which lights reach it ([`Arrival::reaching`]) and their Omega
    /// ([`Arrival::omega`]) from one evaluation, for the light-mesh demand
    /// that asks for both. Always
    /// inlined: returned out of line, its eight-lane struct went back
    /// through memory and cost a fifth of the lanes' time.
    #[inline(always)]
    pub fn arrival(&self, point: &PointLanes, block: usize) -> Arrival {
        let light = &self.blocks[block];
        let zero = f32x8::splat(0.0);
        let one = f32x8::splat(1.0);

        // Towards the light and the inverse-square falloff with glTF's
        // range window.
        let to_light = each3(|axis| {
            light.directional.select(
                light.origin[axis],
                light.origin[axis] - point.position[axis],
            )
        });
        let distance_squared = light.directional.select(one, dot(to_light, to_light));
        let window = if light.ranged {
            let ratio = distance_squared / light.range_squared;
            let window = (one - ratio * ratio).max(zero).min(one);
            window * window
        } else {
            // range² = ∞ in every lane: the ratio is 0 and the window 1,
            // except where distance² is ∞ or NaN, where the window is 0
            // but window / distance² is the same either way.
            one
        };
        let length = distance_squared.sqrt();
        let direction = each3(|axis| to_light[axis] / length);
        // glTF's spot falloff, a squared smooth ramp between the cones (a
        // hard edge where they coincide).
        let cone = if light.coned {
            let cos_angle = -dot(direction, light.axis);
            let ramp = ((cos_angle - light.cos_outer) / (light.cos_inner - light.cos_outer))
                .max(zero)
                .min(one);
            light.cos_inner.simd_le(light.cos_outer).select(
                cos_angle.simd_gt(light.cos_outer).select(one, zero),
                ramp * ramp,
            )
        } else {
            // No cone in any lane: the ramp is 2, clamped to 1, wherever
            // the direction is finite. Where it is not, distance² is 0 (the
            // light reaches nothing there) or not finite (the falloff is 0
            // or NaN either way).
            one
        };
        let falloff = window / distance_squared * cone;
        let irradiance = each3(|c| light.power[c] * falloff);

        let cos_theta = dot(point.shading_normal, direction);
        let reaches = distance_squared.simd_gt(zero)
            & irradiance[0]
                .max(irradiance[1])
                .max(irradiance[2])
                .simd_gt(zero)
            & dot(point.geometric_normal, direction).simd_gt(zero)
            & cos_theta.simd_gt(zero);
        Arrival {
            direction,
            irradiance,
            cos_theta,
            reaches,
        }
    }
}

/// One light as Omega's arithmetic takes it, one lane's worth of a
/// [`LightBlock`]: every kind of light in the same fields, so the same
/// operations serve all of them (and the GPU's direct-light pass, which
/// uploads these).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OmegaLight {
    /// Position of a point or spot light; unit direction towards a
    /// directional one.
    pub origin: Vec3,
    pub directional: bool,
    /// Colour × intensity.
    pub power: Vec3,
    /// range², infinite where the light has none (and for directional
    /// lights).
    pub range_squared: f32,
    /// The spot's unit axis; zero for other lights, so every direction is
    /// at cos 0 from it, inside the open cone below.
    pub axis: Vec3,
    /// cos of the outer and inner cone angles: −2 and −1 where there is no
    /// cone, so the smooth ramp gives exactly 1.
    pub cos_outer: f32,
    pub cos_inner: f32,
}

impl OmegaLight {
    /// What fills the lanes of a block past the last light: no power.
    pub const PADDING: OmegaLight = OmegaLight {
        origin: Vec3::ZERO,
        directional: false,
        power: Vec3::ZERO,
        range_squared: f32::INFINITY,
        axis: Vec3::ZERO,
        cos_outer: -2.0,
        cos_inner: -1.0,
    };
}

impl From<&RenderLight> for OmegaLight {
    fn from(light: &RenderLight) -> OmegaLight {
        let open = OmegaLight::PADDING;
        let positional = |position: Vec3| OmegaLight {
            origin: position,
            power: light.power,
            range_squared: light.range.map_or(f32::INFINITY, |range| range * range),
            ..open
        };
        match light.source {
            LightSource::Point { position } => positional(position),
            LightSource::Spot {
                position,
                axis,
                cos_outer,
                cos_inner,
            } => OmegaLight {
                axis,
                cos_outer,
                cos_inner,
                ..positional(position)
            },
            LightSource::Directional { towards } => OmegaLight {
                origin: towards,
                directional: true,
                power: light.power,
                ..open
            },
        }
    }
}

/// Light arriving at a point from eight lights, visibility aside.
pub struct Arrival {
    /// Unit directions towards the lights.
    direction: Lanes3,
    /// Irradiance on a surface facing each light.
    irradiance: Lanes3,
    /// Cosine with the shading normal.
    cos_theta: f32x8,
    /// All bits set where the light reaches the point.
    reaches: f32x8,
}

impl Arrival {
    /// Bit per lane: the light can send something to the point,
    /// visibility aside (in range, inside its cone, above both the
    /// geometric and the shading horizon). The light-mesh demand stage
    /// asks it of every point and light.
    #[inline(always)]
    pub fn reaching(&self) -> u8 {
        self.reaches.to_bitmask() as u8
    }

    /// Omega of the eight lights at `point`, the point this arrived at.
    #[inline(always)]
    pub fn omega(&self, point: &PointLanes) -> OmegaBlock {
        let zero = f32x8::splat(0.0);
        let reflectance = point.brdf.evaluate_lanes(self.direction);
        let value = each3(|c| reflectance[c] * self.irradiance[c] * self.cos_theta);
        let brings_light = self.reaches & value[0].max(value[1]).max(value[2]).simd_gt(zero);
        OmegaBlock {
            value: each3(|c| brings_light.select(value[c], zero).to_array()),
            reaching: brings_light.to_bitmask() as u8,
        }
    }
}

/// The per-point inputs of [`LightLanes::omega`], prepared once.
pub struct PointLanes {
    position: Lanes3,
    geometric_normal: Lanes3,
    shading_normal: Lanes3,
    brdf: PointBrdf,
}

impl PointLanes {
    pub fn new(point: &ShadingPoint) -> PointLanes {
        PointLanes {
            position: splat3(point.position),
            geometric_normal: splat3(point.geometric_normal),
            shading_normal: splat3(point.shading_normal),
            brdf: point.brdf(),
        }
    }
}

/// Omega of eight lights at one point.
#[derive(Clone, Copy, Debug)]
pub struct OmegaBlock {
    /// r, g, b per lane.
    value: [[f32; LANES]; 3],
    /// Bit per lane: the light brings something to the point (the lanes
    /// [`ShadingPoint::omega`] would answer Some for).
    pub reaching: u8,
}

impl OmegaBlock {
    /// Omega of lane `lane`, zero where the light brings nothing.
    #[inline]
    pub fn get(&self, lane: usize) -> Vec3 {
        Vec3::new(
            self.value[0][lane],
            self.value[1][lane],
            self.value[2][lane],
        )
    }
}

/// A lane with every bit set (true) or none (false), as comparisons make.
fn all_bits(flag: bool) -> f32 {
    f32::from_bits(if flag { u32::MAX } else { 0 })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::render::material::SurfaceMaterial;
    use glam::{DMat4, DQuat, DVec3};

    fn material(metallic: f32, roughness: f32, transmission: f32) -> SurfaceMaterial {
        SurfaceMaterial {
            base_color: Vec3::new(0.8, 0.6, 0.4),
            metallic,
            roughness,
            specular: 1.0,
            transmission,
            ior: 1.5,
            emissive: Vec3::ZERO,
        }
    }

    fn point(material: SurfaceMaterial, normal: Vec3) -> ShadingPoint {
        let view = Vec3::new(0.3, 0.8, -0.2).normalize();
        ShadingPoint {
            sample: 0,
            weight: Vec3::ONE,
            depth: 0,
            position: Vec3::new(0.25, 0.0, -0.5),
            geometric_normal: Vec3::Y,
            shading_normal: normal,
            front_face: true,
            view,
            material,
        }
    }

    /// Lights of every kind around the point: near and far, with and
    /// without range (some beyond it), spots aimed at it and away, below
    /// the horizon, grazing, and directional ones.
    fn lights() -> Vec<RenderLight> {
        use crate::scene::{Light, LightKind};
        let mut lights = Vec::new();
        for i in 0..21 {
            let angle = i as f64 * 0.7;
            let height = [3.0, 0.5, -1.0, 1e-4, 8.0][i % 5];
            let at = DVec3::new(angle.cos() * 2.0, height, angle.sin() * 3.0);
            let kind = match i % 4 {
                0 | 1 => LightKind::Point,
                2 => LightKind::Spot {
                    inner_cone: [0.6, 0.1, 0.3][i % 3],
                    outer_cone: 0.6,
                },
                _ => LightKind::Directional,
            };
            let light = Light {
                name: None,
                kind,
                color: Vec3::new(1.0, 0.5 + 0.02 * i as f32, 0.25),
                intensity: 1.0 + i as f32,
                range: (i % 3 == 1).then_some(2.0 + i as f32 * 0.3),
                radius: None,
                group: None,
            };
            // Spots and directional lights look down −Z of their node:
            // aim them at the point, or away.
            let towards_point = (DVec3::new(0.25, 0.0, -0.5) - at).normalize();
            let aim = DMat4::from_rotation_translation(
                DQuat::from_rotation_arc(DVec3::NEG_Z, towards_point),
                at,
            );
            let node = if i % 5 == 3 {
                DMat4::from_translation(at)
            } else {
                aim
            };
            lights.push(RenderLight::place(&light, node, DVec3::ZERO, 0.0));
        }
        lights
    }

    #[test]
    fn every_lane_agrees_with_the_scalar_omega() {
        let lights = lights();
        let lanes = LightLanes::new(&lights);
        assert_eq!(lanes.blocks(), 3);
        let materials = [
            material(0.0, 0.5, 0.0),
            material(1.0, 0.3, 0.0),
            material(0.4, 0.05, 0.5),
        ];
        let mut reaching = 0;
        for material in materials {
            for normal in [Vec3::Y, Vec3::new(0.2, 0.9, 0.1).normalize()] {
                let point = point(material, normal);
                let at = PointLanes::new(&point);
                for (index, light) in lights.iter().enumerate() {
                    let block = lanes.omega(&at, index / LANES);
                    let lane = index % LANES;
                    assert_eq!(
                        lanes.arrival(&at, index / LANES).reaching() >> lane & 1 == 1,
                        point.reaching(light).is_some(),
                        "light {index} reaching"
                    );
                    let expected = point.omega(light);
                    assert_eq!(
                        block.reaching >> lane & 1 == 1,
                        expected.is_some(),
                        "light {index}"
                    );
                    let found = block.get(lane);
                    let expected = expected.unwrap_or(Vec3::ZERO);
                    reaching += (expected != Vec3::ZERO) as usize;
                    assert!(
                        (found - expected).abs().max_element() <= 1e-6 * expected.max_element(),
                        "light {index}: {found} against {expected}"
                    );
                }
            }
        }
        assert!(reaching > 30, "too few lights reach the point: {reaching}");
    }

    /// Lights without a range or a cone, as a street's lamps mostly are,
    /// placed where the skipped window and cone would have mattered if
    /// anywhere: on the point itself, beyond f32's range of squared
    /// distances, near and far, below the horizon, and directional ones.
    #[test]
    fn blocks_without_ranges_or_cones_skip_them_to_the_same_bits() {
        use crate::scene::{Light, LightKind};
        let point_at = Vec3::new(0.25, 0.0, -0.5);
        let places = [
            point_at,
            Vec3::new(3e19, 1e19, 0.0),
            Vec3::new(0.25, 1e-30, -0.5),
            Vec3::new(1.0, 2.0, 3.0),
            Vec3::new(-40.0, 0.5, 7.0),
            Vec3::new(2.0, -1.0, 0.0),
            Vec3::new(0.0, 1e-4, 5.0),
        ];
        let lamp = |kind, intensity| Light {
            name: None,
            kind,
            color: Vec3::new(1.0, 0.7, 0.2),
            intensity,
            range: None,
            radius: None,
            group: None,
        };
        let mut lights: Vec<RenderLight> = (places.iter().enumerate())
            .map(|(i, &at)| {
                let node = DMat4::from_translation(at.as_dvec3());
                RenderLight::place(
                    &lamp(LightKind::Point, 1.0 + i as f32),
                    node,
                    DVec3::ZERO,
                    0.0,
                )
            })
            .collect();
        let sun = lamp(LightKind::Directional, 3.0);
        let down = DQuat::from_rotation_arc(DVec3::NEG_Z, DVec3::new(0.3, -1.0, 0.2).normalize());
        lights.push(RenderLight::place(
            &sun,
            DMat4::from_quat(down),
            DVec3::ZERO,
            0.0,
        ));
        let skipping = LightLanes::new(&lights);
        assert!(skipping
            .blocks
            .iter()
            .all(|block| !block.ranged && !block.coned));
        let mut every_term = skipping.clone();
        for block in &mut every_term.blocks {
            (block.ranged, block.coned) = (true, true);
        }
        let bits = |block: &OmegaBlock| block.value.map(|channel| channel.map(f32::to_bits));
        let mut reached = 0;
        for position in places
            .into_iter()
            .chain([Vec3::new(1e19, 0.0, 0.0), Vec3::NAN])
        {
            for normal in [Vec3::Y, Vec3::new(0.0, 0.1, 1.0).normalize()] {
                let point = ShadingPoint {
                    position,
                    ..point(material(0.3, 0.4, 0.0), normal)
                };
                let at = PointLanes::new(&point);
                let (fast, full) = (skipping.arrival(&at, 0), every_term.arrival(&at, 0));
                assert_eq!(fast.reaching(), full.reaching(), "at {position}");
                let (fast, full) = (fast.omega(&at), full.omega(&at));
                assert_eq!(fast.reaching, full.reaching, "at {position}");
                assert_eq!(bits(&fast), bits(&full), "at {position}");
                reached += fast.reaching.count_ones();
            }
        }
        assert!(reached > 20, "too few lights reach the points: {reached}");
    }

    #[test]
    fn padding_lanes_bring_nothing() {
        let lights = &lights()[..3];
        let lanes = LightLanes::new(lights);
        let point = point(material(0.0, 0.5, 0.0), Vec3::Y);
        let block = lanes.omega(&PointLanes::new(&point), 0);
        assert_eq!(block.reaching >> 3, 0);
        for lane in 3..LANES {
            assert_eq!(block.get(lane), Vec3::ZERO);
        }
    }
}
