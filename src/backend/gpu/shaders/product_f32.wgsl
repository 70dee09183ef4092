// Products in plain f32. Where every float operation is marked
// NoContraction (our own SPIR-V on Vulkan, `spirv.rs`), Vulkan rounds a
// product correctly and no compiler fuses it into a sum: it is the CPU's
// product, and the f64 round trip's (`product_f64.wgsl`: the exact
// product rounded once to f32), at f32's rate. Elsewhere a compiler may
// fuse it into a following add (`Arithmetic::PlainF32` on WGSL).

fn mul(a: f32, b: f32) -> f32 {
    return a * b;
}
