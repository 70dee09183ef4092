//! Invalidation between frames (DESIGN.md, "Invalidation rule"): a
//! (node x, light i) bit can change only if the segment [x, L_i] meets a
//! region where geometry changed — the old and the new world bounds of every
//! moved or deformed object — or light i itself moved. Camera motion,
//! material changes and light colour or intensity changes invalidate
//! nothing. Moving objects are dynamic, so they only touch the dynamic layer;
//! a moved light drops both layers of its bits.
//!
//! Testing every cached node against every region and light would cost more
//! than a frame, so space is culled first against the cone that a region's
//! bounding sphere casts from the light (a directional light casts a
//! cylinder): groups of 8×8×8 bricks against every (light, region) pair,
//! then each brick of a group against the pairs its group kept; only nodes
//! of bricks inside a cone get the exact segment test.
//! Culling is conservative and the node test pads the regions by rounding
//! error, so a bit that may have changed is always dropped: re-computing it
//! gives the same value, which is what makes a reused frame equal a cold one.

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::masks::{join, BRICK_EDGE, BRICK_NODES};
use super::LightMesh;
use crate::accel::Ray;
use crate::render::light::{LightSource, RenderLight};

/// Bricks along each edge of a group culled as one.
const GROUP_EDGE: i32 = 8;

/// A box of render space whose geometry changed between two frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChangedRegion {
    pub min: Vec3,
    pub max: Vec3,
}

impl ChangedRegion {
    /// The region grown by the rounding error of coordinates of its size,
    /// so that segments grazing it still count as meeting it.
    fn padded(&self) -> ChangedRegion {
        let scale =
            self.min.abs().max(self.max.abs()).max_element() + (self.max - self.min).max_element();
        let pad = Vec3::splat(16.0 * f32::EPSILON * scale);
        ChangedRegion {
            min: self.min - pad,
            max: self.max + pad,
        }
    }

    fn centre(&self) -> Vec3 {
        0.5 * (self.min + self.max)
    }

    fn radius(&self) -> f32 {
        0.5 * (self.max - self.min).length()
    }

    /// Whether `ray`'s segment (t in [0, t_max]) meets the box.
    pub fn meets(&self, ray: &Ray) -> bool {
        SlabSegment::new(ray).meets(self)
    }
}

/// A segment prepared for slab tests against many boxes: the reciprocals
/// of its direction computed once.
struct SlabSegment {
    origin: Vec3,
    inverse: Vec3,
    t_max: f32,
}

impl SlabSegment {
    fn new(ray: &Ray) -> SlabSegment {
        SlabSegment {
            origin: ray.origin,
            inverse: ray.direction.recip(),
            t_max: ray.t_max,
        }
    }

    /// Whether the segment meets the box (closed intervals). An axis the
    /// segment runs parallel to has an infinite reciprocal: the slab
    /// either holds the origin (the interval is everything) or not (empty).
    fn meets(&self, region: &ChangedRegion) -> bool {
        let mut t_near = 0.0f32;
        let mut t_far = self.t_max;
        for axis in 0..3 {
            let (origin, inverse) = (self.origin[axis], self.inverse[axis]);
            let (low, high) = (region.min[axis], region.max[axis]);
            if inverse.is_infinite() {
                if origin < low || origin > high {
                    return false;
                }
                continue;
            }
            let (a, b) = ((low - origin) * inverse, (high - origin) * inverse);
            t_near = t_near.max(a.min(b));
            t_far = t_far.min(a.max(b));
            if t_near > t_far {
                return false;
            }
        }
        true
    }
}

/// The set of points whose segment to a light may meet a region: for a
/// positional light the cone from the light around the region's bounding
/// sphere, for a directional one the cylinder swept from the sphere against
/// the light's direction.
#[derive(Clone, Copy, Debug)]
enum ShadowVolume {
    /// The light is inside the region's sphere: everything may be affected.
    Everywhere,
    Cone {
        apex: Vec3,
        axis: Vec3,
        sin_half_angle: f32,
        cos_half_angle: f32,
    },
    Cylinder {
        centre: Vec3,
        towards: Vec3,
        radius: f32,
    },
}

impl ShadowVolume {
    fn new(light: &RenderLight, region: &ChangedRegion) -> ShadowVolume {
        let (centre, radius) = (region.centre(), region.radius());
        match light.source {
            LightSource::Directional { towards } => ShadowVolume::Cylinder {
                centre,
                towards,
                radius,
            },
            LightSource::Point { position } | LightSource::Spot { position, .. } => {
                let to_region = centre - position;
                let distance = to_region.length();
                if distance <= radius {
                    return ShadowVolume::Everywhere;
                }
                let sin_half_angle = radius / distance;
                ShadowVolume::Cone {
                    apex: position,
                    axis: to_region / distance,
                    sin_half_angle,
                    cos_half_angle: (1.0 - sin_half_angle * sin_half_angle).sqrt(),
                }
            }
        }
    }

    /// Whether a sphere (a brick's bounds) may meet the volume.
    fn may_meet(&self, centre: Vec3, radius: f32) -> bool {
        match *self {
            ShadowVolume::Everywhere => true,
            ShadowVolume::Cone {
                apex,
                axis,
                sin_half_angle,
                cos_half_angle,
            } => {
                // In the plane of the axis and the sphere's centre, at `along`
                // the axis and `across` from it, the centre's distance from
                // the cone's side line is `across·cos − along·sin` (negative
                // inside); past the apex the apex itself is nearest. The
                // sphere may meet the cone when that distance is within its
                // radius (padded for the rounding of these few products).
                let offset = centre - apex;
                let along = offset.dot(axis);
                let across = (offset.length_squared() - along * along).max(0.0).sqrt();
                let slack = radius + 1e-5 * (offset.abs().max_element() + radius);
                let beside = across * cos_half_angle - along * sin_half_angle <= slack;
                let ahead = across * sin_half_angle + along * cos_half_angle >= 0.0;
                beside && (ahead || offset.length() <= slack)
            }
            ShadowVolume::Cylinder {
                centre: region,
                towards,
                radius: region_radius,
            } => {
                // Points whose ray towards the light passes the sphere: the
                // region lies ahead along `towards`, within the radii.
                let offset = region - centre;
                let along = offset.dot(towards);
                let across = (offset - along * towards).length();
                along >= -(radius + region_radius) && across <= radius + region_radius
            }
        }
    }
}

impl LightMesh {
    /// Drops the bits that geometry changes in `regions` and the moves of
    /// `moved_lights` can have changed; returns how many valid bits were
    /// dropped. `lights` are the lights of the new frame.
    pub fn invalidate(
        &mut self,
        regions: &[ChangedRegion],
        moved_lights: &[usize],
        lights: &[RenderLight],
    ) -> u64 {
        if regions.is_empty() && moved_lights.is_empty() {
            return 0;
        }
        let padded: Vec<ChangedRegion> = regions.iter().map(ChangedRegion::padded).collect();
        let volumes: Vec<Vec<ShadowVolume>> = lights
            .iter()
            .map(|light| {
                padded
                    .iter()
                    .map(|region| ShadowVolume::new(light, region))
                    .collect()
            })
            .collect();
        let lattice = self.lattice;
        let words = lights.len().div_ceil(64).max(1);
        let brick_radius = lattice.h * (BRICK_EDGE - 1) as f32 * 3f32.sqrt() * 0.5 * (1.0 + 1e-5);
        let group_radius =
            lattice.h * (GROUP_EDGE * BRICK_EDGE - 1) as f32 * 3f32.sqrt() * 0.5 * (1.0 + 1e-5);
        let sphere_of = |first: IVec3, last: IVec3| {
            0.5 * (lattice.node_position(first) + lattice.node_position(last))
        };
        // The (light, region) pairs whose volume may reach each group.
        let mut groups: Vec<IVec3> = self
            .masks
            .brick_keys()
            .map(|brick| brick.div_euclid(IVec3::splat(GROUP_EDGE)))
            .collect();
        groups.sort_unstable_by_key(|group| group.to_array());
        groups.dedup();
        let group_span = GROUP_EDGE * BRICK_EDGE;
        let reaching: FxHashMap<IVec3, Vec<(usize, usize)>> = groups
            .par_iter()
            .map(|&group| {
                let first = group * group_span;
                let centre = sphere_of(first, first + IVec3::splat(group_span - 1));
                let pairs = volumes
                    .iter()
                    .enumerate()
                    .flat_map(|(light, of_light)| {
                        of_light
                            .iter()
                            .enumerate()
                            .filter(move |(_, volume)| volume.may_meet(centre, group_radius))
                            .map(move |(region, _)| (light, region))
                    })
                    .collect();
                (group, pairs)
            })
            .collect();
        self.masks.invalidate(|brick, validity| {
            let mut cleared = 0;
            for &light in moved_lights {
                for slot in 0..BRICK_NODES {
                    cleared += validity.clear_both(slot, light / 64, 1 << (light % 64));
                }
            }
            let pairs = &reaching[&brick.div_euclid(IVec3::splat(GROUP_EDGE))];
            if pairs.is_empty() {
                return cleared;
            }
            let centre = sphere_of(join(brick, 0), join(brick, BRICK_NODES - 1));
            // The regions each light's volume brings near this brick, and
            // per word the lights that have any: one pass over the slots
            // then tests only their valid bits.
            let mut near: Vec<(usize, &ChangedRegion)> = Vec::new();
            let mut near_lights = vec![0u64; words];
            for &(light, region) in pairs {
                if volumes[light][region].may_meet(centre, brick_radius) {
                    near.push((light, &padded[region]));
                    near_lights[light / 64] |= 1 << (light % 64);
                }
            }
            if near.is_empty() {
                return cleared;
            }
            for slot in 0..BRICK_NODES {
                if (0..words)
                    .all(|word| validity.dynamic_valid(slot, word) & near_lights[word] == 0)
                {
                    continue;
                }
                let node = lattice.node_position(join(brick, slot));
                for (word, &candidates) in near_lights.iter().enumerate() {
                    let mut bits = validity.dynamic_valid(slot, word) & candidates;
                    while bits != 0 {
                        let bit = bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        let index = word * 64 + bit;
                        let segment = SlabSegment::new(&lights[index].shadow_ray(node));
                        // `near` follows `pairs`, sorted by light.
                        let first = near.partition_point(|&(light, _)| light < index);
                        let meets = near[first..]
                            .iter()
                            .take_while(|&&(light, _)| light == index)
                            .any(|(_, region)| segment.meets(region));
                        if meets {
                            cleared += validity.clear_dynamic(slot, word, 1 << bit);
                        }
                    }
                }
            }
            cleared
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn region(min: Vec3, max: Vec3) -> ChangedRegion {
        ChangedRegion { min, max }
    }

    #[test]
    fn segments_meet_boxes_they_cross_and_touch() {
        let unit = region(Vec3::ZERO, Vec3::ONE);
        let across = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(3.0, 0.0, 0.0), 1.0);
        assert!(unit.meets(&across));
        let short = Ray::new(Vec3::new(-1.0, 0.5, 0.5), Vec3::new(0.5, 0.0, 0.0), 1.0);
        assert!(!unit.meets(&short), "the segment ends before the box");
        let along_face = Ray::new(Vec3::new(-1.0, 1.0, 0.5), Vec3::new(3.0, 0.0, 0.0), 1.0);
        assert!(unit.meets(&along_face), "grazing a face counts");
        let parallel_outside = Ray::new(Vec3::new(-1.0, 1.5, 0.5), Vec3::new(3.0, 0.0, 0.0), 1.0);
        assert!(!unit.meets(&parallel_outside));
        let infinite = Ray::new(Vec3::new(0.5, -5.0, 0.5), Vec3::Y, f32::INFINITY);
        assert!(unit.meets(&infinite));
    }

    /// The brick cull never rejects a sphere that holds a point whose
    /// segment to the light meets the region.
    #[test]
    fn cones_hold_every_point_whose_segment_meets_the_region() {
        let light = RenderLight {
            source: LightSource::Point {
                position: Vec3::new(0.0, 5.0, 0.0),
            },
            power: Vec3::ONE,
            range: None,
            lamp_radius: 0.0,
        };
        let car = region(Vec3::new(3.0, 0.0, -1.0), Vec3::new(7.0, 1.5, 1.0));
        let volume = ShadowVolume::new(&light, &car);
        let mut inside = 0;
        for i in 0..40 {
            for j in 0..40 {
                let x = Vec3::new(
                    i as f32 * 0.75 - 5.0,
                    0.3 + (j % 5) as f32 * 0.4,
                    j as f32 * 0.5 - 10.0,
                );
                if car.meets(&light.shadow_ray(x)) {
                    inside += 1;
                    assert!(volume.may_meet(x, 0.0), "{x} is in the car's shadow volume");
                    assert!(volume.may_meet(x + Vec3::splat(0.3), 0.6));
                }
            }
        }
        assert!(inside > 10);
        // Far from the cone, a brick is culled.
        assert!(!volume.may_meet(Vec3::new(-20.0, 0.0, 0.0), 1.0));
    }
}
