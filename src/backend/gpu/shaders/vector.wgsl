// Vector arithmetic as glam's `Vec3` does it on the CPU: left to right,
// each product rounded on its own through the prelude's `mul`, so no
// product fuses into the sum that follows.

const PI: f32 = 3.14159265358979323846;

// The CPU lanes' max and min (wide's, SSE's): `b` is never NaN here, and
// a NaN `a` gives `b`.
fn lane_max(a: f32, b: f32) -> f32 {
    return select(b, a, a > b);
}

fn lane_min(a: f32, b: f32) -> f32 {
    return select(b, a, a < b);
}

fn dot3(a: vec3<f32>, b: vec3<f32>) -> f32 {
    return mul(a.x, b.x) + mul(a.y, b.y) + mul(a.z, b.z);
}

fn scale3(v: vec3<f32>, s: f32) -> vec3<f32> {
    return vec3<f32>(mul(v.x, s), mul(v.y, s), mul(v.z, s));
}

// `Vec3::cross` as glam rounds it.
fn cross3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(
        mul(a.y, b.z) - mul(b.y, a.z),
        mul(a.z, b.x) - mul(b.z, a.x),
        mul(a.x, b.y) - mul(b.x, a.y),
    );
}

// `Vec3 * Vec3`, component by component.
fn mul3(a: vec3<f32>, b: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(mul(a.x, b.x), mul(a.y, b.y), mul(a.z, b.z));
}

// `f32::clamp` to [0, 1]: NaN stays NaN, as on the CPU.
fn unit_clamp(x: f32) -> f32 {
    return select(select(x, 1.0, x > 1.0), 0.0, x < 0.0);
}

// Whether `x` is neither infinite nor NaN, read from its bits: a compiler
// may assume that no float is either, and fold a comparison away.
fn is_finite(x: f32) -> bool {
    return (bitcast<u32>(x) & 0x7f800000u) != 0x7f800000u;
}

// `Vec3::normalize`: times the reciprocal of the length.
fn normalize3(v: vec3<f32>) -> vec3<f32> {
    return scale3(v, div(1.0, root(dot3(v, v))));
}

// `Vec3::normalize_or_zero`: zero where the reciprocal length is not a
// finite positive number.
fn normalize_or_zero3(v: vec3<f32>) -> vec3<f32> {
    let reciprocal = div(1.0, root(dot3(v, v)));
    if is_finite(reciprocal) && reciprocal > 0.0 {
        return scale3(v, reciprocal);
    }
    return vec3<f32>(0.0);
}

// `Mat3 * Vec3` for a matrix given by its columns.
fn map3(x: vec3<f32>, y: vec3<f32>, z: vec3<f32>, v: vec3<f32>) -> vec3<f32> {
    return (scale3(x, v.x) + scale3(y, v.y)) + scale3(z, v.z);
}

// `accel::offset::offset_ray_origin`, one coordinate: integer ULPs along
// the normal, a fixed step near zero.
fn offset_coordinate(p: f32, n: f32) -> f32 {
    if abs(p) < 1.0 / 32.0 {
        return p + mul(1.0 / 65536.0, n);
    }
    var ulps = i32(mul(256.0, n));
    if p < 0.0 {
        ulps = -ulps;
    }
    return bitcast<f32>(bitcast<i32>(p) + ulps);
}

fn offset_ray_origin(p: vec3<f32>, n: vec3<f32>) -> vec3<f32> {
    return vec3<f32>(offset_coordinate(p.x, n.x), offset_coordinate(p.y, n.y), offset_coordinate(p.z, n.z));
}
