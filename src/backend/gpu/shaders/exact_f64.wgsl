// Arithmetic that rounds as the CPU's does, for adapters with f64.
//
// WGSL lets a compiler fuse `a * b + c` into one FMA (SPIR-V from naga
// carries no NoContraction), and lets division be off by 2.5 ULP. The
// product of two f32s is exact in f64 and rounds to the f32 product on
// the way back; the subtraction that follows then has f32 operands that
// are no product, so nothing is left to fuse. Division rounds once in
// f64, then to f32: the CPU's correctly rounded quotient except where the
// f64 quotient lands within 2.5 f64 ULPs of an f32 tie.

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
