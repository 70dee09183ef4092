//! The weights formula (2) gives the nodes of an interpolation set.
//!
//! The paper counts every node alike (`Box`): a point's value then jumps
//! by 1/m each time a node enters or leaves its half-ball, which shows as
//! blotches in a penumbra (STUDY.md). `Smooth` weighs a node at distance
//! d from the point by (1 − d²/r²)², which falls to zero at the radius
//! with a zero slope, so a node enters or leaves with no weight and the
//! value changes continuously as the point moves:
//!
//!   U(P) = Σ_i Omega(i, P) · Σ_{k sees i} w_k / Σ_k w_k.
//!
//! Weights are integers (the smooth one in 1/4095 steps), so the sums are
//! exact and their order cannot change a bit: the GPU backend's shader
//! (`light_mesh.wgsl`) adds the same integers in its own order and gets
//! the CPU's frames. A half-ball of at most `MAX_KI` steps holds fewer
//! than 2^12 nodes (about 2150), so a sum stays below 2^24 and converts
//! to f32 exactly.

use serde::{Deserialize, Serialize};

/// The largest smooth weight, a node at the point itself: fine enough
/// that rounding the weights moves a value by far less than the kernel's
/// own slope does between neighbouring pixels.
pub const SMOOTH_WEIGHT_SCALE: f32 = 4095.0;

#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize, clap::ValueEnum,
)]
#[serde(rename_all = "lowercase")]
pub enum Kernel {
    /// The paper's formula (2): every node of the set counts once.
    #[default]
    Box,
    /// Weights (1 − d²/r²)², continuous as the point moves.
    Smooth,
}

/// A kernel for one interpolation radius r, ready to weigh nodes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Weights {
    kernel: Kernel,
    /// 1/r², rounded once, so every weight multiplies by the same value
    /// (the GPU gets this very number rather than dividing itself).
    inverse_radius_squared: f32,
}

impl Weights {
    pub fn new(kernel: Kernel, radius: f32) -> Weights {
        Weights {
            kernel,
            inverse_radius_squared: 1.0 / (radius * radius),
        }
    }

    pub fn kernel(&self) -> Kernel {
        self.kernel
    }

    pub fn inverse_radius_squared(&self) -> f32 {
        self.inverse_radius_squared
    }

    /// The weight of a node at squared distance `distance_squared` from
    /// the point (at most r², as the half-ball rounds it). Each step is
    /// one rounded f32 operation, the order the shader keeps.
    pub fn weight(&self, distance_squared: f32) -> u32 {
        match self.kernel {
            Kernel::Box => 1,
            Kernel::Smooth => {
                let falloff = (1.0 - distance_squared * self.inverse_radius_squared).max(0.0);
                ((falloff * falloff) * SMOOTH_WEIGHT_SCALE).floor() as u32
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn box_weighs_every_node_alike() {
        let weights = Weights::new(Kernel::Box, 0.3);
        assert_eq!(weights.weight(0.0), 1);
        assert_eq!(weights.weight(0.09), 1);
    }

    #[test]
    fn smooth_falls_from_the_point_to_zero_at_the_radius() {
        let weights = Weights::new(Kernel::Smooth, 2.0);
        assert_eq!(weights.weight(0.0), 4095);
        assert_eq!(weights.weight(4.0), 0);
        // Just inside the radius, and a rounded d² just past it, weigh nothing.
        assert_eq!(weights.weight(3.9999), 0);
        assert_eq!(weights.weight(4.000_001), 0);
        // (1 − 1/4)² · 4095 = 2303.4.
        assert_eq!(weights.weight(1.0), 2303);
        let falling: Vec<u32> = (0..=40).map(|i| weights.weight(i as f32 * 0.1)).collect();
        assert!(
            falling.windows(2).all(|pair| pair[0] >= pair[1]),
            "{falling:?}"
        );
    }
}
