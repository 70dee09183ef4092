//! How wide a light's penumbra is at a shading point, from the distance
//! between the point and what blocks the light.
//!
//! Formula (2) over a half-ball of fixed radius r = kI·h draws every
//! penumbra about 2r wide. A real lamp's is not: for a spherical lamp of
//! radius R at distance D from the point, an occluder's edge at distance
//! z from the point casts a penumbra of width 2·R·z / (D − z) there.
//! It is narrow where the occluder touches the receiver (an umbra
//! remains at the contact) and wide far from it (STUDY.md measured this
//! as what the fixed radius leaves: "the width of the transition, not its
//! shape").
//!
//! With `lightmesh.penumbra: blocker`, a point whose interpolation set
//! disagrees on a light (some of its nodes see the light, some do not)
//! traces one closest-hit ray towards the light's centre; where that ray
//! is clear (the lit half of the penumbra), one more from the blocked
//! node nearest the point. The first hit gives z, and the light's share
//! is then interpolated over the nodes within r_i = R·z / (D − z), capped
//! at kI·h. Where r_i is below one lattice step the set holds too few
//! nodes to interpolate, and the light is taken as visible or not as the
//! centre ray found: a hard shadow, which is what the lamp gives there.
//!
//! Points whose nodes all agree on a light (far from any shadow edge, most
//! points) trace nothing and keep their value. Nothing here is kept from
//! frame to frame, so reuse of the masks stays exact.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::accel::{Ray, World};
use crate::render::light::{LightSource, RenderLight};

/// How formula (2) sizes each light's interpolation set.
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Penumbra {
    /// The paper's: one radius kI·h for every light and point.
    #[default]
    Fixed,
    /// Each light's radius from the distance to its blocker, where the
    /// nodes disagree on it.
    Blocker,
}

/// What the rays towards one light found at one point.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlockerEstimate {
    /// The radius the light's penumbra wants at the point, capped at the
    /// half-ball's; `None` where it is below one lattice step.
    pub radius: Option<f32>,
    /// Whether the ray from the point to the light's centre is clear.
    pub centre_visible: bool,
    /// Closest-hit rays traced: one or two.
    pub rays: u64,
}

/// The physical penumbra radius of `light` at the point whose ray origin
/// is `origin`, for a set whose blocked node nearest the point lies at
/// `nearest_blocked`. `max_radius` is the half-ball's radius and `h` the
/// lattice step. Returns `None` for a light without a position (a
/// directional light has no lamp to size a penumbra by).
pub fn estimate(
    origin: Vec3,
    light: &RenderLight,
    nearest_blocked: Vec3,
    world: &World,
    max_radius: f32,
    h: f32,
) -> Option<BlockerEstimate> {
    let centre = match light.source {
        LightSource::Point { position } | LightSource::Spot { position, .. } => position,
        LightSource::Directional { .. } => return None,
    };
    let centre_ray = light.shadow_ray(origin);
    let (blocker, rays) = match blocker_distance(&centre_ray, centre, world) {
        Some(found) => (Some(found), 1),
        None => {
            let node_ray = light.shadow_ray(nearest_blocked);
            (blocker_distance(&node_ray, centre, world), 2)
        }
    };
    let centre_visible = rays == 2;
    // A blocked node whose own segment is found clear (it can only be one
    // the dynamic layer marked, since moved away): nothing to size by,
    // so the set keeps the half-ball's radius.
    let Some((z, distance)) = blocker else {
        return Some(BlockerEstimate {
            radius: Some(max_radius),
            centre_visible,
            rays,
        });
    };
    let radius = light.lamp_radius * z / (distance - z).max(f32::MIN_POSITIVE);
    Some(BlockerEstimate {
        radius: (radius >= h).then(|| radius.min(max_radius)),
        centre_visible,
        rays,
    })
}

/// The distance from `ray`'s origin to the first thing it hits, and from
/// its origin to the light's `centre`.
fn blocker_distance(ray: &Ray, centre: Vec3, world: &World) -> Option<(f32, f32)> {
    let hit = world.closest_hit(ray)?;
    let distance = (centre - ray.origin).length();
    Some((hit.t * distance, distance))
}
