//! Self-intersection avoidance for rays leaving a surface (Wächter & Binder,
//! "A Fast and Robust Method for Avoiding Self-Intersection", Ray Tracing
//! Gems, ch. 6). The renderer re-launches secondary and shadow rays from hit
//! points; moving the origin a few integer ULPs along the geometric normal puts
//! it on the right side of the surface whatever the coordinates' magnitude, so
//! no scene-dependent epsilon is ever needed.

use glam::Vec3;

/// Below this magnitude a coordinate is offset by a fixed amount instead of in
/// ULPs: near zero, ULPs are so small that a few of them would not clear the
/// rounding error of the hit point.
const ORIGIN: f32 = 1.0 / 32.0;
/// The fixed offset used near zero, per unit of the normal.
const FLOAT_SCALE: f32 = 1.0 / 65536.0;
/// ULPs to move per unit of the normal.
const INT_SCALE: f32 = 256.0;

/// Moves the hit point `p` off its surface into the side that `n` faces.
///
/// `n` is the unit geometric normal pointing to the side the new ray leaves
/// into (flip it for transmission, or when the ray leaves from the back). The
/// result is the origin to use for the new ray; a ray from it towards that
/// side never re-hits the triangle `p` lies on.
pub fn offset_ray_origin(p: Vec3, n: Vec3) -> Vec3 {
    let offset = |p: f32, n: f32| -> f32 {
        if p.abs() < ORIGIN {
            return p + FLOAT_SCALE * n;
        }
        // Saturating float-to-int cast; |n| <= 1 keeps it in range anyway.
        let ulps = (INT_SCALE * n) as i32;
        let ulps = if p < 0.0 { -ulps } else { ulps };
        f32::from_bits((p.to_bits() as i32).wrapping_add(ulps) as u32)
    };
    Vec3::new(offset(p.x, n.x), offset(p.y, n.y), offset(p.z, n.z))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn moves_towards_the_normal_at_every_magnitude() {
        for &scale in &[0.0f32, 1e-3, 1.0, 1e3, 1e5, 1e7, -1e5, -1.0] {
            let p = Vec3::splat(scale);
            for n in [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Z] {
                let q = offset_ray_origin(p, n);
                assert!((q - p).dot(n) > 0.0, "p {p} n {n} q {q}");
            }
        }
    }
}
