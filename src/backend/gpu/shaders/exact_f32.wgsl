// Quotients, roots, the tie-breaker and normals for adapters without
// f64, in plain f32 (products come before this file, `product_f32.wgsl`).
// Division may be 2.5 ULP off and products may fuse where the driver gets
// WGSL, so rays through shared edges can be decided differently from the
// CPU (never missed by both neighbours: the edge functions keep their
// sign symmetry up to one rounding). The adapter's lack of f64 is
// reported.

fn div(a: f32, b: f32) -> f32 {
    return a / b;
}

// p q - r s, each product rounded first where the compiler keeps them.
fn difference_of_products(p: f32, q: f32, r: f32, s: f32) -> f32 {
    let rs = r * s;
    return fma(p, q, -rs) - fma(r, s, -rs);
}

// Within a few ULPs of the CPU's root.
fn root(x: f32) -> f32 {
    return sqrt(x);
}

// The unit normal of triangle (a, b, c) along (b - a) × (c - a), in f32:
// within a few ULPs of the CPU's, which makes it in f64.
fn triangle_normal(a: vec3<f32>, b: vec3<f32>, c: vec3<f32>) -> vec3<f32> {
    return normalize(cross(b - a, c - a));
}
