//! Light-mesh masks kept across frames equal masks computed cold: after a
//! dynamic object moves (a truck passing between a lamp and a facade more
//! than 15 m from the truck), deforms (a sheet whose one half a morph
//! target bends) or a light moves, invalidation drops exactly enough bits
//! that re-filling them reproduces a cold fill, bit for bit.

mod common;

use glam::{Affine3A, IVec3, Vec3};
use lmanim::accel::{Bounds, World, WorldObject};
use lmanim::lightmesh::demand::{BrickDemand, Demand};
use lmanim::lightmesh::invalidate::ChangedRegion;
use lmanim::lightmesh::lattice::Lattice;
use lmanim::lightmesh::masks::{join, split, BRICK_NODES};
use lmanim::lightmesh::{LightMesh, LightMeshStats};
use lmanim::render::light::{LightSource, RenderLight};

const H: f32 = 0.25;

fn quad(corners: [Vec3; 4]) -> (Vec<Vec3>, Vec<[u32; 3]>) {
    (corners.to_vec(), vec![[0, 1, 2], [0, 2, 3]])
}

fn cube() -> (Vec<Vec3>, Vec<[u32; 3]>) {
    let p: Vec<Vec3> = (0..8)
        .map(|i| {
            Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2 & 1) as f32) - Vec3::splat(0.5)
        })
        .collect();
    let faces = [
        [0, 1, 3, 2],
        [4, 6, 7, 5],
        [0, 4, 5, 1],
        [2, 3, 7, 6],
        [0, 2, 6, 4],
        [1, 5, 7, 3],
    ];
    let triangles = faces
        .iter()
        .flat_map(|f| [[f[0], f[1], f[2]], [f[0], f[2], f[3]]])
        .collect();
    (p, triangles)
}

fn lamp(position: Vec3) -> RenderLight {
    RenderLight {
        source: LightSource::Point { position },
        power: Vec3::splat(100.0),
        range: None,
        lamp_radius: 0.2,
    }
}

/// A truck (4 × 3.5 × 2 m) standing at `x` on the street.
fn truck_at(x: f32) -> Affine3A {
    Affine3A::from_scale_rotation_translation(
        Vec3::new(2.0, 3.5, 2.0),
        glam::Quat::IDENTITY,
        Vec3::new(x, 1.75, 0.0),
    )
}

struct Street {
    ground: (Vec<Vec3>, Vec<[u32; 3]>),
    facade: (Vec<Vec3>, Vec<[u32; 3]>),
    truck: (Vec<Vec3>, Vec<[u32; 3]>),
}

impl Street {
    fn new() -> Street {
        Street {
            ground: quad([
                Vec3::new(-50.0, 0.0, -50.0),
                Vec3::new(-50.0, 0.0, 50.0),
                Vec3::new(50.0, 0.0, 50.0),
                Vec3::new(50.0, 0.0, -50.0),
            ]),
            // A facade at x = 30 facing the street (−X).
            facade: quad([
                Vec3::new(30.0, 0.0, -10.0),
                Vec3::new(30.0, 0.0, 10.0),
                Vec3::new(30.0, 12.0, 10.0),
                Vec3::new(30.0, 12.0, -10.0),
            ]),
            truck: cube(),
        }
    }

    fn world(&self, truck: Affine3A) -> World {
        World::build(&[
            object(&self.ground, Affine3A::IDENTITY, false),
            object(&self.facade, Affine3A::IDENTITY, false),
            object(&self.truck, truck, true),
        ])
    }
}

fn object(
    mesh: &(Vec<Vec3>, Vec<[u32; 3]>),
    to_render: Affine3A,
    dynamic: bool,
) -> WorldObject<'_> {
    WorldObject {
        positions: &mesh.0,
        triangles: &mesh.1,
        to_render,
        dynamic,
    }
}

/// Every node of the bricks covering the band in front of the facade, all
/// lights needed.
fn facade_demand(lattice: &Lattice, lights: usize) -> Demand {
    let mut bricks: Vec<IVec3> = Vec::new();
    for (x, y, z) in [
        (28.5f32, 0.5f32, -1.5f32),
        (29.5, 0.5, 1.5),
        (28.5, 3.0, 0.0),
        (29.5, 3.0, -1.5),
    ] {
        let node = ((Vec3::new(x, y, z) - lattice.origin) / lattice.h)
            .floor()
            .as_ivec3();
        bricks.push(split(node).0);
    }
    bricks.sort_by_key(|b| b.to_array());
    bricks.dedup();
    let words = lights.div_ceil(64);
    let all = if lights >= 64 {
        u64::MAX
    } else {
        (1u64 << lights) - 1
    };
    Demand {
        bricks: bricks
            .into_iter()
            .map(|brick| BrickDemand {
                brick,
                needed: vec![all; BRICK_NODES * words].into_boxed_slice(),
            })
            .collect(),
        reach: Vec::new(),
        faint: Vec::new(),
        words,
    }
}

fn mesh(lights: usize) -> LightMesh {
    LightMesh::new(Lattice::new(H), 2.5, lights, 1 << 30)
}

/// A light mesh filled cold for `demand`, with what the fill did.
fn filled(demand: &Demand, lights: &[RenderLight], world: &World) -> (LightMesh, LightMeshStats) {
    let mut mesh = mesh(lights.len());
    let mut stats = LightMeshStats::default();
    mesh.fill(demand, lights, world, &mut stats).unwrap();
    (mesh, stats)
}

/// Visibility of every demanded (node, light) pair.
fn masks_of(mesh: &LightMesh, demand: &Demand, lights: usize) -> Vec<Option<bool>> {
    demand
        .bricks
        .iter()
        .flat_map(|brick| (0..BRICK_NODES).map(move |slot| join(brick.brick, slot)))
        .flat_map(|node| (0..lights).map(move |light| mesh.masks().get(node, light)))
        .collect()
}

/// Fills what invalidation dropped from `reused`, checks the masks equal a
/// cold fill of the same world and lights, bit for bit, and returns them
/// with what the refill did.
fn refill_equals_cold(
    reused: &mut LightMesh,
    demand: &Demand,
    lights: &[RenderLight],
    world: &World,
) -> (Vec<Option<bool>>, LightMeshStats) {
    let mut refill = LightMeshStats::default();
    reused.fill(demand, lights, world, &mut refill).unwrap();
    let (cold, _) = filled(demand, lights, world);
    let after = masks_of(reused, demand, lights.len());
    assert_eq!(
        after,
        masks_of(&cold, demand, lights.len()),
        "reused masks equal cold ones"
    );
    (after, refill)
}

#[test]
fn a_truck_passing_far_from_the_facade_invalidates_exactly_its_shadow() {
    let street = Street::new();
    // Lamp 0 lights the facade across the street; lamp 1 stands beside it.
    let lights = vec![
        lamp(Vec3::new(0.0, 5.0, 0.0)),
        lamp(Vec3::new(27.0, 5.0, 8.0)),
    ];
    let lattice = Lattice::new(H);
    let demand = facade_demand(&lattice, lights.len());

    let parked = truck_at(-40.0);
    let passing = truck_at(11.0);
    let mut world = street.world(parked);
    let (mut reused, _) = filled(&demand, &lights, &world);
    let before = masks_of(&reused, &demand, lights.len());
    assert!(
        before.iter().all(Option::is_some),
        "every demanded bit is filled"
    );

    // The truck drives between lamp 0 and the facade, 17 m from it.
    let old = world.object_bounds(2).unwrap();
    world.set_transform(2, passing).unwrap();
    let new = world.object_bounds(2).unwrap();
    assert!(
        30.0 - new.max.x > 15.0,
        "the truck stays more than 15 m from the facade"
    );
    let invalidated = reused.invalidate(
        &[ChangedRegion::from(old), ChangedRegion::from(new)],
        &[],
        &lights,
    );
    let (after, refill) = refill_equals_cold(&mut reused, &demand, &lights, &world);

    let changed = before.iter().zip(&after).filter(|(a, b)| a != b).count();
    assert!(
        changed > 50,
        "the truck's shadow reaches the facade's nodes: {changed} bits changed"
    );
    assert!(
        invalidated as usize >= changed,
        "every changed bit was invalidated"
    );
    let total = before.len() as u64;
    assert!(
        invalidated < total / 2,
        "only the shadow's bits: {invalidated} of {total}"
    );
    assert_eq!(
        refill.bits_computed, invalidated,
        "only dropped dynamic bits are re-tested"
    );
    // Lamp 1 is beside the facade: the truck cannot touch its bits.
    let lamp1_changed = before
        .iter()
        .zip(&after)
        .enumerate()
        .filter(|(i, (a, b))| i % 2 == 1 && a != b)
        .count();
    assert_eq!(lamp1_changed, 0);
}

#[test]
fn a_moved_light_drops_its_bits_and_refills_like_cold() {
    let street = Street::new();
    let world = street.world(truck_at(11.0));
    let mut lights = vec![
        lamp(Vec3::new(0.0, 5.0, 0.0)),
        lamp(Vec3::new(27.0, 5.0, 8.0)),
    ];
    let lattice = Lattice::new(H);
    let demand = facade_demand(&lattice, lights.len());
    let (mut reused, _) = filled(&demand, &lights, &world);

    lights[0] = lamp(Vec3::new(0.0, 9.0, 4.0));
    let invalidated = reused.invalidate(&[], &[0], &lights);
    assert!(invalidated > 0);
    let (_, refill) = refill_equals_cold(&mut reused, &demand, &lights, &world);
    assert!(refill.bits_reused > 0, "lamp 1's bits were kept");
}

#[test]
fn camera_and_colour_changes_invalidate_nothing() {
    let street = Street::new();
    let world = street.world(truck_at(11.0));
    let mut lights = vec![lamp(Vec3::new(0.0, 5.0, 0.0))];
    let demand = facade_demand(&Lattice::new(H), 1);
    let (mut reused, _) = filled(&demand, &lights, &world);
    lights[0].power = Vec3::new(5.0, 1.0, 0.5);
    assert_eq!(reused.invalidate(&[], &[], &lights), 0);
    let mut refill = LightMeshStats::default();
    reused.fill(&demand, &lights, &world, &mut refill).unwrap();
    assert_eq!(refill.bits_computed, 0);
}

/// Bits settled a brick at a time, by shafts (nothing in the way) or by one
/// wall hiding a whole group, equal the bits single segments give, in both
/// layers: around a truck that shadows part of the facade, for lamps
/// behind the facade, hiding whole bricks, cutting bricks with its top edge
/// or casting the diagonal between its two triangles across a brick, and
/// for one whose shadow edge crosses bricks below their first node.
#[test]
fn shaft_settled_bits_equal_single_segments() {
    let street = Street::new();
    let world = street.world(truck_at(11.0));
    let lights = vec![
        lamp(Vec3::new(0.0, 5.0, 0.0)),
        lamp(Vec3::new(27.0, 5.0, 8.0)),
        lamp(Vec3::new(40.0, 5.0, 0.0)),
        lamp(Vec3::new(31.0, 20.0, 0.0)),
        // Under the ground and past its far edge: the ground hides a
        // brick's lowest nodes from it, not its highest.
        lamp(Vec3::new(20.0, -0.5, 60.0)),
    ];
    let lattice = Lattice::new(H);
    let mut demand = facade_demand(&lattice, lights.len());
    // Nodes whose shadows from the lamp at x = 40 straddle the facade's
    // diagonal, y = 6 + 0.6 z.
    let diagonal = ((Vec3::new(29.5, 6.0, 0.0) - lattice.origin) / lattice.h)
        .floor()
        .as_ivec3();
    demand.bricks.push(BrickDemand {
        brick: split(diagonal).0,
        needed: vec![(1 << lights.len()) - 1; BRICK_NODES].into_boxed_slice(),
    });
    demand.bricks.sort_by_key(|b| b.brick.to_array());
    demand.bricks.dedup_by_key(|b| b.brick);
    let (shafted, stats) = filled(&demand, &lights, &world);
    let mut blocked = 0;
    for brick in &demand.bricks {
        for slot in 0..BRICK_NODES {
            let node = join(brick.brick, slot);
            let x = lattice.node_position(node);
            for (index, light) in lights.iter().enumerate() {
                let expected = !world.occluded(&light.shadow_ray(x));
                blocked += !expected as u32;
                assert_eq!(
                    shafted.masks().get(node, index),
                    Some(expected),
                    "node {node}, light {index}"
                );
            }
        }
    }
    assert!(blocked > 50, "the truck and the facade block some segments");
    assert!(stats.fill_shafts > 0);
    assert!(
        stats.fill_hidden_groups > 0,
        "the facade hides whole bricks"
    );
    assert!(
        stats.fill_segments < stats.bits_computed * 3 / 5,
        "shafts and walls settled many bits: {} segments for {} bits",
        stats.fill_segments,
        stats.bits_computed
    );
}

/// Bounds of the sheet's vertices on one side of z = 0.
fn half_bounds(positions: &[Vec3], moving: bool) -> ChangedRegion {
    ChangedRegion::from(Bounds::from_points(
        positions.iter().copied().filter(|p| (p.z > 0.0) == moving),
    ))
}

/// A sheet between lamp 0 and the facade, whose z > 0 half a morph target
/// bends down (its top edge sinks up to 1 m) while the other half stays:
/// only the moving half's clusters give changed regions, segments through
/// the still half alone keep their bits (the sheet's box would have
/// dropped them), and what is dropped refills to the cold masks.
///
/// Mutation tried: `TriangleClusters::changed` giving only each cluster's
/// box at the new positions (the old-position boxes dropped) fails the
/// check that the boxes hold every old triangle, and without that check
/// the reused masks differ from the cold ones: segments that the sinking
/// edge uncovered keep their stale "blocked" bits.
#[test]
fn a_half_bent_sheet_drops_only_the_bits_its_moving_half_can_change() {
    let street = Street::new();
    let sheet = common::half_morphing_sheet(15.0, 3.0, 3.5, 0.25, 1.0);
    let bent = lmanim::anim::deform(&sheet, &[1.0], None).positions;
    let sheet_mesh = (sheet.positions.clone(), sheet.triangles.clone());
    let mut world = World::build(&[
        object(&street.ground, Affine3A::IDENTITY, false),
        object(&street.facade, Affine3A::IDENTITY, false),
        object(&sheet_mesh, Affine3A::IDENTITY, true),
    ]);
    let lights = vec![lamp(Vec3::new(0.0, 5.0, 0.0))];
    let lattice = Lattice::new(H);
    let demand = facade_demand(&lattice, lights.len());
    let (mut reused, _) = filled(&demand, &lights, &world);
    let before = masks_of(&reused, &demand, lights.len());

    let sheet_before = world.object_bounds(2).unwrap();
    let boxes = world.set_positions(2, &bent).unwrap();
    assert!(!boxes.is_empty());
    assert!(
        boxes.iter().all(|b| b.min.z >= 0.0),
        "only the moving half changed: {boxes:?}"
    );
    for triangle in &sheet.triangles {
        let corners = |positions: &[Vec3]| triangle.map(|v| positions[v as usize]);
        if corners(&sheet.positions) == corners(&bent) {
            continue;
        }
        for corners in [corners(&sheet.positions), corners(&bent)] {
            let held = |b: &Bounds| {
                corners
                    .iter()
                    .all(|p| p.cmpge(b.min).all() && p.cmple(b.max).all())
            };
            assert!(boxes.iter().any(held), "{corners:?} is in a changed box");
        }
    }

    let sheet_box = [
        ChangedRegion::from(sheet_before),
        ChangedRegion::from(world.object_bounds(2).unwrap()),
    ];
    let mut whole = reused.clone();
    let dropped_by_box = whole.invalidate(&sheet_box, &[], &lights);
    let changed: Vec<ChangedRegion> = boxes.iter().map(|&b| ChangedRegion::from(b)).collect();
    let dropped = reused.invalidate(&changed, &[], &lights);
    assert!(
        0 < dropped && dropped < dropped_by_box,
        "{dropped} bits dropped, {dropped_by_box} by the sheet's box"
    );

    let still = half_bounds(&sheet.positions, false);
    let (moving_before, moving_after) = (
        half_bounds(&sheet.positions, true),
        half_bounds(&bent, true),
    );
    let mut kept = 0;
    for brick in &demand.bricks {
        for slot in 0..BRICK_NODES {
            let node = join(brick.brick, slot);
            let segment = lights[0].shadow_ray(lattice.node_position(node));
            let sees_past_statics = reused
                .masks()
                .node(node)
                .is_some_and(|mask| mask.static_layer(0).0 & 1 == 1);
            if sees_past_statics
                && still.meets(&segment)
                && !moving_before.meets(&segment)
                && !moving_after.meets(&segment)
            {
                assert_eq!(whole.masks().get(node, 0), None, "the box drops {node}");
                assert!(
                    reused.masks().get(node, 0).is_some(),
                    "{node} keeps its bit"
                );
                kept += 1;
            }
        }
    }
    assert!(kept > 20, "{kept} segments cross the still half alone");

    let (after, refill) = refill_equals_cold(&mut reused, &demand, &lights, &world);
    assert_eq!(refill.bits_computed, dropped);
    let uncovered = before.iter().zip(&after).filter(|(a, b)| a != b).count();
    assert!(uncovered > 10, "the sinking edge uncovers {uncovered} bits");
}
