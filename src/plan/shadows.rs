//! A light's shadow class, the plan's answer per light that the render
//! layer's shadow split (`render/shadow_split.rs`) turns into integrators.
//! It stands apart from the rest of the plan so that the render layer can
//! read it without the plan, which builds on the render layer.

use serde::Serialize;

/// How a light's shadows are simulated, decided per light over the
/// planned frames.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Shadows {
    /// It sends nothing to any surface a camera path can see: switched off.
    None,
    /// Nothing can stand between it and what it lights: formula (1) with
    /// no shadow ray.
    Unshadowed,
    /// An ideal point (no lamp radius): formula (1) with shadow rays.
    Hard,
    /// A lamp with a radius: the light mesh.
    Soft,
}

impl Shadows {
    pub const ALL: [Shadows; 4] = [
        Shadows::None,
        Shadows::Unshadowed,
        Shadows::Hard,
        Shadows::Soft,
    ];

    pub fn name(self) -> &'static str {
        match self {
            Shadows::None => "none",
            Shadows::Unshadowed => "unshadowed",
            Shadows::Hard => "hard",
            Shadows::Soft => "soft",
        }
    }

    /// The class a light has before any plan: by its lamp radius alone.
    pub fn by_lamp_radius(lamp_radius: f32) -> Shadows {
        if lamp_radius > 0.0 {
            Shadows::Soft
        } else {
            Shadows::Hard
        }
    }
}

impl std::fmt::Display for Shadows {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}
