//! Which integrator shades each light of a frame: the plan's class of the
//! light ([`Shadows`]) and the run's method decide it together. `auto`
//! follows the class (formula (1) with shadow rays for hard lights, with
//! none for unshadowed ones, the light mesh by LMM1 for soft ones); the
//! other methods force their integrator on every light, except that a
//! `none` light is off everywhere and no formula-(1) term of an
//! unshadowed light tests its segment (it would be clear).
//!
//! [`ShadowSplit::resolve`] is the one place that reads `auto`: it turns
//! the run's [`Method`] and the frame's classes into a [`FrameMethod`],
//! the integrators the frame runs, and every later question (a light's
//! role, the lights an integrator is handed) is asked of that. Backends
//! match on a `FrameMethod`, which has no `auto` to resolve again.
//!
//! One frame may so use two integrators. Each light's term is computed by
//! its own, and a point's terms are summed in a fixed order (the
//! formula-(1) lights first, in light order, then the light mesh's), so a
//! light's term has the bits the forced method gives it.

use glam::Vec3;

use super::light::RenderLight;
use super::omega::LightLanes;
use crate::plan::shadows::Shadows;
use crate::settings::Method;

/// The integrators a frame runs: the run's [`Method`] with `auto`
/// resolved against the frame's lights' classes
/// ([`ShadowSplit::resolve`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FrameMethod {
    /// Formula (1) for every light that is on (`whitted`, and `auto`
    /// where no light is soft).
    FormulaOne,
    /// Monte Carlo samples of every lamp that is on (`area`).
    Lamps,
    /// Formula (2) from the light mesh for `lights`, with LMM's
    /// point-to-node tests or without them (LMM1's rule); formula (1)
    /// shades the other lights that are on, their terms first.
    LightMesh {
        point_to_node_tests: bool,
        lights: MeshLights,
    },
}

impl FrameMethod {
    /// What every frame by `method` runs, whatever its lights' classes;
    /// None for `auto`, which the plan's classes decide
    /// ([`ShadowSplit::resolve`]).
    pub fn forced(method: Method) -> Option<FrameMethod> {
        let light_mesh = |point_to_node_tests| FrameMethod::LightMesh {
            point_to_node_tests,
            lights: MeshLights::All,
        };
        match method {
            Method::Whitted => Some(FrameMethod::FormulaOne),
            Method::Area => Some(FrameMethod::Lamps),
            Method::Lmm => Some(light_mesh(true)),
            Method::Lmm1 => Some(light_mesh(false)),
            Method::Auto => None,
        }
    }

    /// Whether formula (2) keeps only the nodes a point sees (LMM's step
    /// 3, one point-to-node segment per candidate); LMM1 keeps them all.
    pub fn tests_point_to_node(self) -> bool {
        matches!(
            self,
            FrameMethod::LightMesh {
                point_to_node_tests: true,
                ..
            }
        )
    }
}

/// The lights a [`FrameMethod::LightMesh`] frame shades from the light
/// mesh.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeshLights {
    /// Every light that is on (`lmm`, `lmm1`).
    All,
    /// The soft ones (`auto`).
    Soft,
}

/// How one light is shaded in a frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LightRole {
    /// Switched off: it reaches nothing the camera sees.
    Off,
    /// Formula (1); `test_segment` is false for unshadowed lights.
    FormulaOne { test_segment: bool },
    /// Formula (2) from the light mesh.
    LightMesh,
    /// Monte Carlo samples of the spherical lamp (`area`).
    Lamp,
}

/// The frame's lights' shadow classes. The default (no plan) takes every
/// light as `hard` or `soft` by its lamp radius at the time of asking.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ShadowSplit {
    classes: Vec<Shadows>,
}

impl ShadowSplit {
    pub fn new(classes: Vec<Shadows>) -> ShadowSplit {
        ShadowSplit { classes }
    }

    /// The class of light `index` of `lights`.
    pub fn class(&self, index: usize, lights: &[RenderLight]) -> Shadows {
        match self.classes.get(index) {
            Some(&class) => class,
            None => Shadows::by_lamp_radius(lights.get(index).map_or(0.0, |l| l.lamp_radius)),
        }
    }

    /// Whether a formula-(1) term of light `index` tests its shadow
    /// segment: all but unshadowed lights'.
    pub fn tests_segment(&self, index: usize) -> bool {
        self.classes.get(index) != Some(&Shadows::Unshadowed)
    }

    /// The integrators `method` runs in a frame with `lights`: `auto`
    /// runs the light mesh (by LMM1's rule) where some light is soft, and
    /// formula (1) alone where none is.
    pub fn resolve(&self, method: Method, lights: &[RenderLight]) -> FrameMethod {
        match FrameMethod::forced(method) {
            Some(forced) => forced,
            None if self.has_class(Shadows::Soft, lights) => FrameMethod::LightMesh {
                point_to_node_tests: false,
                lights: MeshLights::Soft,
            },
            None => FrameMethod::FormulaOne,
        }
    }

    /// What one frame with `lights` runs: [`ShadowSplit::resolve`]'s
    /// answer, except that a light-mesh frame none of whose lights the
    /// mesh would shade (every lamp off, or no light at all) runs formula
    /// (1) alone: it shades the lights that are on as the light-mesh frame
    /// would have, and there is no mesh to build. (A run prepares its
    /// pipelines by `resolve`, for the frames whose lamps are on.)
    pub fn frame_method(&self, method: Method, lights: &[RenderLight]) -> FrameMethod {
        match self.resolve(method, lights) {
            resolved @ FrameMethod::LightMesh { .. } if !self.uses_light_mesh(resolved, lights) => {
                FrameMethod::FormulaOne
            }
            resolved => resolved,
        }
    }

    /// Whether some light of `lights` (or of the plan) is in `class`.
    fn has_class(&self, class: Shadows, lights: &[RenderLight]) -> bool {
        self.indices(lights)
            .any(|index| self.class(index, lights) == class)
    }

    /// How `method` shades light `index` of `lights`.
    pub fn role(&self, method: FrameMethod, index: usize, lights: &[RenderLight]) -> LightRole {
        let class = self.class(index, lights);
        let test_segment = class != Shadows::Unshadowed;
        match (class, method) {
            (Shadows::None, _) => LightRole::Off,
            (_, FrameMethod::FormulaOne) => LightRole::FormulaOne { test_segment },
            (_, FrameMethod::Lamps) => LightRole::Lamp,
            (Shadows::Soft, FrameMethod::LightMesh { .. }) => LightRole::LightMesh,
            (_, FrameMethod::LightMesh { lights, .. }) => match lights {
                MeshLights::All => LightRole::LightMesh,
                MeshLights::Soft => LightRole::FormulaOne { test_segment },
            },
        }
    }

    /// Whether `method` shades some light of `lights` from the light mesh.
    pub fn uses_light_mesh(&self, method: FrameMethod, lights: &[RenderLight]) -> bool {
        self.indices(lights)
            .any(|index| self.role(method, index, lights) == LightRole::LightMesh)
    }

    /// Whether `method` shades some light of `lights` by formula (1).
    pub fn uses_formula_one(&self, method: FrameMethod, lights: &[RenderLight]) -> bool {
        self.indices(lights).any(|index| {
            matches!(
                self.role(method, index, lights),
                LightRole::FormulaOne { .. }
            )
        })
    }

    /// The lights' indices: those of `lights`, and those the plan classed
    /// (a caller without the frame's lights passes none).
    fn indices(&self, lights: &[RenderLight]) -> std::ops::Range<usize> {
        0..lights.len().max(self.classes.len())
    }

    /// `lights` with only those `method` shades by `wanted` left powered:
    /// a light without power reaches no point, so an integrator given
    /// these spends nothing on the others, and their lanes add nothing.
    pub fn only(
        &self,
        method: FrameMethod,
        lights: &[RenderLight],
        wanted: impl Fn(LightRole) -> bool,
    ) -> Vec<RenderLight> {
        (lights.iter().enumerate())
            .map(
                |(index, light)| match wanted(self.role(method, index, lights)) {
                    true => *light,
                    false => RenderLight {
                        power: Vec3::ZERO,
                        ..*light
                    },
                },
            )
            .collect()
    }

    /// [`ShadowSplit::only`] in SIMD lanes.
    pub fn lanes(
        &self,
        method: FrameMethod,
        lights: &[RenderLight],
        wanted: impl Fn(LightRole) -> bool,
    ) -> LightLanes {
        LightLanes::new(&self.only(method, lights, wanted))
    }

    /// Per class, a bit per light of `lights` in that class, in 64-bit
    /// words (as the light mesh's masks hold them).
    pub fn class_words(&self, class: Shadows, lights: &[RenderLight]) -> Vec<u64> {
        let mut words = vec![0u64; lights.len().div_ceil(64)];
        for index in (0..lights.len()).filter(|&i| self.class(i, lights) == class) {
            words[index / 64] |= 1 << (index % 64);
        }
        words
    }
}
