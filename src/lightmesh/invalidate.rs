//! Invalidation between frames (ARCHITECTURE.md, "The light mesh"): a
//! (node x, light i) bit can change only if the segment [x, L_i] meets a
//! region where geometry changed, or light i itself moved. The regions are
//! the old and the new world bounds of every rigidly moved object, and for
//! a deformed one the boxes of its clusters of triangles that have a moved
//! vertex, before and after (`accel::clusters`). Camera motion, material
//! changes and light colour or intensity changes invalidate nothing.
//! Moving objects are dynamic, so they only touch the dynamic layer; a
//! moved light drops both layers of its bits.
//!
//! Testing every cached node against every region and light would cost more
//! than a frame, so space is culled first, with the regions in a tree
//! (`region_tree`) so that a few hundred small boxes cost a query little
//! more than a few large ones: each group of 8×8×8 bricks keeps the lights
//! for which the cone that some region's bounding sphere casts from the
//! light (a cylinder for a directional light) reaches the group; each
//! brick, for each of those lights that it holds a valid dynamic bit of,
//! collects the regions that the shaft from the brick to the light may
//! meet (for a directional light, whose cylinder may reach the brick); only
//! those meet the exact segment test of the brick's nodes.
//! Culling is conservative and the node test pads the regions by rounding
//! error, so a bit that may have changed is always dropped: re-computing it
//! gives the same value, which is what makes a reused frame equal a cold one.

use glam::{IVec3, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::lattice::Lattice;
use super::masks::{join, BrickValidity, BRICK_EDGE, BRICK_NODES};
use super::region_tree::RegionTree;
use super::LightMesh;
use crate::accel::shaft::Shaft;
use crate::accel::{Bounds, Ray};
use crate::bits::set_bits;
use crate::render::light::{LightSource, RenderLight};

/// Bricks along each edge of a group culled as one.
const GROUP_EDGE: i32 = 8;

/// A box of render space whose geometry changed between two frames.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ChangedRegion {
    pub min: Vec3,
    pub max: Vec3,
}

impl From<Bounds> for ChangedRegion {
    fn from(bounds: Bounds) -> ChangedRegion {
        ChangedRegion {
            min: bounds.min,
            max: bounds.max,
        }
    }
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

    pub(super) fn centre(&self) -> Vec3 {
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
        let culling = Culling::new(self.lattice, lights, regions);
        let reaching = culling.lights_reaching_groups(self.masks.brick_keys());
        let mut moved = vec![0u64; culling.words];
        for &light in moved_lights {
            moved[light / 64] |= 1 << (light % 64);
        }
        self.masks.invalidate(|brick, validity| {
            let cleared: u64 = (moved.iter().enumerate())
                .filter(|(_, &lights)| lights != 0)
                .map(|(word, &lights)| validity.clear_lights(word, lights))
                .sum();
            cleared + culling.clear_brick(brick, validity, &reaching[&group_of(brick)])
        })
    }
}

/// The group of bricks `brick` is culled with.
fn group_of(brick: IVec3) -> IVec3 {
    brick.div_euclid(IVec3::splat(GROUP_EDGE))
}

/// One frame's changed regions, padded, with what culls space against
/// them: a tree over the regions and, per light, the shadow volume of each
/// of its nodes.
struct Culling<'a> {
    lattice: Lattice,
    lights: &'a [RenderLight],
    /// Bit words per node, one bit per light.
    words: usize,
    regions: Vec<ChangedRegion>,
    tree: RegionTree,
    /// The tree's node boxes, by node index.
    node_bounds: Vec<ChangedRegion>,
    /// Per light, by tree node.
    volumes: Vec<Vec<ShadowVolume>>,
}

impl Culling<'_> {
    fn new<'a>(
        lattice: Lattice,
        lights: &'a [RenderLight],
        regions: &[ChangedRegion],
    ) -> Culling<'a> {
        let regions: Vec<ChangedRegion> = regions.iter().map(ChangedRegion::padded).collect();
        let tree = RegionTree::new(&regions);
        let node_bounds: Vec<ChangedRegion> = tree.node_bounds().copied().collect();
        let volumes = lights
            .iter()
            .map(|light| {
                (node_bounds.iter())
                    .map(|bounds| ShadowVolume::new(light, bounds))
                    .collect()
            })
            .collect();
        Culling {
            lattice,
            lights,
            words: lights.len().div_ceil(64).max(1),
            regions,
            tree,
            node_bounds,
            volumes,
        }
    }

    /// Radius of the sphere around a cube of `nodes` nodes along each
    /// edge, padded for rounding.
    fn sphere_radius(&self, nodes: i32) -> f32 {
        self.lattice.h * (nodes - 1) as f32 * 3f32.sqrt() * 0.5 * (1.0 + 1e-5)
    }

    /// Whether the shadow volume of some region from `light` may meet the
    /// sphere.
    fn reaches(&self, light: usize, centre: Vec3, radius: f32) -> bool {
        let volumes = &self.volumes[light];
        self.tree
            .reaches(|node| volumes[node].may_meet(centre, radius))
    }

    /// For each group of bricks holding one of `bricks`, the lights (bit
    /// words) for which the shadow volume of some region reaches the
    /// group's sphere.
    fn lights_reaching_groups(
        &self,
        bricks: impl Iterator<Item = IVec3>,
    ) -> FxHashMap<IVec3, Vec<u64>> {
        let mut groups: Vec<IVec3> = bricks.map(group_of).collect();
        groups.sort_unstable_by_key(|group| group.to_array());
        groups.dedup();
        let span = GROUP_EDGE * BRICK_EDGE;
        let radius = self.sphere_radius(span);
        groups
            .par_iter()
            .map(|&group| {
                let first = self.lattice.node_position(group * span);
                let last = self
                    .lattice
                    .node_position(group * span + IVec3::splat(span - 1));
                let centre = 0.5 * (first + last);
                let mut lights = vec![0u64; self.words];
                for light in 0..self.lights.len() {
                    let reaches = self.reaches(light, centre, radius);
                    lights[light / 64] |= u64::from(reaches) << (light % 64);
                }
                (group, lights)
            })
            .collect()
    }

    /// Drops the dynamic bits of `brick`'s nodes, for the lights in
    /// `reaching` (bit words), whose segment meets a region; returns how
    /// many. Only the lights of which the brick holds a valid dynamic bit
    /// (as the brick keeps count) are culled further: each takes the
    /// regions near the brick from the tree, and only those are tested.
    fn clear_brick(&self, brick: IVec3, validity: &mut BrickValidity, reaching: &[u64]) -> u64 {
        if reaching.iter().all(|&word| word == 0) {
            return 0;
        }
        let first = self.lattice.node_position(join(brick, 0));
        let last = self.lattice.node_position(join(brick, BRICK_NODES - 1));
        let mut cleared = 0;
        let mut near = Vec::new();
        for (word, &reaching) in reaching.iter().enumerate() {
            for bit in set_bits(reaching & validity.dynamic_lights(word)) {
                let light = word * 64 + bit;
                near.clear();
                self.near_regions(light, first, last, &mut near);
                if !near.is_empty() {
                    cleared += self.clear_segments(brick, validity, light, &near);
                }
            }
        }
        cleared
    }

    /// Drops the dynamic bit of `light` of each node of `brick` whose
    /// segment to the light meets one of the `near` regions; returns how
    /// many.
    fn clear_segments(
        &self,
        brick: IVec3,
        validity: &mut BrickValidity,
        light: usize,
        near: &[usize],
    ) -> u64 {
        validity.clear_dynamic_where(light / 64, (light % 64) as u32, |slot| {
            let node = self.lattice.node_position(join(brick, slot));
            let segment = SlabSegment::new(&self.lights[light].shadow_ray(node));
            near.iter()
                .any(|&region| segment.meets(&self.regions[region]))
        })
    }

    /// Appends to `near` the regions that a segment from a point of the
    /// box `first..=last` (a brick's nodes) to `light` may meet: for a
    /// positional light those that may meet the shaft from the box to it
    /// (which holds every such segment), for a directional one those whose
    /// shadow cylinder may reach the box's sphere.
    fn near_regions(&self, light: usize, first: Vec3, last: Vec3, near: &mut Vec<usize>) {
        match self.lights[light].position() {
            Some(position) => {
                let shaft = Shaft::new(first, last, position);
                let boxes = &self.node_bounds;
                self.tree.reached(
                    |node| shaft.may_meet_box(boxes[node].min, boxes[node].max),
                    near,
                );
            }
            None => {
                let (centre, radius) = (0.5 * (first + last), self.sphere_radius(BRICK_EDGE));
                let volumes = &self.volumes[light];
                self.tree
                    .reached(|node| volumes[node].may_meet(centre, radius), near);
            }
        }
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
