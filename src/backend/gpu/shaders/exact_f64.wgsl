// Arithmetic that rounds as the CPU's does, for adapters with f64.
//
// WGSL lets a compiler fuse `a * b + c` into one FMA and lets division be
// off by 2.5 ULP. The product of two f32s is exact in f64 and rounds to
// the f32 product on the way back. That alone does not stop fusing: a
// compiler may see that the round trip is an f32 product (NVIDIA's does)
// and fuse that; on Vulkan the SPIR-V marks every float operation
// NoContraction (`spirv.rs`), which does. Division rounds once in f64,
// then to f32: the CPU's correctly rounded quotient except where the f64
// quotient lands within 2.5 f64 ULPs of an f32 tie.

fn mul(a: f32, b: f32) -> f32 {
    return f32(f64(a) * f64(b));
}

fn div(a: f32, b: f32) -> f32 {
    return f32(f64(a) / f64(b));
}

// p q - r s with one rounding: the tie-breaker of the watertight test.
fn difference_of_products(p: f32, q: f32, r: f32, s: f32) -> f32 {
    return f32(f64(p) * f64(q) - f64(r) * f64(s));
}

// The square root the CPU takes: rounding the f64 root to f32 gives the
// correctly rounded f32 root (f64 has more than twice f32's precision).
fn root(x: f32) -> f32 {
    return f32(sqrt(f64(x)));
}

// The unit normal of triangle (a, b, c) along (b - a) × (c - a), made in
// f64 and rounded once, as `accel::mesh_bvh` makes a hit's normal.
fn triangle_normal(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    let e1 = vec3<f64>(b) - vec3<f64>(a);
    let e2 = vec3<f64>(c) - vec3<f64>(a);
    let n = vec3<f64>(
        e1.y * e2.z - e2.y * e1.z,
        e1.z * e2.x - e2.z * e1.x,
        e1.x * e2.y - e2.x * e1.y,
    );
    let reciprocal = 1.0 / sqrt((n.x * n.x + n.y * n.y) + n.z * n.z);
    return vec3<f32>(n * reciprocal);
}
