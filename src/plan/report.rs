//! The plan as a user reads it (`lmanim plan`, `--explain`): text, or
//! JSON with the field names the README documents.

use std::fmt::Write;

use serde::{Serialize, Serializer};

use super::{LightPlan, Plan};
use crate::render::shadow_split::{LightRole, ShadowSplit};
use crate::schedule::FrameSet;
use crate::settings::Settings;

/// What one frame costs at most, by the plan: every figure an upper bound
/// for primary hits (secondary rays add to them where mirrors and glass
/// are in view).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize)]
pub struct WorkEstimate {
    /// Camera samples: the primary rays and their shading points.
    pub shading_points: u64,
    /// Formula (1)'s shadow rays: a point per light that traces them.
    pub shadow_rays: u64,
    /// Lights shaded from the light mesh, and the lattice nodes of one
    /// point's interpolation half-ball.
    pub mesh_lights: u64,
    pub nodes_per_point: u64,
    /// (node, light) bits the light mesh may need, before reuse: points ×
    /// half-ball nodes × light-mesh lights.
    pub mask_bits: u64,
}

impl WorkEstimate {
    pub fn of(settings: &Settings, lights: &[LightPlan]) -> WorkEstimate {
        let points =
            u64::from(settings.width) * u64::from(settings.height) * u64::from(settings.spp);
        let split = ShadowSplit::new(lights.iter().map(|light| light.shadows).collect());
        let method = split.resolve(settings.method, &[]);
        let (mut ray_lights, mut mesh_lights) = (0, 0);
        for index in 0..lights.len() {
            match split.role(method, index, &[]) {
                LightRole::LightMesh => mesh_lights += 1,
                LightRole::FormulaOne { test_segment: true } => ray_lights += 1,
                LightRole::Lamp if split.tests_segment(index) => ray_lights += 1,
                _ => {}
            }
        }
        let ki = f64::from(settings.lightmesh.ki);
        let nodes_per_point = if mesh_lights > 0 {
            (2.0 / 3.0 * std::f64::consts::PI * ki * ki * ki).ceil() as u64
        } else {
            0
        };
        WorkEstimate {
            shading_points: points,
            shadow_rays: points * ray_lights,
            mesh_lights,
            nodes_per_point,
            mask_bits: points * nodes_per_point * mesh_lights,
        }
    }
}

/// The plan as text, a few lines per section.
pub fn text(plan: &Plan) -> String {
    let mut out = String::new();
    let frames = compact(plan.frames.frames());
    let _ = writeln!(out, "plan over frames {frames}, --method {}", plan.method);
    let _ = writeln!(out, "lights:");
    for light in &plan.lights {
        let name = light.name.as_deref().unwrap_or("(unnamed)");
        let _ = writeln!(
            out,
            "  {:>3} {:<20} {:<10} {}",
            light.index, name, light.shadows, light.reason
        );
    }
    let dynamic: Vec<_> = plan.objects.iter().filter(|o| o.dynamic).collect();
    let _ = writeln!(
        out,
        "objects: {} static, {} dynamic",
        plan.objects.len() - dynamic.len(),
        dynamic.len()
    );
    for object in dynamic {
        let name = object.name.as_deref().unwrap_or("(unnamed)");
        let moves = if !object.moves_in.is_empty() {
            format!("moves in {}", object.moves_in.join(","))
        } else if object.deforms {
            "deforms (skin or morph targets)".to_owned()
        } else {
            "animated, still in the planned frames".to_owned()
        };
        let _ = writeln!(out, "  node {:>4} {:<20} {moves}", object.node, name);
    }
    let spawning: Vec<String> = (plan.materials.iter())
        .filter(|m| m.spawns_secondary)
        .map(|m| {
            let kind = match (m.reflects, m.transmits) {
                (true, true) => "mirror, glass",
                (true, false) => "mirror",
                _ => "glass",
            };
            format!("{} ({kind})", m.name.as_deref().unwrap_or("(unnamed)"))
        })
        .collect();
    let _ = match spawning.is_empty() {
        true => writeln!(out, "secondary rays: none (no mirror or glass in view)"),
        false => writeln!(out, "secondary rays from: {}", spawning.join(", ")),
    };
    let copied = match plan.copied_frames.is_empty() {
        true => "none".to_owned(),
        false => compact(&plan.copied_frames),
    };
    let _ = writeln!(out, "frames copied (nothing changes): {copied}");
    let work = &plan.work;
    let _ = writeln!(
        out,
        "work per frame at most: {} shading points, {} shadow rays, {} light-mesh lights × {} nodes per point = {} mask bits",
        work.shading_points, work.shadow_rays, work.mesh_lights, work.nodes_per_point, work.mask_bits
    );
    out
}

/// The plan as pretty JSON.
pub fn json(plan: &Plan) -> String {
    serde_json::to_string_pretty(plan).expect("a plan serializes")
}

/// Frame numbers as ranges: `0..3`, `7`.
pub fn frame_ranges(frames: &[u32]) -> Vec<String> {
    let mut ranges: Vec<(u32, u32)> = Vec::new();
    for &frame in frames {
        match ranges.last_mut() {
            Some(last) if last.1 + 1 == frame => last.1 = frame,
            _ => ranges.push((frame, frame)),
        }
    }
    (ranges.into_iter())
        .map(|(start, end)| match start == end {
            true => start.to_string(),
            false => format!("{start}..{}", u64::from(end) + 1),
        })
        .collect()
}

fn compact(frames: &[u32]) -> String {
    frame_ranges(frames).join(",")
}

pub(super) fn frame_list<S: Serializer>(frames: &FrameSet, s: S) -> Result<S::Ok, S::Error> {
    s.serialize_str(&compact(frames.frames()))
}

pub(super) fn numbers<S: Serializer>(frames: &[u32], s: S) -> Result<S::Ok, S::Error> {
    frame_ranges(frames).serialize(s)
}

pub(super) fn display<S: Serializer, T: std::fmt::Display>(
    value: &T,
    s: S,
) -> Result<S::Ok, S::Error> {
    s.collect_str(value)
}
