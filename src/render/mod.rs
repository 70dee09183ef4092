//! Shading: cameras, lights, the glTF BRDF (Omega), the Whitted recursion
//! and the integrators' per-point work. Nothing here knows which backend
//! runs it or what time it is: a frame arrives as a [`FrameJob`].

pub mod area;
pub mod brdf;
pub mod camera;
pub mod environment;
pub mod frame;
pub mod lanes;
pub mod light;
pub mod light_terms;
pub mod material;
pub mod omega;
pub mod scatter;
pub mod shading;
pub mod shadow_split;
pub mod surface;
pub mod whitted;

use crate::accel::World;
use crate::scene::SceneDesc;
use crate::settings::Aov;
use environment::Environment;
use frame::FrameScene;
use shadow_split::ShadowSplit;

/// Everything a backend needs to render one frame.
#[derive(Clone, Copy)]
pub struct FrameJob<'a> {
    pub scene: &'a SceneDesc,
    pub frame: &'a FrameScene,
    pub world: &'a World,
    pub width: u32,
    pub height: u32,
    /// Samples per pixel: 1 traces the pixel centre, more jitter within
    /// strata of the pixel.
    pub spp: u32,
    /// Deepest Whitted recursion (0: primary hits only).
    pub max_depth: u32,
    /// The background and the ambient sky (both off by default).
    pub environment: Environment,
    /// The AOV layers to make beside the beauty.
    pub aovs: &'a [Aov],
    /// The plan's shadow class of each light, which with the method
    /// decides how each is shaded.
    pub shadows: &'a ShadowSplit,
}
