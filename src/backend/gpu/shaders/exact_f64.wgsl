// Quotients, roots, the watertight test's tie-breaker and triangle
// normals rounded as the CPU rounds them, through f64, for adapters with
// it. Products come before this file: `product_f32.wgsl` where every
// float operation is marked NoContraction, else `product_f64.wgsl`.
//
// WGSL lets division be off by 2.5 ULP. Division rounds once in f64,
// then to f32: the CPU's correctly rounded quotient except where the f64
// quotient lands within 2.5 f64 ULPs of an f32 tie.

fn div(a: f32, b: f32) -> f32 {
    return f32(f64(a) / f64(b));
}

// p q - r s as the CPU's tie-breaker of the watertight test makes it:
// exact products, their difference rounded to f64, then to f32. That is
// not always the correctly rounded difference an exact f32 method (FMA
// and a two-product) would give: with p = q = 1 + 2^-12 and r s = -2^-80
// the f64 difference lands on an f32 tie and rounds to even, below the
// true value's nearest f32. So it stays in f64; only a triangle test
// whose edge function rounds to zero takes it.
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
