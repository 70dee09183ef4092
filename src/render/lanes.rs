//! Vectors of eight lanes: the shape in which shading evaluates Omega for
//! eight lights at once (`omega.rs`, the BRDF's `evaluate_lanes`).

use glam::Vec3;
use wide::f32x8;

/// Three eight-lane components: x, y, z (or r, g, b).
pub type Lanes3 = [f32x8; 3];

/// The dot product of each lane's vectors.
#[inline]
pub fn dot(a: Lanes3, b: Lanes3) -> f32x8 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// `v` in every lane.
#[inline]
pub fn splat3(v: Vec3) -> Lanes3 {
    [f32x8::splat(v.x), f32x8::splat(v.y), f32x8::splat(v.z)]
}

/// `[f(0), f(1), f(2)]`: what `[0, 1, 2].map(f)` means, spelled out. The
/// array's `map` goes through a drain that the compiler left out of line
/// in Omega's loop (6% of a 64-lamp bench's samples), passing each
/// eight-lane value through memory.
#[inline(always)]
pub fn each3<T>(mut f: impl FnMut(usize) -> T) -> [T; 3] {
    [f(0), f(1), f(2)]
}
