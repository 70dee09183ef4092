// Products through f64, for adapters with f64 whose passes reach the
// driver as WGSL (`Arithmetic::ExactF64`): nothing there marks a product
// unfusable, and WGSL lets a compiler fuse `a * b + c` into one FMA. The
// product of two f32s is exact in f64 and rounds to the f32 product on
// the way back, an expression a compiler fuses only if it sees that the
// round trip is an f32 product (NVIDIA's does: such an adapter's
// description warns that its frames may differ from the CPU's).

fn mul(a: f32, b: f32) -> f32 {
    return f32(f64(a) * f64(b));
}
