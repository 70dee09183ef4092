//! Per-frame and per-run statistics, written as JSON by `--stats`. The
//! field names are part of the CLI's contract (see README).

use std::collections::BTreeMap;

use serde::Serialize;

use crate::lightmesh::LightMeshStats;

/// Rays traced in one frame, by kind.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct RayCounts {
    pub primary: u64,
    pub shadow: u64,
    pub secondary: u64,
}

impl std::ops::AddAssign for RayCounts {
    fn add_assign(&mut self, other: RayCounts) {
        self.primary += other.primary;
        self.shadow += other.shadow;
        self.secondary += other.secondary;
    }
}

/// What one frame cost.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FrameStats {
    pub frame: u32,
    pub seconds: f64,
    /// Wall time of each stage of the frame, by stage name.
    pub stages: BTreeMap<String, f64>,
    pub rays: RayCounts,
    pub shading_points: u64,
    /// What changed since the previous rendered frame.
    pub camera_moved: bool,
    pub lights_moved: u64,
    pub objects_moved: u64,
    /// Nothing changed: the previous frame's image was written again.
    pub copied: bool,
    /// Light-mesh bits dropped because geometry or lights moved.
    pub bits_invalidated: u64,
    pub invalidate_seconds: f64,
    /// Light-mesh work, for the LMM and LMM1 methods.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub lightmesh: Option<LightMeshStats>,
}

impl FrameStats {
    /// Adds `seconds` to the stage `name` (stages can run once per band).
    pub fn add_stage_time(&mut self, name: &str, seconds: f64) {
        *self.stages.entry(name.to_owned()).or_default() += seconds;
    }
}

/// What a whole run cost.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct RunStats {
    pub frames: Vec<FrameStats>,
    pub total_seconds: f64,
    pub threads: usize,
    pub method: String,
    /// The GPU adapter a `--backend gpu` run rendered on (name, backend,
    /// driver); absent on the CPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adapter: Option<String>,
}
