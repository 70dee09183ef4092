//! Per-frame and per-run statistics, written as JSON by `--stats`. The
//! field names are part of the CLI's contract (see README).

use std::collections::BTreeMap;

use serde::Serialize;

use crate::backend::gpu::traffic::GpuFrameStats;
use crate::lightmesh::LightMeshStats;
use crate::plan::Shadows;

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

/// Shadow rays traced for lights of each shadow class of the plan.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct ClassRays([u64; 4]);

impl ClassRays {
    /// Counts indexed as [`Shadows::ALL`] lists the classes.
    pub fn new(counts: [u64; 4]) -> ClassRays {
        ClassRays(counts)
    }

    pub fn add(&mut self, class: Shadows) {
        self.0[class as usize] += 1;
    }

    pub fn of(&self, class: Shadows) -> u64 {
        self.0[class as usize]
    }

    pub fn total(&self) -> u64 {
        self.0.iter().sum()
    }
}

impl std::ops::AddAssign for ClassRays {
    fn add_assign(&mut self, other: ClassRays) {
        for (mine, theirs) in self.0.iter_mut().zip(other.0) {
            *mine += theirs;
        }
    }
}

/// What a frame spent on the lights of one shadow class.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ClassCost {
    /// Shadow rays of formula (1) (hard lights, formula (2)'s fallback)
    /// and lamp samples (`area`) for these lights.
    pub shadow_rays: u64,
    /// (node, light) mask bits the light mesh holds for these lights
    /// after the frame.
    pub mask_bits: u64,
}

/// A frame's cost by the plan's shadow class of the lights it served, so
/// that what the plan skips can be seen to cost nothing.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct ShadowClassCosts {
    pub none: ClassCost,
    pub unshadowed: ClassCost,
    pub hard: ClassCost,
    pub soft: ClassCost,
}

impl ShadowClassCosts {
    pub fn get(&self, class: Shadows) -> ClassCost {
        match class {
            Shadows::None => self.none,
            Shadows::Unshadowed => self.unshadowed,
            Shadows::Hard => self.hard,
            Shadows::Soft => self.soft,
        }
    }

    pub fn get_mut(&mut self, class: Shadows) -> &mut ClassCost {
        match class {
            Shadows::None => &mut self.none,
            Shadows::Unshadowed => &mut self.unshadowed,
            Shadows::Hard => &mut self.hard,
            Shadows::Soft => &mut self.soft,
        }
    }

    /// Adds `rays`, class by class.
    pub fn add_rays(&mut self, rays: ClassRays) {
        for class in Shadows::ALL {
            self.get_mut(class).shadow_rays += rays.of(class);
        }
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
    /// Shadow rays and mask bits by the plan's class of their light.
    pub shadow_classes: ShadowClassCosts,
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
    /// What crossed between the CPU and the GPU, and the pipelines
    /// compiled for the frame (`--backend gpu` only).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub gpu: Option<GpuFrameStats>,
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
    /// The frames rendered.
    pub frames: Vec<FrameStats>,
    /// The frames not rendered because they were on disk already
    /// (`--skip-existing`), in order.
    pub skipped: Vec<u32>,
    pub total_seconds: f64,
    pub threads: usize,
    pub method: String,
    /// The GPU adapter a `--backend gpu` run rendered on (name, backend,
    /// driver); absent on the CPU.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adapter: Option<String>,
    /// Which objects the run traced as static.
    pub static_set: StaticSet,
}

/// The objects a run keeps in its static structures, and the hash of
/// their triangles and placements that keys the light-mesh disk cache.
/// Every run of a shot (a frame alone, a farm chunk, the whole shot)
/// must report the same: objects traced the other way round would render
/// other bits, and would not share the cache.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize)]
pub struct StaticSet {
    pub static_objects: u64,
    pub dynamic_objects: u64,
    /// 32 hex digits.
    pub hash: String,
}
