// Arithmetic for adapters without f64: plain f32 operations. A compiler
// may fuse a product into a following add and divide to 2.5 ULP, so rays
// through shared edges can be decided differently from the CPU (never
// missed by both neighbours: the edge functions keep their sign
// symmetry up to one rounding). The adapter's lack of f64 is reported.

fn mul(a: f32, b: f32) -> f32 {
    return a * b;
}

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
